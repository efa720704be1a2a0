//! Bad input, and inputs that could make strata lose data: broken scenes (`loaders`), destinations that collide
//! or cannot be written (`destinations`: nothing is deleted or overwritten that was not asked for, and every
//! refusal comes before the work), and hostile parts, environments, expectations and numbers (`inputs`: no
//! abort, panic or hang). Each case of issue 34's list is here with its exact reproducer and at least one other
//! spelling of the same path or value.
use crate::common;

mod destinations;
mod inputs;
mod loaders;

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// Runs `command` to its end, or kills it after `limit` and fails the test: a hang is a failure, not a wait.
pub fn finishes_within(mut command: Command, limit: Duration) -> (Output, Duration) {
    use std::process::Stdio;
    let started = Instant::now();
    let mut child = command.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("start strata");
    loop {
        if child.try_wait().expect("wait for strata").is_some() {
            return (child.wait_with_output().expect("read strata's output"), started.elapsed());
        }
        if started.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().expect("read strata's output");
            panic!("still running after {limit:?} (a hang); stderr:\n{}", String::from_utf8_lossy(&out.stderr));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A failed run: non-zero exit (not a signal), and an error naming `names` in stderr.
pub fn refused(out: &Output, names: &[&str]) -> String {
    let text = common::cli::stderr(out);
    assert!(out.status.code().is_some_and(|c| c != 0), "expected a clean failure: {}", common::cli::outcome(out));
    assert!(!text.contains("panicked"), "{text}");
    for name in names {
        assert!(text.contains(name), "the error should name {name:?}: {text}");
    }
    text
}

/// The names of the entries of `dir`, sorted (what a run left there).
pub fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// A render that would take hours (`--spp 65536` at 512×512): a refusal that comes "before any work" must come
/// at once, and the timeout catches one that does not.
pub const LONG_RENDER: [&str; 4] = ["--size", "512x512", "--spp", "65536"];

/// How long a refusal before any work may take before it counts as a hang (it takes milliseconds).
pub const PROMPTLY: Duration = Duration::from_secs(60);

/// A part of a `width × height` frame of `spp` samples holding `samples`, every sum `count`.
pub fn part(
    width: u32,
    height: u32,
    spp: u32,
    samples: strata::partial::SampleSet,
    count: u64,
) -> strata::partial::file::Part {
    use strata::partial::file::{Part, PartLook, Provenance};
    Part {
        provenance: Provenance {
            strata_version: env!("CARGO_PKG_VERSION").into(),
            device: "a test".into(),
            scene: "fnv1a64:1".into(),
            settings: "fnv1a64:2".into(),
            seed: 0,
        },
        look: PartLook {
            exposure: 0.0,
            tone_map: strata::scene::settings::ToneMap::Clamp,
            transparent: false,
            auto_exposure: false,
        },
        sums: strata::partial::PartialSums {
            width,
            height,
            spp,
            samples,
            counts: vec![count; width as usize * height as usize * 4],
        },
    }
}
