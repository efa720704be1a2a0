//! Scale-out as a user runs it, every render under the validation layer: parts of one frame rendered by separate
//! processes (`--samples`, `--shard`) and merged by `strata merge` into the bytes one render writes; merges that
//! cannot be made; checkpoints that survive kill -9 and SIGTERM; shards read from a scheduler's variables.
use crate::common;
use common::cli::{command, outcome, strata, temp_dir};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn scene() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml").to_string_lossy().into_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Renders `scene()` with `frame` and `extra`, under the layer; panics with stderr on failure.
fn render(frame: &[&str], output: &Path, extra: &[&str]) {
    let scene = scene();
    let mut args = vec!["render", scene.as_str(), "-o", path(output), "--quiet", "--validate"];
    args.extend_from_slice(frame);
    args.extend_from_slice(extra);
    let out = strata(&args);
    assert!(out.status.success(), "strata {}: {}", args.join(" "), outcome(&out));
}

fn merge(parts: &[PathBuf], output: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["merge".to_string()];
    args.extend(parts.iter().map(|p| p.display().to_string()));
    args.extend(["-o".to_string(), output.display().to_string(), "--quiet".into(), "--validate".into()]);
    args.extend(extra.iter().map(|s| s.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    strata(&args)
}

fn same_bytes(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} ({} bytes) and {} ({} bytes) differ", a.display(), x.len(), b.display(), y.len());
}

/// 1, 2, 3 and 7 shards of a 64-sample frame, and ranges given out of order, merge to the single run's PNG and
/// EXR bytes.
fn splits_merge_to_the_single_run(tag: &str, frame: &[&str]) {
    let dir = temp_dir(tag);
    let (png, exr) = (dir.join("single.png"), dir.join("single.exr"));
    render(frame, &png, &["--exr", path(&exr)]);
    let mut splits: Vec<(String, Vec<PathBuf>)> = Vec::new();
    for count in [1, 2, 3, 7] {
        let parts: Vec<PathBuf> = (1..=count)
            .map(|k| {
                let part = dir.join(format!("shard-{k}-of-{count}.exr"));
                render(frame, &part, &["--shard", &format!("{k}/{count}")]);
                part
            })
            .rev() // merged last shard first: the order of parts does not matter
            .collect();
        splits.push((format!("{count} shards"), parts));
    }
    let ranges = ["40..64", "0..17", "17..40"];
    let parts = ranges
        .iter()
        .map(|r| {
            let part = dir.join(format!("samples-{}.exr", r.replace("..", "-")));
            render(frame, &part, &["--samples", r]);
            part
        })
        .collect();
    splits.push(("ranges out of order".into(), parts));
    for (name, parts) in &splits {
        let (merged_png, merged_exr) = (dir.join("merged.png"), dir.join("merged.exr"));
        let out = merge(parts, &merged_png, &["--exr", path(&merged_exr)]);
        assert!(out.status.success(), "{name}: {}", outcome(&out));
        same_bytes(&png, &merged_png);
        same_bytes(&exr, &merged_exr);
    }
}

const RASTER: [&str; 5] = ["--size", "40x30", "--spp", "64", "--indirect"];

#[test]
fn splits_merge_to_the_single_run_bytes_raster_primary() {
    splits_merge_to_the_single_run("raster", &RASTER);
}

/// Two paths per camera sample: a part holds whole camera samples, each the mean of its paths.
#[test]
fn splits_merge_to_the_single_run_bytes_ray_primary_two_paths_per_sample() {
    let frame = ["--size", "40x30", "--spp", "64", "--indirect", "--primary", "rays", "--shading-samples", "2"];
    splits_merge_to_the_single_run("rays", &frame);
}

/// Replaces the first `from` in the file with `to` (the same length): a header field edited in place.
fn edit_header(file: &Path, from: &str, to: &str) {
    assert_eq!(from.len(), to.len());
    let mut bytes = std::fs::read(file).unwrap();
    let at = bytes.windows(from.len()).position(|w| w == from.as_bytes()).expect("the field is in the header");
    bytes[at..at + to.len()].copy_from_slice(to.as_bytes());
    std::fs::write(file, bytes).unwrap();
}

#[test]
fn merges_that_cannot_be_made_are_clear_errors_that_write_nothing() {
    let dir = temp_dir("merge-errors");
    let frame = ["--size", "24x16", "--spp", "8"];
    let part = |name: &str, extra: &[&str]| {
        let p = dir.join(name);
        render(&frame, &p, extra);
        p
    };
    let a = part("a.exr", &["--samples", "0..4"]);
    // The same scene by another path (from its own directory, as another machine may mount it): the same render.
    let b = dir.join("b.exr");
    let out = command(&["render", "cornell.toml", "-o", path(&b), "--samples", "4..8", "--quiet", "--validate"])
        .args(frame)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", outcome(&out));
    let overlapping = part("overlapping.exr", &["--samples", "3..8"]);
    let other_seed = part("other-seed.exr", &["--samples", "4..8", "--seed", "7"]);
    let other_scene = dir.join("other-scene.exr");
    let showcase = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.toml");
    let out = strata(&[
        "render",
        path(&showcase),
        "-o",
        path(&other_scene),
        "--samples",
        "4..8",
        "--quiet",
        "--validate",
        "--size",
        "24x16",
        "--spp",
        "8",
    ]);
    assert!(out.status.success(), "{}", outcome(&out));
    let other_version = dir.join("other-version.exr");
    std::fs::copy(&b, &other_version).unwrap();
    edit_header(&other_version, env!("CARGO_PKG_VERSION"), &"9".repeat(env!("CARGO_PKG_VERSION").len()));
    let truncated = dir.join("truncated.exr");
    let bytes = std::fs::read(&b).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() * 2 / 3]).unwrap();

    let output = dir.join("frame.png");
    let cases: [(&str, Vec<PathBuf>, &[&str]); 6] = [
        ("a gap", vec![a.clone()], &["samples 4..8 are in no part"]),
        ("an overlap", vec![a.clone(), overlapping.clone()], &["a.exr and", "overlapping.exr both hold samples 3..4"]),
        ("another seed", vec![a.clone(), other_seed], &["other-seed.exr", "seed is 7"]),
        ("another scene", vec![a.clone(), other_scene], &["other-scene.exr", "scene"]),
        ("another strata version", vec![a.clone(), other_version], &["other-version.exr", "strata version"]),
        ("a truncated part", vec![a.clone(), truncated], &["truncated.exr", "not a readable strata part"]),
    ];
    for (name, parts, expected) in cases {
        let out = merge(&parts, &output, &[]);
        let text = outcome(&out);
        assert!(!out.status.success(), "{name}: the merge succeeded");
        for needle in expected {
            assert!(text.contains(needle), "{name}: expected {needle:?} in {text}");
        }
        assert!(!output.exists(), "{name}: a failed merge wrote {}", output.display());
    }
    // The parts that do fit merge, whatever path each machine read the scene by.
    let out = merge(&[b, a.clone()], &output, &[]);
    assert!(out.status.success(), "{}", outcome(&out));
    // And a render that goes on from a part (--resume) renders only the rest, to the same bytes.
    let single = dir.join("single.png");
    render(&frame, &single, &[]);
    let resumed = dir.join("resumed.png");
    render(&frame, &resumed, &["--resume", path(&a)]);
    same_bytes(&single, &resumed);
    same_bytes(&single, &output);
    assert!(a.exists(), "--resume reads a part; only --checkpoint files are removed");
}

/// Waits until `file` exists (the first checkpoint), at most a minute.
fn wait_for(file: &Path, child: &mut std::process::Child) {
    let start = std::time::Instant::now();
    while !file.exists() {
        assert!(child.try_wait().unwrap().is_none(), "the render ended before its first checkpoint");
        assert!(start.elapsed().as_secs() < 60, "no checkpoint at {} after a minute", file.display());
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn a_render_killed_or_terminated_goes_on_from_its_checkpoint_to_the_same_bytes() {
    let dir = temp_dir("checkpoint");
    let frame = ["--size", "64x48", "--spp", "256", "--indirect"];
    let single = dir.join("single.png");
    render(&frame, &single, &[]);
    let scene = scene();
    let (output, checkpoint) = (dir.join("frame.png"), dir.join("frame.checkpoint.exr"));
    let mut args = vec!["render", scene.as_str(), "-o", path(&output), "--validate"];
    args.extend_from_slice(&frame);
    args.extend_from_slice(&["--checkpoint", path(&checkpoint)]);

    // kill -9 once the first checkpoint is on disk: nothing else is left, and the same command goes on from it.
    let mut often = args.clone();
    often.extend_from_slice(&["--checkpoint-every", "0.05"]);
    let mut child = command(&often).stderr(Stdio::piped()).spawn().unwrap();
    wait_for(&checkpoint, &mut child);
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success(), "the render finished before the kill: make it longer");
    assert!(!output.exists(), "a killed render wrote its output");
    let out = strata(&often);
    assert!(out.status.success(), "{}", outcome(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("going on from"), "{}", outcome(&out));
    same_bytes(&single, &output);
    assert!(!checkpoint.exists(), "the checkpoint outlived the finished render");

    // SIGTERM, as a scheduler sends it before the kill, once the render is under way (its first checkpoint is
    // on disk): the samples so far saved, exit 75, and the same command goes on.
    std::fs::remove_file(&output).unwrap();
    let mut child = command(&often).stderr(Stdio::piped()).spawn().unwrap();
    wait_for(&checkpoint, &mut child);
    assert!(Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap().success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(75), "{}", outcome(&out));
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(said.contains("stopped by SIGTERM; the samples so far are saved in"), "{}", outcome(&out));
    assert!(checkpoint.exists() && !output.exists(), "SIGTERM keeps the checkpoint and writes no output");
    let out = strata(&args);
    assert!(out.status.success(), "{}", outcome(&out));
    same_bytes(&single, &output);
}

#[test]
fn shard_auto_reads_the_scheduler_and_fails_clearly_without_one() {
    let dir = temp_dir("auto");
    let scene = scene();
    let part = dir.join("part.exr");
    let base = ["render", scene.as_str(), "-o", path(&part), "--size", "16x16", "--spp", "8", "--validate"];
    let out = strata(&[&base[..], &["--shard", "auto"]].concat());
    let text = outcome(&out);
    assert!(!out.status.success() && text.contains("SLURM_ARRAY_TASK_ID") && text.contains("JOB_COMPLETION_INDEX"));
    assert!(!part.exists());

    let out = command(&[&base[..], &["--shard", "auto"]].concat())
        .env("SLURM_ARRAY_TASK_ID", "2")
        .env("SLURM_ARRAY_TASK_MIN", "1")
        .env("SLURM_ARRAY_TASK_COUNT", "4")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", outcome(&out));
    assert!(outcome(&out).contains("shard 2/4 (Slurm): samples 2..4 of 8"), "{}", outcome(&out));

    let out = command(&[&base[..], &["--shard", "auto/2"]].concat()).env("JOB_COMPLETION_INDEX", "1").output().unwrap();
    assert!(outcome(&out).contains("shard 2/2 (Kubernetes): samples 4..8 of 8"), "{}", outcome(&out));
}

#[test]
fn shards_of_a_turntable_render_their_share_of_the_frames() {
    let dir = temp_dir("frames");
    let scene = scene();
    let output = dir.join("spin.png");
    let shard_of_five_views = |shard: &str| {
        let out = strata(&[
            "render",
            scene.as_str(),
            "-o",
            path(&output),
            "--size",
            "16x16",
            "--spp",
            "2",
            "--turntable",
            "5",
            "--shard",
            shard,
            "--validate",
            "--quiet",
        ]);
        assert!(out.status.success(), "{}", outcome(&out));
        out
    };
    shard_of_five_views("2/2");
    let mut names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    // Five frames over two shards: the second takes frames 3 to 5 (5·1/2 = 2 frames go to the first).
    assert_eq!(names, ["spin.0003.png", "spin.0004.png", "spin.0005.png"]);
    // A shard may hold a single frame of a sequence: it is still that frame, not a part of its samples.
    let out = shard_of_five_views("1/4");
    assert!(dir.join("spin.0001.png").is_file(), "{}", outcome(&out));
}

/// The scale-out benchmark runs clean under the layer on a tiny frame and prints its figures.
#[test]
fn the_scale_out_benchmark_runs_clean_and_prints_its_figures() {
    let out =
        command(&["bench", "--only", "scale-out", "--size", "32x24", "--spp", "16", "--samples", "1", "--validate"])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{}\n{text}", outcome(&out));
    assert!(text.contains("checkpoint: read back") && text.contains("% of a render"), "{text}");
    assert!(text.contains("fingerprint of the scene (once per part)") && text.contains("1M-triangle mesh"), "{text}");
    for n in [2, 4, 8, 16] {
        assert!(text.contains(&format!("merge of {n:>2} parts: read + add")), "{text}");
    }
}
