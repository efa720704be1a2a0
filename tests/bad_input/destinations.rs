//! What a run writes and deletes, decided before any work (issue 34, problems 1, 2, 5, 6 and the last two of 9):
//! the checkpoint never lands on an output, a merge never writes over or removes its own parts or outputs, a
//! batch never writes one file twice, an impossible destination is refused at once, and a write that fails
//! half-way leaves nothing. Every path collision is tried as given and as at least one other spelling of the same
//! file (`./`, `../`, absolute, a symlinked directory, a hard link).
use super::{finishes_within, listing, part, refused, LONG_RENDER, PROMPTLY};
use crate::common::cli::{command, repo_file, stderr, strata, temp_dir};
use std::path::{Path, PathBuf};

/// Whether a message says that two paths are one file (as the same text, or as two spellings).
fn collides(text: &str) -> bool {
    text.contains("same file") || text.contains(" is both ")
}

fn cornell() -> String {
    repo_file("scenes/cornell.toml").display().to_string()
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// A render command of the Cornell box (hours long: see [`LONG_RENDER`]) with `args` after it.
fn long_render(args: &[String]) -> std::process::Command {
    let mut all = vec!["render".to_string(), cornell()];
    all.extend(LONG_RENDER.iter().map(|a| a.to_string()));
    all.extend_from_slice(args);
    command(&all)
}

/// The checkpoint as the output, in every spelling: refused before rendering, the existing output untouched.
#[test]
fn a_checkpoint_never_lands_on_an_output() {
    let dir = temp_dir("checkpoint-on-output");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::os::unix::fs::symlink(&dir, dir.join("sub/link")).unwrap();
    let sentinel = b"the user's earlier render".to_vec();
    for name in ["out.exr", "ck.exr", "p.exr", "f.3.exr"] {
        std::fs::write(dir.join(name), &sentinel).unwrap();
    }
    std::fs::hard_link(dir.join("out.exr"), dir.join("hard.exr")).unwrap();
    let d = |name: &str| s(&dir.join(name));
    let cases: Vec<Vec<String>> = vec![
        // The reproducers of the issue.
        vec!["-o".into(), d("out.exr"), "--checkpoint".into(), format!("{}/./out.exr", s(&dir))],
        vec!["-o".into(), d("out.png"), "--exr".into(), d("ck.exr"), "--checkpoint".into(), d("ck.exr")],
        vec![
            "--samples".into(),
            "0..2".into(),
            "-o".into(),
            d("p.exr"),
            "--checkpoint".into(),
            format!("{}/./p.exr", s(&dir)),
        ],
        vec!["-o".into(), d("f.#.exr"), "--frames".into(), "3..3".into(), "--checkpoint".into(), d("f.3.exr")],
        // Other spellings of the same files.
        vec!["-o".into(), d("out.exr"), "--checkpoint".into(), d("sub/../out.exr")],
        vec!["-o".into(), d("out.exr"), "--checkpoint".into(), d("sub/link/out.exr")],
        vec!["-o".into(), d("out.exr"), "--checkpoint".into(), d("hard.exr")],
        vec!["-o".into(), d("out.png"), "--exr".into(), d("sub/link/ck.exr"), "--checkpoint".into(), d("ck.exr")],
        vec!["-o".into(), d("f.#.exr"), "--frames".into(), "3..3".into(), "--checkpoint".into(), d("sub/../f.3.exr")],
    ];
    for args in cases {
        let (out, _) = finishes_within(long_render(&args), PROMPTLY);
        let text = refused(&out, &["--checkpoint"]);
        assert!(collides(&text), "{args:?}: {text}");
    }
    for name in ["out.exr", "ck.exr", "p.exr", "f.3.exr", "hard.exr"] {
        assert_eq!(std::fs::read(dir.join(name)).unwrap(), sentinel, "{name} was changed");
    }
    assert!(!dir.join("out.png").exists());
}

/// Two parts (written by the library, no render needed) that merge: samples 0..2 and 2..4 of a 4×2 frame.
fn two_parts(dir: &Path) -> (PathBuf, PathBuf) {
    use strata::partial::{file::write_part, SampleSet};
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    write_part(&a, &part(4, 2, 4, SampleSet::range(0, 2), 1 << 23)).unwrap();
    write_part(&b, &part(4, 2, 4, SampleSet::range(2, 4), 1 << 23)).unwrap();
    (a, b)
}

/// A merge's output or --exr on one of its parts, in every spelling: refused, both parts still there as they were.
#[test]
fn a_merge_never_overwrites_or_removes_its_parts() {
    let dir = temp_dir("merge-aliases");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::os::unix::fs::symlink(&dir, dir.join("sub/link")).unwrap();
    let (a, b) = two_parts(&dir);
    let before = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    std::os::unix::fs::symlink(&a, dir.join("alias.exr")).unwrap();
    let d = |name: &str| s(&dir.join(name));
    let cases: Vec<Vec<String>> = vec![
        vec![
            d("a.exr"),
            d("b.exr"),
            "-o".into(),
            format!("{}/./a.exr", s(&dir)),
            "--partial".into(),
            "--remove-parts".into(),
        ],
        vec![
            d("a.exr"),
            d("b.exr"),
            "-o".into(),
            d("m.png"),
            "--exr".into(),
            format!("{}/./b.exr", s(&dir)),
            "--remove-parts".into(),
        ],
        vec![d("a.exr"), d("b.exr"), "-o".into(), s(&std::fs::canonicalize(&b).unwrap()), "--partial".into()],
        vec![d("a.exr"), d("b.exr"), "-o".into(), d("sub/link/a.exr"), "--partial".into()],
        vec![d("a.exr"), d("b.exr"), "-o".into(), d("sub/../b.exr"), "--partial".into()],
        vec![d("alias.exr"), d("b.exr"), "-o".into(), d("a.exr"), "--partial".into()],
        vec![d("a.exr"), d("sub/link/a.exr"), "-o".into(), d("m.exr"), "--partial".into(), "--remove-parts".into()],
    ];
    for args in cases {
        let mut all = vec!["merge".to_string()];
        all.extend(args.iter().cloned());
        let out = strata(&all);
        let text = refused(&out, &["the part"]);
        assert!(collides(&text), "{args:?}: {text}");
    }
    assert_eq!((std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap()), before, "a part was changed");
    assert!(!dir.join("m.png").exists() && !dir.join("m.exr").exists());
    // The same parts merge when the output is a file of its own (the control).
    let out = strata(&["merge", &d("a.exr"), &d("b.exr"), "-o", &d("ab.exr"), "--partial", "--remove-parts"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(dir.join("ab.exr").is_file() && !a.exists() && !b.exists());
}

/// Two scenes whose `{name}` is the same, or a name that is `..`: refused before anything renders.
#[test]
fn a_batch_never_writes_one_file_twice_or_outside_its_folder() {
    let dir = temp_dir("batch");
    let box_gltf = repo_file("tests/data/gltf-samples/Box.gltf");
    for sub in ["d1", "d2", "out"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    std::fs::copy(&box_gltf, dir.join("d1/Box.gltf")).unwrap();
    std::fs::copy(&box_gltf, dir.join("d2/Box.gltf")).unwrap();
    std::fs::copy(&box_gltf, dir.join("d2/...gltf")).unwrap();
    std::fs::copy(&box_gltf, dir.join("d2/box.gltf")).unwrap();
    let d = |name: &str| s(&dir.join(name));
    let out_pattern = d("out/{name}.png");
    // The reproducer, and the same file reached through `..`.
    for (first, second) in [(d("d1/Box.gltf"), d("d2/Box.gltf")), (d("d1/Box.gltf"), d("d2/../d2/Box.gltf"))] {
        let (out, _) = finishes_within(command(&["render", &first, &second, "-o", &out_pattern]), PROMPTLY);
        refused(&out, &["Box.png", "d1/Box.gltf", "one would overwrite the other"]);
    }
    // Two names that differ only in an --aov file beside them collide too: x.png's normals are x.normal.png.
    std::fs::copy(&box_gltf, dir.join("d1/x.gltf")).unwrap();
    std::fs::copy(&box_gltf, dir.join("d2/x.normal.gltf")).unwrap();
    let (out, _) = finishes_within(
        command(&["render", &d("d1/x.gltf"), &d("d2/x.normal.gltf"), "-o", &out_pattern, "--aov", "normal"]),
        PROMPTLY,
    );
    refused(&out, &["x.normal.png"]);
    // A scene named `...gltf` would make `{name}` climb out of out/: refused, alone or in a batch.
    for scenes in [vec![d("d2/...gltf")], vec![d("d1/Box.gltf"), d("d2/...gltf")]] {
        let mut args = vec!["render".to_string()];
        args.extend(scenes);
        args.extend(["-o".to_string(), out_pattern.clone()]);
        let (out, _) = finishes_within(command(&args), PROMPTLY);
        refused(&out, &["...gltf", "cannot stand for {name}"]);
    }
    assert!(listing(&dir.join("out")).is_empty(), "{:?}", listing(&dir.join("out")));
    assert!(!listing(&dir).iter().any(|n| n.ends_with(".png")), "{:?}", listing(&dir));
}

/// Where a destination cannot take the file, the run ends before the work: a checkpoint in a missing folder or
/// on a directory, an existing directory as -o, a symlink, a FIFO or a device where the output would go.
#[test]
fn impossible_destinations_are_refused_before_the_render() {
    let dir = temp_dir("impossible");
    std::fs::create_dir_all(dir.join("taken.png")).unwrap();
    std::fs::create_dir_all(dir.join("taken.exr")).unwrap();
    std::os::unix::fs::symlink("/dev/null", dir.join("device-link.png")).unwrap();
    std::os::unix::fs::symlink(dir.join("elsewhere.png"), dir.join("link.png")).unwrap();
    make_fifo(&dir.join("fifo.png"));
    let d = |name: &str| s(&dir.join(name));
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["-o".into(), d("x.png"), "--checkpoint".into(), d("missing/ck.exr")], "does not exist"),
        (vec!["-o".into(), d("x.png"), "--checkpoint".into(), d("taken.exr")], "a directory is there"),
        (vec!["-o".into(), d("x.png"), "--checkpoint".into(), format!("{}/new.exr/", s(&dir))], "not a file name"),
        (vec!["-o".into(), d("taken.png")], "a directory is there"),
        (vec!["-o".into(), format!("{}/taken.png/", s(&dir))], "not a file name"),
        (vec!["-o".into(), d("x.png"), "--exr".into(), d("taken.exr")], "a directory is there"),
        (vec!["-o".into(), d("device-link.png")], "symbolic link"),
        (vec!["-o".into(), d("link.png")], "symbolic link"),
        (vec!["-o".into(), d("fifo.png")], "device, FIFO or socket"),
    ];
    for (args, expected) in cases {
        let (out, _) = finishes_within(long_render(&args), PROMPTLY);
        refused(&out, &[expected]);
    }
    assert!(dir.join("taken.png").is_dir() && dir.join("fifo.png").exists());
    assert_eq!(std::fs::read_link(dir.join("device-link.png")).unwrap(), Path::new("/dev/null"));
    assert!(!dir.join("x.png").exists() && !dir.join("elsewhere.png").exists());
}

pub fn make_fifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo {}", path.display());
}

/// A command that runs as a user who cannot write in `dir`: as root (CI), the child drops to `nobody`, for whom
/// a directory of root's with mode 755 is read-only; as anyone else, the directory is made read-only.
fn unwritable_for(dir: &Path, mut cmd: std::process::Command) -> std::process::Command {
    use std::os::unix::fs::PermissionsExt as _;
    use std::os::unix::process::CommandExt as _;
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o555)).unwrap();
    if unsafe { libc::geteuid() } == 0 {
        cmd.uid(65534).gid(65534);
    }
    cmd
}

/// An unwritable place for the checkpoint, -o or --junit is found before the render or the suite.
#[test]
fn unwritable_destinations_are_refused_before_the_work() {
    let parent = temp_dir("unwritable");
    let locked = parent.join("locked");
    std::fs::create_dir_all(&locked).unwrap();
    let d = |name: &str| s(&locked.join(name));
    let writable = std::env::temp_dir();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["render".into(), cornell(), "-o".into(), d("x.png")], "cannot write in"),
        (
            vec![
                "render".into(),
                cornell(),
                "-o".into(),
                s(&writable.join(format!("strata-unwritable-{}.png", std::process::id()))),
                "--checkpoint".into(),
                d("ck.exr"),
            ],
            "--checkpoint",
        ),
        (
            vec![
                "check".into(),
                "--out".into(),
                s(&writable.join(format!("strata-unwritable-report-{}", std::process::id()))),
                "--junit".into(),
                d("junit.xml"),
                "--cases".into(),
                "optics/penumbra".into(),
            ],
            "--junit",
        ),
    ];
    for (mut args, expected) in cases {
        if args[0] == "render" {
            args.extend(LONG_RENDER.iter().map(|a| a.to_string()));
        }
        let (out, _) = finishes_within(unwritable_for(&locked, command(&args)), PROMPTLY);
        let text = refused(&out, &[expected, "locked"]);
        assert!(!text.contains("wrote"), "{text}");
    }
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    assert!(listing(&locked).is_empty());
}

/// `strata check --junit` on a directory, in a missing folder, or on one of the reports: refused before any case.
#[test]
fn check_reports_are_planned_before_the_suite() {
    let dir = temp_dir("check-plan");
    std::fs::create_dir_all(dir.join("a-directory.xml")).unwrap();
    let report = dir.join("report");
    for (junit, expected) in [
        (dir.join("a-directory.xml"), "a directory is there"),
        (dir.join("missing/junit.xml"), "does not exist"),
        (report.join("results.csv"), "results.csv"),
        (report.join("../report/./summary.md"), "summary.md"),
    ] {
        let args = ["check", "--out", &s(&report), "--junit", &s(&junit), "--cases", "optics/penumbra"];
        let (out, _) = finishes_within(command(&args), PROMPTLY);
        let text = refused(&out, &[expected]);
        assert!(expected.contains(' ') || collides(&text), "{text}");
        assert!(!report.join("results.json").exists(), "a case ran before the refusal");
    }
}

/// Runs `strata ARGS` with its outputs on a file system of `bytes` (a tmpfs mounted in a mount namespace of its
/// own, `unshare -rm`: no privileges needed, nothing mounted outside the child): a full disk. `{disk}` in the
/// arguments is the tmpfs's directory. Returns the run and what it left on the disk.
fn on_a_full_disk(tag: &str, bytes: u64, args: &[&str]) -> (std::process::Output, Vec<String>) {
    let dir = temp_dir(tag);
    let disk = dir.join("disk");
    std::fs::create_dir_all(&disk).unwrap();
    let script = r#"mount -t tmpfs -o size="$1" tmpfs "$2" || exit 99
shift 2
"$@"
status=$?
echo "LEFT ON THE DISK:"
ls -A "$(dirname "$0")/disk"
exit $status"#;
    let mut all: Vec<String> = vec!["-rm".into(), "sh".into(), "-c".into(), script.into(), s(&dir.join("sh"))];
    all.extend([bytes.to_string(), s(&disk), env!("CARGO_BIN_EXE_strata").to_string()]);
    all.extend(args.iter().map(|a| a.replace("{disk}", &s(&disk))));
    let mut cmd = std::process::Command::new("unshare");
    cmd.args(&all);
    for name in crate::common::cli::SCHEDULER_VARIABLES {
        cmd.env_remove(name);
    }
    let (out, _) = finishes_within(cmd, PROMPTLY * 5);
    assert_ne!(out.status.code(), Some(99), "could not mount a tmpfs in a user namespace: {}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let left = stdout
        .split("LEFT ON THE DISK:")
        .nth(1)
        .unwrap_or("")
        .lines()
        .filter(|l| !l.is_empty())
        .map(String::from)
        .collect();
    (out, left)
}

/// A full disk at the --exr after a good PNG: the run fails and leaves neither file (nor a temporary one).
#[test]
fn a_failed_exr_leaves_no_png_behind() {
    // A 48×48 PNG is under 8 KB; the EXR's four float channels are over 16 KB however they compress.
    let (out, left) = on_a_full_disk(
        "full-disk-exr",
        16 << 10,
        &[
            "render",
            &cornell(),
            "-o",
            "{disk}/out.png",
            "--exr",
            "{disk}/out.exr",
            "--size",
            "48x48",
            "--spp",
            "2",
            "--validate",
            "--quiet",
        ],
    );
    let text = refused(&out, &["out.exr"]);
    assert!(left.is_empty(), "left behind: {left:?}; {text}");
}

/// A checkpoint that cannot be written (a full disk) is a warning: the render goes on and writes its output.
#[test]
fn a_full_disk_at_a_checkpoint_does_not_abort_the_render() {
    // The PNG fits in 16 KB; a part of 48×48 sums (36 bytes a pixel) does not.
    let (out, left) = on_a_full_disk(
        "full-disk-checkpoint",
        16 << 10,
        &[
            "render",
            &cornell(),
            "-o",
            "{disk}/out.png",
            "--checkpoint",
            "{disk}/ck.exr",
            "--checkpoint-every",
            "0.01",
            "--size",
            "48x48",
            // Three batches of 8 (render::frame's batch size): a checkpoint after each of the first two.
            "--spp",
            "24",
            "--validate",
            "--quiet",
        ],
    );
    let text = stderr(&out);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("warning: the checkpoint was not saved") && text.contains("ck.exr"), "{text}");
    assert_eq!(left, vec!["out.png".to_string()], "{text}");
}

/// Hidden temporary files strata left behind.
fn leftovers(dir: &Path) -> Vec<String> {
    listing(dir).into_iter().filter(|n| n.starts_with(".strata-")).collect()
}

/// A legal 249-byte output name (and one of 255, the file system's limit) is written: the temporary file's
/// name no longer grows with it. One byte more is refused before the render.
#[test]
fn the_longest_legal_output_names_are_written() {
    let dir = temp_dir("long-names");
    for length in [249usize, 255] {
        let name = format!("{}.png", "n".repeat(length - 4));
        let path = dir.join(&name);
        let out =
            strata(&["render", &cornell(), "-o", &s(&path), "--size", "16x16", "--spp", "1", "--validate", "--quiet"]);
        assert!(out.status.success(), "{length}: {}", stderr(&out));
        assert!(path.is_file());
    }
    let too_long = dir.join(format!("{}.png", "n".repeat(252)));
    let (out, _) = finishes_within(long_render(&["-o".into(), s(&too_long)]), PROMPTLY);
    refused(&out, &["file systems take 255"]);
    assert!(leftovers(&dir).is_empty());
}
