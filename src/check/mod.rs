//! `strata check`: a render check suite for driver, layer and renderer CI. It ships with strata (cases in code,
//! goldens and scenes embedded in the binary) and judges what a driver developer can act on:
//!
//! - *optics*: closed-form checks of the distributed ray tracing effects ([`optics`]), each with its measured
//!   figure, the figure geometry predicts and the tolerance;
//! - *golden*: a scene, settings and seed against a committed reference ([`golden`]): bit-identical on the
//!   device that made it (or any device whose hash was blessed), else ꟻLIP (Andersson et al. 2020) mean and 99th
//!   percentile against thresholds calibrated on Monte Carlo noise;
//! - *aov*: G-buffer channels against goldens with tight numeric tolerances;
//! - *determinism*: a scene rendered twice in one process, the same bits;
//! - *canary*: deliberately broken renders that must fail their comparisons: proof the suite can fail.
//!
//! Every case runs in a child process of its own under the validation layer ([`runner`]), with a timeout; the
//! parent applies an expectations file ([`expectations`]) and writes the reports ([`report`]). Statuses follow
//! deqp-runner's names ([`Status`]).
pub mod cases;
pub mod embedded;
pub mod expectations;
pub mod golden;
pub mod html;
pub mod junit;
pub mod measure;
pub mod optics;
pub mod report;
pub mod runner;

use serde::{Deserialize, Serialize};
use std::fmt;

/// What a case came to, in deqp-runner's words.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
pub enum Status {
    Pass,
    Fail,
    /// The child process died (a signal, an abort, `VK_ERROR_DEVICE_LOST`) or wrote no result.
    Crash,
    /// The child ran past `--timeout` and was killed.
    Timeout,
    /// Failed, then passed when run again.
    Flake,
    /// Failed as the expectations file says it does.
    ExpectedFail,
    /// The expectations file says it fails, and it passed.
    UnexpectedPass,
    /// Its golden is not there (`--bless` makes it; nothing is ever created silently).
    Missing,
    /// Not run: the device cannot run it, or the expectations file says to skip it.
    Skip,
}

impl Status {
    pub const ALL: [Status; 9] = [
        Status::Pass,
        Status::Fail,
        Status::Crash,
        Status::Timeout,
        Status::Flake,
        Status::ExpectedFail,
        Status::UnexpectedPass,
        Status::Missing,
        Status::Skip,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Status::Pass => "Pass",
            Status::Fail => "Fail",
            Status::Crash => "Crash",
            Status::Timeout => "Timeout",
            Status::Flake => "Flake",
            Status::ExpectedFail => "ExpectedFail",
            Status::UnexpectedPass => "UnexpectedPass",
            Status::Missing => "Missing",
            Status::Skip => "Skip",
        }
    }

    pub fn parse(word: &str) -> Option<Status> {
        Status::ALL.into_iter().find(|s| s.name().eq_ignore_ascii_case(word))
    }

    /// Whether this result fails the run: anything not expected.
    pub fn is_unexpected(self) -> bool {
        matches!(
            self,
            Status::Fail | Status::Crash | Status::Timeout | Status::Flake | Status::UnexpectedPass | Status::Missing
        )
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One number a case measured, with what it should be: it passes when |measured − expected| ≤ tolerance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    pub name: String,
    pub measured: f64,
    pub expected: f64,
    pub tolerance: f64,
    pub unit: String,
}

impl Figure {
    pub fn new(name: &str, measured: f64, expected: f64, tolerance: f64, unit: &str) -> Self {
        Self { name: name.into(), measured, expected, tolerance, unit: unit.into() }
    }

    /// A figure that passes at or below `limit` (an error measure whose ideal is 0).
    pub fn at_most(name: &str, measured: f64, limit: f64, unit: &str) -> Self {
        Self::new(name, measured, 0.0, limit, unit)
    }

    pub fn passes(&self) -> bool {
        (self.measured - self.expected).abs() <= self.tolerance
    }
}

impl fmt::Display for Figure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verdict = if self.passes() { "ok" } else { "OUT OF TOLERANCE" };
        let unit = if self.unit.is_empty() { String::new() } else { format!(" {}", self.unit) };
        if self.expected == 0.0 {
            write!(f, "{}: {:.5}{unit} (at most {:.5}{unit}) {verdict}", self.name, self.measured, self.tolerance)
        } else {
            write!(
                f,
                "{}: {:.5}{unit}, expected {:.5}{unit} ± {:.5} {verdict}",
                self.name, self.measured, self.expected, self.tolerance
            )
        }
    }
}

/// A validation-layer message id a case provoked: how often, and the first text.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidationSummary {
    pub id: String,
    pub count: u32,
    pub first_text: String,
}

/// What a case's child process reports: its own verdict (Pass, Fail, Missing, Skip, or Crash for a lost device)
/// before the parent adds validation messages, expectations and re-runs.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct CaseReport {
    pub case: String,
    pub verdict: Option<Status>,
    /// One line on why: the figure out of tolerance, the tier that decided, the missing file.
    pub message: String,
    /// Which comparison decided a golden or AOV case: "bit-identical", "perceptual", "numeric".
    pub tier: Option<String>,
    pub figures: Vec<Figure>,
    /// Every warning and error the validation layer reported, by id.
    pub validation: Vec<ValidationSummary>,
    /// Pictures for the report: (label, file name in the case's directory).
    pub images: Vec<(String, String)>,
    /// The one command that reproduces the case.
    pub reproduce: String,
    /// The device that actually ran the case (name / driver info).
    pub device: String,
    pub seconds: f64,
    /// What `--bless` copies: (golden file name, file in the case's directory).
    pub bless: Vec<(String, String)>,
    /// `--calibrate`: the perceptual thresholds (FLIP mean, 99th percentile) the spread over seeds suggests.
    pub proposed_thresholds: Option<[f64; 2]>,
}
