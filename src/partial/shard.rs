//! Splitting work into shards: `--shard K/N` by hand, or `--shard auto` from the array job a scheduler runs
//! (Slurm job arrays, Kubernetes Indexed Jobs, AWS Batch array jobs).
use anyhow::{anyhow, bail, Result};

/// Shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

/// What `--shard` says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardSpec {
    Fixed(Shard),
    /// The index from the scheduler's environment; the count too where the scheduler tells it (Slurm), else
    /// given as `auto/N`.
    Auto {
        count: Option<u32>,
    },
}

/// `K/N` (1 ≤ K ≤ N), `auto` or `auto/N`.
pub fn parse_shard(text: &str) -> Result<ShardSpec, String> {
    let (k, n) = match text.split_once('/') {
        Some((k, n)) => (k.trim(), Some(n.trim())),
        None => (text.trim(), None),
    };
    let count = match n {
        Some(n) => match n.parse::<u32>() {
            Ok(n) if n >= 1 => Some(n),
            _ => return Err(format!("{text:?}: N must be a whole number from 1")),
        },
        None => None,
    };
    if k == "auto" {
        return Ok(ShardSpec::Auto { count });
    }
    let Some(count) = count else {
        return Err(format!("{text:?}: expected K/N (e.g. 2/4: the second of four shards) or auto"));
    };
    match k.parse::<u32>() {
        Ok(index) if (1..=count).contains(&index) => Ok(ShardSpec::Fixed(Shard { index, count })),
        _ => Err(format!("{text:?}: K must be 1 to {count} (the first shard is 1/{count})")),
    }
}

impl ShardSpec {
    /// The shard, reading the scheduler's variables through `var` for `auto`; with the scheduler's name.
    pub fn resolve(self, var: &dyn Fn(&str) -> Option<String>) -> Result<(Shard, &'static str)> {
        match self {
            ShardSpec::Fixed(shard) => Ok((shard, "--shard")),
            ShardSpec::Auto { count } => from_scheduler(var, count),
        }
    }
}

fn number(var: &dyn Fn(&str) -> Option<String>, name: &str) -> Result<Option<u32>> {
    match var(name) {
        None => Ok(None),
        Some(text) => text.trim().parse().map(Some).map_err(|_| anyhow!("{name}={text:?} is not a whole number")),
    }
}

fn from_scheduler(var: &dyn Fn(&str) -> Option<String>, given: Option<u32>) -> Result<(Shard, &'static str)> {
    let check = |index0: u32, count: u32, scheduler: &'static str| -> Result<(Shard, &'static str)> {
        if let Some(given) = given {
            if given != count {
                bail!("--shard auto/{given}, but {scheduler} runs {count} tasks");
            }
        }
        if index0 >= count {
            // Counted in 64 bits: task 4294967295 must not print as task 0.
            bail!("{scheduler}'s task {} is beyond its {count} tasks", u64::from(index0) + 1);
        }
        Ok((Shard { index: index0 + 1, count }, scheduler))
    };
    // Slurm: task ids run from SLURM_ARRAY_TASK_MIN by SLURM_ARRAY_TASK_STEP (`--array=0-7`, `--array=1-16:2`).
    if let Some(id) = number(var, "SLURM_ARRAY_TASK_ID")? {
        let count = number(var, "SLURM_ARRAY_TASK_COUNT")?
            .ok_or_else(|| anyhow!("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not"))?;
        let min = number(var, "SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let step = number(var, "SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
        if id < min || (id - min) % step != 0 {
            bail!("SLURM_ARRAY_TASK_ID={id} is not on the array's grid (min {min}, step {step})");
        }
        return check((id - min) / step, count, "Slurm");
    }
    let count_needed = |scheduler: &str, count_of: &str| {
        anyhow!("{scheduler} does not tell a task how many there are: use --shard auto/N with N = the {count_of}")
    };
    if let Some(index) = number(var, "JOB_COMPLETION_INDEX")? {
        let count = given.ok_or_else(|| count_needed("a Kubernetes Indexed Job", "Job's completions"))?;
        return check(index, count, "Kubernetes");
    }
    if let Some(index) = number(var, "AWS_BATCH_JOB_ARRAY_INDEX")? {
        let count = given.ok_or_else(|| count_needed("AWS Batch", "array job's size"))?;
        return check(index, count, "AWS Batch");
    }
    bail!(
        "--shard auto found no array job: none of SLURM_ARRAY_TASK_ID (Slurm), JOB_COMPLETION_INDEX (Kubernetes \
         Indexed Job) or AWS_BATCH_JOB_ARRAY_INDEX (AWS Batch) is set; outside a scheduler give --shard K/N"
    )
}

impl Shard {
    /// This shard's share of `total` items: `total·(K−1)/N .. total·K/N`, so the N shards cover `0..total`
    /// exactly once, in order, their sizes differing by at most one (empty when N > total).
    pub fn range(&self, total: u32) -> (u32, u32) {
        let at = |k: u32| (u64::from(total) * u64::from(k) / u64::from(self.count)) as u32;
        (at(self.index - 1), at(self.index))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| vars.iter().find(|(k, _)| *k == name).map(|(_, v)| v.to_string())
    }

    #[test]
    fn shards_cover_every_item_once() {
        for count in [1, 2, 3, 7, 64, 65] {
            let mut next = 0;
            for index in 1..=count {
                let (a, b) = Shard { index, count }.range(64);
                assert_eq!(a, next);
                next = b;
            }
            assert_eq!(next, 64);
        }
    }

    #[test]
    fn the_text_forms() {
        assert_eq!(parse_shard("2/4"), Ok(ShardSpec::Fixed(Shard { index: 2, count: 4 })));
        assert_eq!(parse_shard("auto"), Ok(ShardSpec::Auto { count: None }));
        assert_eq!(parse_shard("auto/8"), Ok(ShardSpec::Auto { count: Some(8) }));
        for bad in ["0/4", "5/4", "2", "x/4", "2/0", "auto/0"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn slurm_arrays_from_any_start_and_step() {
        let vars = [("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_ARRAY_TASK_MIN", "0"), ("SLURM_ARRAY_TASK_COUNT", "4")];
        let (shard, who) = ShardSpec::Auto { count: None }.resolve(&env(&vars)).unwrap();
        assert_eq!((shard, who), (Shard { index: 4, count: 4 }, "Slurm"));
        let stepped = [
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
        ];
        assert_eq!(ShardSpec::Auto { count: None }.resolve(&env(&stepped)).unwrap().0, Shard { index: 3, count: 8 });
        let err = ShardSpec::Auto { count: Some(5) }.resolve(&env(&vars)).unwrap_err().to_string();
        assert!(err.contains("runs 4 tasks"), "{err}");
    }

    #[test]
    fn kubernetes_and_aws_batch_need_the_count() {
        let k8s = [("JOB_COMPLETION_INDEX", "0")];
        assert_eq!(
            ShardSpec::Auto { count: Some(3) }.resolve(&env(&k8s)).unwrap(),
            (Shard { index: 1, count: 3 }, "Kubernetes")
        );
        let err = ShardSpec::Auto { count: None }.resolve(&env(&k8s)).unwrap_err().to_string();
        assert!(err.contains("--shard auto/N"), "{err}");
        let aws = [("AWS_BATCH_JOB_ARRAY_INDEX", "6")];
        assert_eq!(
            ShardSpec::Auto { count: Some(7) }.resolve(&env(&aws)).unwrap(),
            (Shard { index: 7, count: 7 }, "AWS Batch")
        );
        assert!(ShardSpec::Auto { count: Some(6) }.resolve(&env(&aws)).is_err(), "index beyond the count");
        let last = [("JOB_COMPLETION_INDEX", "4294967295")];
        let err = ShardSpec::Auto { count: Some(4) }.resolve(&env(&last)).unwrap_err().to_string();
        assert!(err.contains("task 4294967296 is beyond its 4 tasks"), "{err}");
    }

    #[test]
    fn no_scheduler_is_an_error_naming_the_variables() {
        let err = ShardSpec::Auto { count: None }.resolve(&env(&[])).unwrap_err().to_string();
        for name in ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "AWS_BATCH_JOB_ARRAY_INDEX"] {
            assert!(err.contains(name), "{err}");
        }
    }
}
