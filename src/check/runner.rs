//! Running the suite: every case in a child process of its own (`strata check --child CASE`), under the
//! validation layer, with a timeout. A crash, an abort or a lost device ends only that child (Crash); a child
//! past its time is killed (Timeout); an unexpected failure is run once more, and a pass then is a Flake. The
//! parent applies the expectations, blesses and calibrates goldens when asked, and returns what the reports need.
use super::cases::{self, Case, CaseContext, Kind};
use super::expectations::{self, Allow, DeviceFacts, Expectations};
use super::golden::Goldens;
use super::{CaseReport, Status, ValidationSummary};
use crate::scene::settings::Trace;
use crate::vk::{Gpu, GpuOptions};
use anyhow::{anyhow, bail, Context as _, Result};
use regex::Regex;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// What a run is asked to do.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The strata binary the children run (the running one).
    pub program: PathBuf,
    pub device: Option<String>,
    pub trace: Trace,
    pub out: PathBuf,
    /// Only cases whose names this matches.
    pub cases: Option<Regex>,
    pub expectations: Expectations,
    pub jobs: usize,
    /// Run every `n`th case from the `k`th (1-based): `(k, n)`.
    pub fraction: (usize, usize),
    pub quick: bool,
    pub bless: bool,
    pub calibrate: bool,
    pub timeout: Duration,
    pub include_test_cases: bool,
    /// `--goldens DIR`; None: the repository's or the embedded copy.
    pub goldens: Option<PathBuf>,
}

/// The device a run checks, and the software around it (the JUnit properties and the report's header).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Environment {
    pub device: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    pub vulkan_api: String,
    pub loader: String,
    pub validation_layer: String,
    pub strata_version: String,
    pub trace: String,
    pub goldens: String,
}

impl Environment {
    pub fn facts(&self) -> DeviceFacts {
        DeviceFacts { name: self.device.clone(), driver: self.driver.clone(), driver_info: self.driver_info.clone() }
    }
}

/// One case's outcome.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CaseResult {
    pub case: String,
    pub kind: String,
    pub about: String,
    /// After re-runs and expectations.
    pub status: Status,
    /// Before the expectations were applied.
    pub raw: Status,
    pub attempts: u32,
    /// What the expectations said: (status, reason, where).
    pub expected: Option<(Status, String, String)>,
    pub report: CaseReport,
}

/// Everything a run found.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunSummary {
    pub environment: Environment,
    pub results: Vec<CaseResult>,
    /// `[[allow]]` entries for this device that no case needed: stale, worth removing.
    pub unused_allows: Vec<String>,
    /// What `--bless` and `--calibrate` wrote.
    pub goldens_written: Vec<String>,
    pub seconds: f64,
}

impl RunSummary {
    pub fn unexpected(&self) -> impl Iterator<Item = &CaseResult> {
        self.results.iter().filter(|r| r.status.is_unexpected())
    }

    pub fn count(&self, status: Status) -> usize {
        self.results.iter().filter(|r| r.status == status).count()
    }

    /// "18 Pass, 2 Fail": each status that occurred, with its count (every report's headline).
    pub fn counts(&self) -> String {
        Status::ALL
            .iter()
            .filter_map(|s| {
                let n = self.count(*s);
                (n > 0).then(|| format!("{n} {s}"))
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The cases a run takes: `--quick` or all (canaries always), those `--cases` matches, then `--fraction`.
pub fn select_cases(options: &RunOptions) -> Vec<Case> {
    let chosen: Vec<Case> = cases::all(options.include_test_cases)
        .into_iter()
        .filter(|c| !options.quick || c.quick || c.kind() == Kind::Canary)
        .filter(|c| options.cases.as_ref().is_none_or(|r| r.is_match(c.name)))
        .collect();
    let (k, n) = options.fraction;
    chosen.into_iter().enumerate().filter(|(i, _)| i % n == k - 1).map(|(_, c)| c).collect()
}

/// Reads the device and the software around it without opening a device (the children do that).
pub fn environment(options: &RunOptions, goldens: &Goldens) -> Result<Environment> {
    let loader = crate::vk::instance::loader_info()?;
    let Some(layer) = loader.validation_layer.clone() else {
        bail!(
            "strata check runs every case under the Khronos validation layer, which is not installed: run \
             scripts/setup.sh (it installs vulkan-validationlayers)"
        );
    };
    let instance = crate::vk::instance::Instance::new(&crate::vk::instance::InstanceOptions {
        validation: false,
        echo_messages: false,
    })
    .context("creating a Vulkan instance")?;
    let reports = crate::vk::device::enumerate_devices(&instance)?;
    let needs = crate::render::accumulate::TracePath::device_needs(options.trace);
    let index = crate::vk::device::select_device(&reports, options.device.as_deref(), needs)?;
    let r = reports.iter().find(|r| r.index == index).ok_or_else(|| anyhow!("device {index} vanished"))?;
    Ok(Environment {
        device: r.name.clone(),
        device_type: r.type_name().into(),
        driver: r.driver_name.clone(),
        driver_info: r.driver_info.clone(),
        vulkan_api: r.api_version_string(),
        loader: crate::vk::instance::version_string(loader.loader_version),
        validation_layer: layer,
        strata_version: env!("CARGO_PKG_VERSION").into(),
        trace: options.trace.name().into(),
        goldens: goldens.describe(),
    })
}

/// A case's directory in the run's output.
pub fn case_dir(out: &Path, case: &str) -> PathBuf {
    out.join("cases").join(cases::slug(case))
}

const RESULT_FILE: &str = "result.json";

/// One child at work.
struct Running {
    index: usize,
    attempt: u32,
    child: Child,
    started: Instant,
}

/// Runs the suite. `progress` gets each result as it is final.
pub fn run(options: &RunOptions, progress: &mut dyn FnMut(usize, usize, &CaseResult)) -> Result<RunSummary> {
    let started = Instant::now();
    if options.jobs == 0 {
        bail!("--jobs 0: run at least one case at a time");
    }
    let (k, n) = options.fraction;
    if n == 0 || k == 0 || k > n {
        bail!("--fraction {k}/{n}: K must be 1 to N");
    }
    std::fs::create_dir_all(&options.out).with_context(|| format!("creating {}", options.out.display()))?;
    let mut goldens = Goldens::open(options.goldens.as_deref())?;
    if options.bless || options.calibrate {
        goldens.writable_dir()?;
    }
    let environment = environment(options, &goldens)?;
    let selected = select_cases(options);
    if selected.is_empty() {
        bail!("no case matches (strata check --list shows them)");
    }
    let mut schedule = Schedule::new(options, &selected, environment.facts());
    let mut running: Vec<Running> = Vec::new();
    loop {
        schedule.start(&mut running, progress)?;
        if running.is_empty() && schedule.pending.is_empty() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
        let mut i = 0;
        while i < running.len() {
            match exit_of(&mut running[i], options.timeout)? {
                None => i += 1,
                Some(exit) => schedule.settle(running.swap_remove(i), exit, &mut goldens, progress)?,
            }
        }
    }
    let facts = environment.facts();
    let device_allows: Vec<&Allow> = options.expectations.allows.iter().filter(|a| a.devices.matches(&facts)).collect();
    let unused_allows = device_allows
        .iter()
        .filter(|a| !schedule.used_allows.contains(&a.id))
        .map(|a| format!("{} ({}): allowed but never reported", a.id, a.at))
        .collect();
    Ok(RunSummary {
        environment,
        results: schedule.results.into_iter().flatten().collect(),
        unused_allows,
        goldens_written: schedule.goldens_written,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// How a case's process ended: its exit status, or Err when it ran past `timeout` and was killed. None while it
/// runs.
fn exit_of(r: &mut Running, timeout: Duration) -> Result<Option<std::result::Result<std::process::ExitStatus, ()>>> {
    match r.child.try_wait() {
        Ok(Some(status)) => Ok(Some(Ok(status))),
        Ok(None) if r.started.elapsed() > timeout => {
            let _ = r.child.kill();
            let _ = r.child.wait();
            Ok(Some(Err(())))
        }
        Ok(None) => Ok(None),
        Err(e) => Err(e).context("waiting for a case's process"),
    }
}

/// The cases of one run in their order: what waits (with its attempt), what a first attempt said before its
/// re-run, and the results so far.
struct Schedule<'a> {
    options: &'a RunOptions,
    selected: &'a [Case],
    facts: DeviceFacts,
    pending: std::collections::VecDeque<(usize, u32)>,
    first_attempt: Vec<Option<(Status, CaseReport)>>,
    results: Vec<Option<CaseResult>>,
    used_allows: BTreeSet<String>,
    goldens_written: Vec<String>,
    done: usize,
    /// Golden-making cases finished, and how many there are in a bless run (0 otherwise).
    blessed: usize,
    bless_phase_len: usize,
}

impl<'a> Schedule<'a> {
    fn new(options: &'a RunOptions, selected: &'a [Case], facts: DeviceFacts) -> Self {
        // Blessing runs the cases that make goldens first, so the canaries compare against the new ones.
        let mut order: Vec<usize> = (0..selected.len()).collect();
        if options.bless {
            order.sort_by_key(|&i| !makes_goldens(&selected[i]));
        }
        let bless_phase_len = if options.bless { selected.iter().filter(|c| makes_goldens(c)).count() } else { 0 };
        Self {
            options,
            selected,
            facts,
            pending: order.iter().map(|&i| (i, 1)).collect(),
            first_attempt: vec![None; selected.len()],
            results: vec![None; selected.len()],
            used_allows: BTreeSet::new(),
            goldens_written: Vec::new(),
            done: 0,
            blessed: 0,
            bless_phase_len,
        }
    }

    /// Starts what may start: up to `--jobs` at once, and in a bless run nothing past the golden-making cases
    /// before they are done. A case expected to be skipped on this device is settled without a process.
    fn start(&mut self, running: &mut Vec<Running>, progress: &mut dyn FnMut(usize, usize, &CaseResult)) -> Result<()> {
        let (options, selected) = (self.options, self.selected);
        while running.len() < options.jobs {
            let Some(&(index, attempt)) = self.pending.front() else { break };
            let case = &selected[index];
            if options.bless && !makes_goldens(case) && attempt == 1 && self.blessed < self.bless_phase_len {
                break;
            }
            self.pending.pop_front();
            let skip = options.expectations.expected(case.name, &self.facts).filter(|e| e.status == Status::Skip);
            match skip {
                Some(e) if attempt == 1 => {
                    let result = CaseResult {
                        case: case.name.into(),
                        kind: case.kind().name().into(),
                        about: case.about.into(),
                        status: Status::Skip,
                        raw: Status::Skip,
                        attempts: 0,
                        expected: Some((e.status, e.reason.clone(), e.at.clone())),
                        report: CaseReport {
                            case: case.name.into(),
                            message: format!("skipped: {}", e.reason),
                            ..Default::default()
                        },
                    };
                    self.record(index, result, progress);
                }
                _ => running.push(spawn(options, case, index, attempt)?),
            }
        }
        Ok(())
    }

    /// A case's process ended: read its result, give an unexpected failure one more try (a pass then is a
    /// flake), apply the expectations, bless or calibrate when asked, and record it.
    fn settle(
        &mut self,
        r: Running,
        exit: std::result::Result<std::process::ExitStatus, ()>,
        goldens: &mut Goldens,
        progress: &mut dyn FnMut(usize, usize, &CaseResult),
    ) -> Result<()> {
        let (options, selected) = (self.options, self.selected);
        let case = &selected[r.index];
        let dir = case_dir(&options.out, case.name);
        let seconds = r.started.elapsed().as_secs_f64();
        let (raw, mut report) = match exit {
            Err(()) => (
                Status::Timeout,
                CaseReport {
                    case: case.name.into(),
                    message: format!("killed after {:.0} s (--timeout)", options.timeout.as_secs_f64()),
                    seconds,
                    ..Default::default()
                },
            ),
            Ok(status) => read_child_result(&dir, case.name, status, seconds),
        };
        // The whole child: starting, opening the device, building pipelines, the case, the teardown.
        report.seconds = seconds;
        let raw = apply_validation(raw, &mut report, &options.expectations, &self.facts, &mut self.used_allows);
        let expected = options.expectations.expected(case.name, &self.facts);
        if r.attempt == 1 && matches!(raw, Status::Fail | Status::Crash | Status::Timeout) && expected.is_none() {
            self.first_attempt[r.index] = Some((raw, report));
            self.pending.push_front((r.index, 2));
            return Ok(());
        }
        let (raw, report, attempts) = match self.first_attempt[r.index].take() {
            Some((first_status, first_report)) if raw == Status::Pass => {
                let mut report = report;
                report.message = format!(
                    "passed on the re-run after {first_status} on the first ({}); see {}",
                    first_report.message,
                    dir.join("attempt-1.json").display()
                );
                let _ = std::fs::write(dir.join("attempt-1.json"), serde_json::to_vec_pretty(&first_report)?);
                (Status::Flake, report, 2)
            }
            Some((first_status, first_report)) => (first_status, first_report, 2),
            None => (raw, report, r.attempt),
        };
        let mut result = CaseResult {
            case: case.name.into(),
            kind: case.kind().name().into(),
            about: case.about.into(),
            status: expectations::apply(raw, expected),
            raw,
            attempts,
            expected: expected.map(|e| (e.status, e.reason.clone(), e.at.clone())),
            report,
        };
        if options.bless && !result.report.bless.is_empty() && raw != Status::Crash && raw != Status::Timeout {
            let written = bless(goldens, &dir, &mut result)?;
            self.goldens_written.extend(written);
        }
        if options.calibrate {
            self.calibrate(goldens, &result)?;
        }
        self.record(r.index, result, progress);
        Ok(())
    }

    /// A golden case's measured spread becomes its perceptual thresholds (`--calibrate`).
    fn calibrate(&mut self, goldens: &mut Goldens, result: &CaseResult) -> Result<()> {
        if let Some([mean, p99]) = result.report.proposed_thresholds {
            let entry = goldens.entries.entry(result.case.clone()).or_default();
            entry.flip_mean = Some(round_up(mean));
            entry.flip_p99 = Some(round_up(p99));
            goldens.save()?;
            self.goldens_written.push(format!(
                "{}: thresholds FLIP mean {}, 99th percentile {}",
                result.case,
                round_up(mean),
                round_up(p99)
            ));
        }
        Ok(())
    }

    fn record(&mut self, index: usize, result: CaseResult, progress: &mut dyn FnMut(usize, usize, &CaseResult)) {
        if makes_goldens(&self.selected[index]) {
            self.blessed += 1;
        }
        self.done += 1;
        progress(self.done, self.selected.len(), &result);
        self.results[index] = Some(result);
    }
}

/// Golden and AOV cases make goldens (`--bless`).
fn makes_goldens(case: &Case) -> bool {
    matches!(case.kind(), Kind::Golden | Kind::Aov)
}

/// Two significant digits, rounded up: thresholds read as numbers a person wrote.
fn round_up(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return 0.0;
    }
    // Two significant digits: k·10^e with k in 10..=99, printed and read back so it is the decimal it reads as.
    let e = x.log10().floor() as i32 - 1;
    let k = (x / 10f64.powi(e)).ceil();
    let text =
        if e >= 0 { format!("{}", k * 10f64.powi(e)) } else { format!("{:.*}", (-e) as usize, k * 10f64.powi(e)) };
    text.parse().unwrap_or(x)
}

fn spawn(options: &RunOptions, case: &Case, index: usize, attempt: u32) -> Result<Running> {
    let dir = case_dir(&options.out, case.name);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let _ = std::fs::remove_file(dir.join(RESULT_FILE));
    let log = std::fs::File::create(dir.join(format!("log-{attempt}.txt")))
        .with_context(|| format!("creating {}", dir.join("log.txt").display()))?;
    let mut command = Command::new(&options.program);
    command
        .arg("check")
        .arg("--child")
        .arg(case.name)
        .arg("--out")
        .arg(&options.out)
        .arg("--attempt")
        .arg(attempt.to_string())
        .arg("--trace")
        .arg(options.trace.name());
    if let Some(d) = &options.device {
        command.arg("--device").arg(d);
    }
    if let Some(g) = &options.goldens {
        command.arg("--goldens").arg(g);
    }
    if options.calibrate {
        command.arg("--calibrate");
    }
    command.stdin(Stdio::null()).stdout(log.try_clone()?).stderr(log);
    let child = command.spawn().with_context(|| format!("starting {}", options.program.display()))?;
    Ok(Running { index, attempt, child, started: Instant::now() })
}

/// What a finished child left: its result file, or a Crash that says how it ended.
fn read_child_result(dir: &Path, case: &str, status: std::process::ExitStatus, seconds: f64) -> (Status, CaseReport) {
    let crash =
        |message: String| (Status::Crash, CaseReport { case: case.into(), message, seconds, ..Default::default() });
    let how = describe_exit(status);
    if !status.success() {
        return crash(format!("{how}; its output is in {}", dir.display()));
    }
    match std::fs::read(dir.join(RESULT_FILE))
        .map_err(anyhow::Error::from)
        .and_then(|bytes| serde_json::from_slice::<CaseReport>(&bytes).map_err(anyhow::Error::from))
    {
        Ok(report) => (report.verdict.unwrap_or(Status::Crash), report),
        Err(e) => crash(format!("the case's process {how} but left no readable result ({e})")),
    }
}

fn describe_exit(status: std::process::ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt as _;
        if let Some(signal) = status.signal() {
            let name = match signal {
                libc::SIGABRT => "SIGABRT",
                libc::SIGSEGV => "SIGSEGV",
                libc::SIGBUS => "SIGBUS",
                libc::SIGILL => "SIGILL",
                libc::SIGFPE => "SIGFPE",
                libc::SIGKILL => "SIGKILL",
                _ => "a signal",
            };
            return format!("died of {name} ({signal})");
        }
    }
    match status.code() {
        Some(0) => "exited normally".into(),
        Some(c) => format!("exited with status {c}"),
        None => "ended without a status".into(),
    }
}

/// A validation message fails its case unless the expectations allow it.
fn apply_validation(
    raw: Status,
    report: &mut CaseReport,
    expectations: &Expectations,
    facts: &DeviceFacts,
    used: &mut BTreeSet<String>,
) -> Status {
    let mut failing: Vec<&ValidationSummary> = Vec::new();
    for v in &report.validation {
        match expectations.allowed(&v.id, facts) {
            Some(a) => {
                used.insert(a.id.clone());
            }
            None => failing.push(v),
        }
    }
    if failing.is_empty() {
        return raw;
    }
    let text: Vec<String> =
        failing.iter().map(|v| format!("{} ×{}: {}", v.id, v.count, first_line(&v.first_text))).collect();
    let note = format!("validation layer: {}", text.join("; "));
    report.message = if raw == Status::Pass || report.message.is_empty() {
        note
    } else {
        format!("{note}; and: {}", report.message)
    };
    match raw {
        Status::Pass => Status::Fail,
        other => other,
    }
}

fn first_line(text: &str) -> &str {
    let line = text.lines().next().unwrap_or_default();
    if line.len() > 300 {
        let mut end = 300;
        while !line.is_char_boundary(end) {
            end -= 1;
        }
        &line[..end]
    } else {
        line
    }
}

/// Copies a case's outputs into the goldens (keeping the old files as `.old`).
fn bless(goldens: &mut Goldens, dir: &Path, result: &mut CaseResult) -> Result<Vec<String>> {
    let device = result.report.device.clone();
    let mut written = Vec::new();
    for (golden_name, local) in &result.report.bless {
        let bytes = std::fs::read(dir.join(local)).with_context(|| format!("reading {}", dir.join(local).display()))?;
        let hash =
            if golden_name.ends_with(".png") { Some(super::golden::Rgba8::decode_png(&bytes)?.hash()) } else { None };
        let entry_name = golden_name.trim_end_matches(".png").trim_end_matches(".exr").replacen('-', "/", 1);
        goldens.bless(&entry_name, golden_name, &bytes, &device, hash)?;
        written.push(format!("{golden_name} (from {})", dir.join(local).display()));
    }
    goldens.save()?;
    result.report.message = format!("blessed: {}", written.join(", "));
    result.status = Status::Pass;
    result.raw = Status::Pass;
    Ok(written)
}

/// What `strata check --child` is given.
#[derive(Debug, Clone)]
pub struct ChildOptions {
    pub case: String,
    pub out: PathBuf,
    pub attempt: u32,
    pub trace: Trace,
    pub device: Option<String>,
    pub goldens: Option<PathBuf>,
    pub calibrate: bool,
}

/// The child's side: open the device under the validation layer, run the case, and write its report, with
/// every message the layer reported, to the case's `result.json`. An error before the case runs is the case's
/// Fail; a crash never gets here.
pub fn run_child(options: &ChildOptions) -> Result<()> {
    let case = cases::find(&options.case).ok_or_else(|| anyhow!("no case named {}", options.case))?;
    let dir = case_dir(&options.out, case.name);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let goldens = Goldens::open(options.goldens.as_deref())?;
    let gpu = Gpu::new(&GpuOptions {
        validation: true,
        echo_messages: false,
        device: options.device.clone(),
        needs: crate::render::accumulate::TracePath::device_needs(options.trace),
    })?;
    let log = gpu.validation_log();
    let ctx = CaseContext {
        gpu: &gpu,
        trace: options.trace,
        out: options.out.clone(),
        dir: dir.clone(),
        goldens: &goldens,
        attempt: options.attempt,
        calibrate: options.calibrate,
        device_arg: options.device.clone(),
    };
    let mut report = cases::run_case(&case, &ctx)?;
    drop(ctx);
    // The device's teardown can report too (leaked objects): collect after it.
    drop(gpu);
    let mut by_id: Vec<ValidationSummary> = Vec::new();
    for m in log.failures() {
        match by_id.iter_mut().find(|v| v.id == m.id_name) {
            Some(v) => v.count += 1,
            None => by_id.push(ValidationSummary { id: m.id_name.clone(), count: 1, first_text: m.text.clone() }),
        }
    }
    report.validation = by_id;
    let json = serde_json::to_vec_pretty(&report)?;
    crate::output::write_atomic(&dir.join(RESULT_FILE), |f| {
        use std::io::Write as _;
        f.write_all(&json).map_err(Into::into)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_round_up_to_two_digits() {
        assert_eq!(round_up(0.012_34), 0.013);
        assert_eq!(round_up(0.5), 0.5);
        assert_eq!(round_up(0.0), 0.0);
        assert_eq!(round_up(1.234), 1.3);
        assert_eq!(round_up(0.02501), 0.026);
        assert_eq!(round_up(0.0260000001).to_string(), "0.027");
    }

    #[test]
    fn fractions_take_every_nth_case_from_the_kth() {
        let options = |k, n| RunOptions {
            program: PathBuf::new(),
            device: None,
            trace: Trace::Auto,
            out: PathBuf::new(),
            cases: None,
            expectations: Expectations::default(),
            jobs: 1,
            fraction: (k, n),
            quick: false,
            bless: false,
            calibrate: false,
            timeout: Duration::from_secs(1),
            include_test_cases: false,
            goldens: None,
        };
        let all = select_cases(&options(1, 1));
        let mut union: Vec<&str> = Vec::new();
        for k in 1..=3 {
            let part = select_cases(&options(k, 3));
            assert!(part.len() >= all.len() / 3);
            union.extend(part.iter().map(|c| c.name));
        }
        union.sort();
        let mut names: Vec<&str> = all.iter().map(|c| c.name).collect();
        names.sort();
        assert_eq!(union, names, "three shards cover every case once");
    }
}
