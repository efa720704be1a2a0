//! The progress bar of long renders.
/// A one-line progress bar on stderr: samples done of N, elapsed time and the estimate of what is left.
pub struct ProgressBar {
    enabled: bool,
    started: std::time::Instant,
}

impl ProgressBar {
    pub fn new(enabled: bool) -> Self {
        let bar = Self { enabled, started: std::time::Instant::now() };
        if enabled {
            eprint!("\r[{}] 0 samples, starting ...", " ".repeat(30));
        }
        bar
    }

    pub fn update(&mut self, done: u32, total: u32) {
        if !self.enabled || total == 0 {
            return;
        }
        let elapsed = self.started.elapsed().as_secs_f64();
        let fraction = f64::from(done) / f64::from(total);
        let filled = (fraction * 30.0).round() as usize;
        let eta = if done > 0 { elapsed / f64::from(done) * f64::from(total - done) } else { 0.0 };
        eprint!(
            "\r\x1b[2K[{}{}] {done}/{total} samples  {elapsed:.1} s elapsed  ETA {eta:.1} s",
            "=".repeat(filled),
            " ".repeat(30 - filled.min(30))
        );
    }

    pub fn finish(&mut self) {
        if self.enabled {
            eprint!("\r\x1b[2K");
        }
    }
}
