//! The progress bar of long renders.
use std::time::{Duration, Instant};

const WIDTH: usize = 30;

/// A one-line progress bar on stderr: samples done of N, elapsed time and the estimate of what is left.
pub struct ProgressBar {
    enabled: bool,
    started: Instant,
    /// The first report after samples were done, and how many: the estimate counts from there, because the first
    /// samples also compile the shaders (lavapipe compiles a pipeline when it first runs; on a machine that has
    /// never compiled strata's shaders that takes half a minute or more, Mesa's shader cache makes it quick after).
    first_batch: Option<(Instant, u32)>,
}

impl ProgressBar {
    pub fn new(enabled: bool) -> Self {
        let bar = Self { enabled, started: Instant::now(), first_batch: None };
        if enabled {
            eprint!("\r[{}] loading ...", " ".repeat(WIDTH));
        }
        bar
    }

    pub fn update(&mut self, done: u32, total: u32) {
        if !self.enabled || total == 0 {
            return;
        }
        let now = Instant::now();
        let measured = match self.first_batch {
            Some((at, first)) if done > first => Some((now - at, done - first)),
            Some(_) => None,
            None => {
                if done > 0 {
                    self.first_batch = Some((now, done));
                }
                None
            }
        };
        eprint!("\r\x1b[2K{}", line(done, total, now - self.started, measured));
    }

    pub fn finish(&mut self) {
        if self.enabled {
            eprint!("\r\x1b[2K");
        }
    }
}

/// The bar's text: `elapsed` since the command started; `measured`, the time some samples took after the first
/// batch (which compiles the shaders), scales the estimate of the rest.
fn line(done: u32, total: u32, elapsed: Duration, measured: Option<(Duration, u32)>) -> String {
    let fraction = f64::from(done.min(total)) / f64::from(total.max(1));
    let filled = ((fraction * WIDTH as f64).round() as usize).min(WIDTH);
    let bar = format!("[{}{}]", "=".repeat(filled), " ".repeat(WIDTH - filled));
    let head = format!("{bar} {done}/{total} samples  {:.1} s elapsed", elapsed.as_secs_f64());
    match measured {
        _ if done >= total => head,
        Some((time, samples)) if samples > 0 => {
            let eta = time.as_secs_f64() / f64::from(samples) * f64::from(total - done);
            format!("{head}  ETA {eta:.1} s")
        }
        _ if done == 0 => format!("{head}  (the first samples compile the shaders: up to a minute on a first run)"),
        _ => format!("{head}  ETA after the next samples"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_leaves_out_the_first_batch_that_compiled_the_shaders() {
        // 40 s so far; the 8 samples after the first batch took 10 s, so the 48 left take 60 s.
        let text = line(16, 64, Duration::from_secs(40), Some((Duration::from_secs(10), 8)));
        assert!(text.ends_with("16/64 samples  40.0 s elapsed  ETA 60.0 s"), "{text}");
        assert!(text.starts_with(&format!("[{}{}]", "=".repeat(8), " ".repeat(22))), "{text}");
        let first = line(8, 64, Duration::from_secs(31), None);
        assert!(first.ends_with("8/64 samples  31.0 s elapsed  ETA after the next samples"), "{first}");
        let start = line(0, 64, Duration::from_secs(1), None);
        assert!(start.contains("0/64 samples  1.0 s elapsed  (the first samples compile the shaders"), "{start}");
        let end = line(64, 64, Duration::from_secs(50), Some((Duration::from_secs(20), 56)));
        assert!(end == format!("[{}] 64/64 samples  50.0 s elapsed", "=".repeat(WIDTH)), "{end}");
    }

    #[test]
    fn the_bar_measures_from_the_first_batch_on() {
        let mut bar = ProgressBar::new(false);
        bar.enabled = true;
        bar.update(0, 64);
        assert!(bar.first_batch.is_none(), "no samples yet");
        bar.update(8, 64);
        assert_eq!(bar.first_batch.map(|(_, done)| done), Some(8));
        bar.update(16, 64);
        assert_eq!(bar.first_batch.map(|(_, done)| done), Some(8), "the first batch stays the reference");
        bar.finish();
    }
}
