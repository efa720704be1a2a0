//! Files strata did not write and numbers no render makes (issue 34, problems 3, 4, 7, 8 and 9): headers that
//! claim huge images end in a clean error naming the file under a 2 GB memory limit; a part's header values are
//! held to the render's own bounds; sample sets and expectations parse in linear time; special files are named
//! as what they are; shards beyond the sample count are empty, not errors; counts cannot wrap.
use super::destinations::make_fifo;
use super::{finishes_within, listing, part, refused, LONG_RENDER, PROMPTLY};
use crate::common::cli::{command, repo_file, stderr, strata, temp_dir};
use std::path::{Path, PathBuf};
use std::time::Duration;
use strata::partial::file::write_part;

fn cornell() -> String {
    repo_file("scenes/cornell.toml").display().to_string()
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Rewrites an OpenEXR file's data and display windows to claim a `width × height` image (the rest of the file,
/// its offset table and pixels, stays that of the small image it was).
fn claim_size(path: &Path, width: i32, height: i32) {
    let mut bytes = std::fs::read(path).unwrap();
    for attribute in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes.windows(attribute.len()).position(|w| w == attribute).expect("the attribute") + attribute.len();
        // A 4-byte size (16), then xMin, yMin, xMax, yMax.
        let values = [0, 0, width - 1, height - 1];
        for (i, v) in values.iter().enumerate() {
            bytes[at + 4 + 4 * i..at + 8 + 4 * i].copy_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// Rewrites a scanline OpenEXR file into a tiled one of a single `width × height` tile claiming that size: its
/// offset table then has one entry, so nothing about the file's length gives the claim away but the pixels it
/// cannot hold (this is how a 982-byte file claimed 100000×100000 and made strata allocate 40 GB).
fn claim_one_tile(path: &Path, width: i32, height: i32) {
    claim_size(path, width, height);
    let mut bytes = std::fs::read(path).unwrap();
    // Walk the attributes (name\0 type\0 size value) to the header's closing zero byte.
    let mut at = 8;
    while bytes[at] != 0 {
        let name_end = at + bytes[at..].iter().position(|&b| b == 0).unwrap();
        let type_end = name_end + 1 + bytes[name_end + 1..].iter().position(|&b| b == 0).unwrap();
        let size = i32::from_le_bytes(bytes[type_end + 1..type_end + 5].try_into().unwrap()) as usize;
        at = type_end + 5 + size;
    }
    let mut tiles = b"tiles\0tiledesc\0".to_vec();
    tiles.extend(9i32.to_le_bytes());
    tiles.extend((width as u32).to_le_bytes());
    tiles.extend((height as u32).to_le_bytes());
    tiles.push(0); // one level, rounding down
    bytes.splice(at..at, tiles);
    // The part's type, as the exr crate writes it for a single part: a tiled image now.
    let scanline = b"type\0string\0\x0d\0\0\0scanlineimage";
    if let Some(i) = bytes.windows(scanline.len()).position(|w| w == scanline) {
        bytes.splice(i..i + scanline.len(), b"type\0string\0\x0a\0\0\0tiledimage".iter().copied());
    }
    // The version field's "single tiled part" flag (bit 9).
    bytes[5] |= 0x02;
    std::fs::write(path, bytes).unwrap();
}

/// Makes a small EXR claim `width × height`: as one tile where its name says "tile", else in scanlines.
fn claim(path: &Path, width: i32, height: i32) {
    if path.to_string_lossy().contains("tile") {
        claim_one_tile(path, width, height);
    } else {
        claim_size(path, width, height);
    }
}

/// `command` with at most 2 GiB of address space (RLIMIT_AS): an allocation of a header's claim fails as it
/// would on a small machine, and must be an error, not an abort.
fn with_memory_limit(mut cmd: std::process::Command) -> std::process::Command {
    use std::os::unix::process::CommandExt as _;
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit { rlim_cur: 2 << 30, rlim_max: 2 << 30 };
            if libc::setrlimit(libc::RLIMIT_AS, &limit) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd
}

/// A Radiance .hdr header claiming `width × height`, with `body` after it.
fn hdr_with(path: &Path, width: u32, height: u32, body: &[u8]) {
    let mut bytes = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    bytes.extend_from_slice(body);
    std::fs::write(path, bytes).unwrap();
}

/// Headers that claim huge images (problem 3), as parts (merge, --resume) and environments (.exr, .hdr): each
/// ends under a 2 GB limit in an error naming the file, exit 1, promptly; none is decoded first.
#[test]
fn huge_claims_in_headers_are_refused_before_any_allocation() {
    let dir = temp_dir("huge-claims");
    let d = |name: &str| dir.join(name);
    let small = part(1, 1, 4, strata::partial::SampleSet::range(0, 4), 7);
    let parts = [
        ("part-100000.exr", 100_000, 100_000),
        ("part-16385.exr", 16_385, 16_385),
        ("part-in-limit.exr", 16_384, 16_384),
        ("part-tile-100000.exr", 100_000, 100_000),
        ("part-tile-in-limit.exr", 16_384, 16_384),
    ];
    for (name, w, h) in parts {
        write_part(&d(name), &small).unwrap();
        claim(&d(name), w, h);
    }
    let tiny = strata::output::Frame::new(1, 1, vec![[1.0, 1.0, 1.0, 1.0]]).unwrap();
    let environments = [
        ("env-100000.exr", 100_000, 100_000),
        ("env-16385.exr", 16_385, 16_385),
        ("env-in-limit.exr", 16_384, 8_192),
        ("env-tile-100000.exr", 100_000, 100_000),
        ("env-tile-in-limit.exr", 16_384, 8_192),
    ];
    for (name, w, h) in environments {
        strata::output::write_frame(&d(name), &tiny).unwrap();
        claim(&d(name), w, h);
    }
    hdr_with(&d("env-in-limit.hdr"), 16_384, 8_192, &[2, 2, 64, 0, 1, 1, 1, 1]);
    hdr_with(&d("env-16385.hdr"), 16_385, 16_385, &[]);
    let bytes = std::fs::metadata(d("part-100000.exr")).unwrap().len();
    assert!(bytes < 2000, "the reproducer is a small file ({bytes} bytes)");
    let mut cases: Vec<(Vec<String>, String)> = Vec::new();
    for (name, _, _) in parts {
        cases.push((vec!["merge".into(), s(&d(name)), "-o".into(), s(&d("m.png"))], name.into()));
        let mut resume = vec!["render".into(), cornell(), "-o".into(), s(&d("r.png")), "--resume".into(), s(&d(name))];
        resume.extend(LONG_RENDER.iter().map(|a| a.to_string()));
        cases.push((resume, name.into()));
    }
    for name in environments.iter().map(|e| e.0).chain(["env-in-limit.hdr", "env-16385.hdr"]) {
        let mut args =
            vec!["render".into(), cornell(), "-o".into(), s(&d("e.png")), "--environment".into(), s(&d(name))];
        args.extend(LONG_RENDER.iter().map(|a| a.to_string()));
        cases.push((args, name.into()));
    }
    for (args, name) in cases {
        let (out, took) = finishes_within(with_memory_limit(command(&args)), PROMPTLY);
        let text = refused(&out, &[&name]);
        assert_eq!(out.status.code(), Some(1), "{name}: {text}");
        assert!(!text.contains("memory allocation"), "{name}: {text}");
        eprintln!("{name}: refused in {:.3} s: {}", took.as_secs_f64(), text.trim());
    }
    assert!(!d("m.png").exists() && !d("r.png").exists() && !d("e.png").exists());
}

/// A valid RLE .hdr larger than the image crate's default 512 MB budget (8192×6000 texels, 590 MB) loads: the
/// limit strata applies is its own documented one (16384 a side), not a decoder's default.
#[test]
fn a_large_valid_hdr_within_the_limit_loads() {
    let dir = temp_dir("large-hdr");
    let (width, height) = (8192u32, 6000u32);
    // Each scanline: the new-RLE marker, then each of R, G, B, E as runs of at most 127 equal bytes.
    let (r, g, b, e) = (128u8, 64u8, 32u8, 129u8); // (0.5, 0.25, 0.125) × 2^(129-128-8)·2 … checked below
    let mut line = vec![2u8, 2, (width >> 8) as u8, (width & 0xff) as u8];
    for value in [r, g, b, e] {
        let mut left = width;
        while left > 0 {
            let run = left.min(127);
            line.extend([128 + run as u8, value]);
            left -= run;
        }
    }
    let body: Vec<u8> = line.iter().copied().cycle().take(line.len() * height as usize).collect();
    let path = dir.join("big.hdr");
    hdr_with(&path, width, height, &body);
    let environment = strata::scene::environment::Environment::load(&path).expect("a valid .hdr within the limit");
    assert_eq!((environment.width, environment.height), (width, height));
    // RGBE: channel × 2^(E − 136).
    let expected = glam::Vec3::new(f32::from(r), f32::from(g), f32::from(b)) * 2f32.powi(i32::from(e) - 136);
    assert_eq!(environment.texels[0], expected);
    assert_eq!(environment.texels[environment.texels.len() - 1], expected);
}

/// Header values no render writes (problem 7): no samples, an exposure that is NaN, infinite or absurd, sums
/// beyond what the samples can make. Each refused naming the file and the field, by merge and by --resume.
#[test]
fn part_header_values_are_held_to_the_renders_bounds() {
    let dir = temp_dir("part-values");
    let d = |name: &str| dir.join(name);
    let all = strata::partial::SampleSet::range(0, 4);
    write_part(&d("none.exr"), &part(2, 2, 4, strata::partial::SampleSet::default(), 0)).unwrap();
    for (name, exposure) in
        [("nan.exr", f32::NAN), ("inf.exr", f32::INFINITY), ("-inf.exr", f32::NEG_INFINITY), ("huge.exr", 3.4e38)]
    {
        let mut p = part(2, 2, 4, all.clone(), 7);
        p.look.exposure = exposure;
        write_part(&d(name), &p).unwrap();
    }
    write_part(&d("ones.exr"), &part(2, 2, 4, all.clone(), u64::MAX)).unwrap();
    // One sample's most, plus one: the first value past the bound.
    let most = 1u64 << 47;
    write_part(&d("past.exr"), &part(2, 2, 4, strata::partial::SampleSet::range(0, 1), most + 1)).unwrap();
    write_part(&d("at.exr"), &part(2, 2, 4, strata::partial::SampleSet::range(0, 1), most)).unwrap();
    let cases = [
        ("none.exr", "holds no samples"),
        ("nan.exr", "strata.exposure is NaN"),
        ("inf.exr", "strata.exposure is inf"),
        ("-inf.exr", "strata.exposure is -inf"),
        ("huge.exr", "strata.exposure is 340000000000000000000000000000000000000"),
        ("ones.exr", "more than 4 samples can make"),
        ("past.exr", "more than 1 samples can make"),
    ];
    for (name, expected) in cases {
        let merged = strata(&["merge", &s(&d(name)), "-o", &s(&d("m.png"))]);
        refused(&merged, &[name, expected]);
        let mut args =
            vec!["render".to_string(), cornell(), "-o".into(), s(&d("r.png")), "--resume".into(), s(&d(name))];
        args.extend(LONG_RENDER.iter().map(|a| a.to_string()));
        let (resumed, _) = finishes_within(command(&args), PROMPTLY);
        refused(&resumed, &[name, expected]);
    }
    // The bound itself is what a render can make: read, not refused.
    assert!(strata::partial::file::read_part(&d("at.exr")).is_ok());
    assert!(!d("m.png").exists() && !d("r.png").exists());
}

/// Option values no camera or render makes (problems 4 and 7): refused by the parser, with the bound said.
#[test]
fn numeric_options_are_bounded_where_their_meaning_ends() {
    let cases: [(&[&str], &str); 9] = [
        (&["--checkpoint-every", "1e30"], "0.01 to 86400"),
        (&["--checkpoint-every", "inf"], "0.01 to 86400"),
        (&["--ev100=-100"], "between -60 and 60"),
        (&["--ev100=-3.4e38"], "between -60 and 60"),
        (&["--ev100", "1e39"], "between -60 and 60"),
        (&["--exposure=-65"], "between -64 and 64"),
        (&["--fps", "1e-45"], "a frame rate from 0.001 to 1000"),
        (&["--time", "3e38"], "a time in seconds"),
        (&["--aperture", "1e30"], "an aperture radius"),
    ];
    for (options, expected) in cases {
        let mut args = vec!["render", "scene.gltf", "-o", "x.png"];
        args.extend_from_slice(options);
        let out = strata(&args);
        assert_eq!(out.status.code(), Some(2), "{options:?}: {}", stderr(&out));
        let text = stderr(&out);
        assert!(text.contains(expected) && !text.contains("panicked"), "{options:?}: {text}");
    }
    let help = String::from_utf8_lossy(&strata(&["render", "--help"]).stdout).into_owned();
    for bound in ["0.01 to 86400", "From -60 to 60", "-64 to 64", "0.001 to 1000", "at most 100000"] {
        assert!(help.contains(bound), "--help should say {bound:?}");
    }
}

/// Sample sets of 100,000 ranges (problem 8) parse and merge in linear time: what took 12 s takes milliseconds.
/// The bound is loose: it tells linear from quadratic on a loaded machine, not a speed goal.
#[test]
fn many_sample_ranges_merge_in_linear_time() {
    let dir = temp_dir("many-ranges");
    let d = |name: &str| dir.join(name);
    let ranges = |offset: u32, count: u32| {
        let text: Vec<String> = (0..count).map(|i| format!("{}..{}", 2 * i + offset, 2 * i + offset + 1)).collect();
        strata::partial::SampleSet::parse(&text.join(",")).unwrap()
    };
    // 100,000 ranges: more than the largest frame holds, so the merge refuses it, after reading it.
    write_part(&d("too-many.exr"), &part(2, 2, 65_536, ranges(0, 100_000), 1)).unwrap();
    let (out, took) =
        finishes_within(command(&["merge", &s(&d("too-many.exr")), "-o", &s(&d("m.exr")), "--partial"]), PROMPTLY);
    let text = refused(&out, &["too-many.exr", "beyond the frame's 65536"]);
    assert!(text.len() < 1000, "the message quotes the whole set: {} bytes", text.len());
    assert!(took < Duration::from_secs(5), "{took:?}");
    // Two parts of 32,768 ranges each, interleaved: every sample once.
    write_part(&d("even.exr"), &part(2, 2, 65_536, ranges(0, 32_768), 1)).unwrap();
    write_part(&d("odd.exr"), &part(2, 2, 65_536, ranges(1, 32_768), 1)).unwrap();
    let (out, took) = finishes_within(
        command(&["merge", &s(&d("even.exr")), &s(&d("odd.exr")), "-o", &s(&d("all.exr")), "--partial"]),
        PROMPTLY,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(took < Duration::from_secs(5), "{took:?}");
    let merged = strata::partial::file::read_part(&d("all.exr")).unwrap();
    assert_eq!(merged.sums.samples.ranges(), &[(0, 65_536)]);
}

/// Expectations (problem 8): 100,000 entries load in linear time; /dev/zero and a FIFO are refused at once; a
/// 1.4 MB pattern's error quotes a line, not the pattern.
#[test]
fn expectations_are_read_bounded_and_in_linear_time() {
    let dir = temp_dir("expectations");
    let d = |name: &str| dir.join(name);
    let mut toml = String::new();
    for i in 0..100_000 {
        toml.push_str(&format!("[[expect]]\ncase = \"golden/scene-{i}\"\nstatus = \"Fail\"\nreason = \"known\"\n"));
    }
    std::fs::write(d("many.toml"), toml).unwrap();
    let mut csv = String::from("case,status,reason\n");
    for i in 0..100_000 {
        csv.push_str(&format!("golden/scene-{i},Fail,known\n"));
    }
    std::fs::write(d("many.csv"), csv).unwrap();
    for name in ["many.toml", "many.csv"] {
        let (out, took) = finishes_within(command(&["check", "--expectations", &s(&d(name)), "--list"]), PROMPTLY);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        assert!(took < Duration::from_secs(10), "{name}: {took:?} (over 30 s when quadratic)");
    }
    make_fifo(&d("fifo.toml"));
    std::fs::create_dir_all(d("dir.toml")).unwrap();
    for (path, expected) in
        [(PathBuf::from("/dev/zero"), "a device"), (d("fifo.toml"), "a FIFO"), (d("dir.toml"), "a directory")]
    {
        let (out, _) = finishes_within(command(&["check", "--expectations", &s(&path), "--list"]), PROMPTLY);
        refused(&out, &[&s(&path), expected]);
    }
    let pattern = "(".repeat(1_400_000);
    std::fs::write(d("regex.toml"), format!("[[expect]]\ncase = \"{pattern}\"\nstatus = \"Fail\"\nreason = \"r\"\n"))
        .unwrap();
    let (out, _) = finishes_within(command(&["check", "--expectations", &s(&d("regex.toml")), "--list"]), PROMPTLY);
    let text = refused(&out, &["regex.toml:1", "not a valid regular expression"]);
    assert!(text.len() < 2000, "the message is {} bytes", text.len());
    // The same through --cases (an argument holds at most 128 KiB).
    let pattern = "(".repeat(100_000);
    let (out, _) = finishes_within(command(&["check", "--cases", &pattern, "--list"]), PROMPTLY);
    let text = refused(&out, &["--cases", "not a valid regular expression"]);
    assert!(text.len() < 2000, "the message is {} bytes", text.len());
}

/// A directory, a loop of symlinks, /dev/zero and a FIFO as a part, --resume or --environment (problem 9): each
/// named as what it is, never "no such file", and never a hang.
#[test]
fn special_files_are_named_as_what_they_are() {
    let dir = temp_dir("special-files");
    let d = |name: &str| dir.join(name);
    std::fs::create_dir_all(d("dir.exr")).unwrap();
    std::os::unix::fs::symlink(d("loop-b.exr"), d("loop-a.exr")).unwrap();
    std::os::unix::fs::symlink(d("loop-a.exr"), d("loop-b.exr")).unwrap();
    make_fifo(&d("fifo.exr"));
    std::os::unix::fs::symlink("/dev/zero", d("zero.exr")).unwrap();
    let kinds = [
        ("dir.exr", "a directory"),
        ("loop-a.exr", "a loop of symbolic links"),
        ("fifo.exr", "a FIFO"),
        ("zero.exr", "a device"),
    ];
    for (name, kind) in kinds {
        let path = s(&d(name));
        let mut runs = vec![command(&["merge", &path, "-o", &s(&d("m.png"))])];
        for option in ["--resume", "--environment"] {
            let mut args =
                vec!["render".to_string(), cornell(), "-o".into(), s(&d("r.png")), option.into(), path.clone()];
            args.extend(LONG_RENDER.iter().map(|a| a.to_string()));
            runs.push(command(&args));
        }
        for run in runs {
            let (out, _) = finishes_within(run, PROMPTLY);
            let text = refused(&out, &[name, kind]);
            assert!(!text.contains("no such file"), "{text}");
        }
    }
    let (out, _) =
        finishes_within(command(&["render", &cornell(), "-o", "x.png", "--environment", "/dev/zero"]), PROMPTLY);
    refused(&out, &["/dev/zero", "a device"]);
    assert!(!listing(&dir).iter().any(|n| n.ends_with(".png")));
}

/// More shards than samples or frames (problem 9): the empty shard says so and exits 0, writing nothing, for a
/// frame (by hand, and a Slurm array of 1000 tasks) and a sequence.
#[test]
fn shards_beyond_the_work_are_empty_not_errors() {
    let dir = temp_dir("empty-shards");
    let part = s(&dir.join("part.exr"));
    let frames = s(&dir.join("frame.#.png"));
    let runs: Vec<(std::process::Command, &str)> = vec![
        (command(&["render", &cornell(), "--spp", "4", "--shard", "1/5", "-o", &part, "--validate"]), "has no samples"),
        (
            {
                let mut c =
                    command(&["render", &cornell(), "--spp", "4", "--shard", "auto", "-o", &part, "--validate"]);
                c.env("SLURM_ARRAY_TASK_ID", "0").env("SLURM_ARRAY_TASK_COUNT", "1000");
                c
            },
            "1000 shards share the frame's 4",
        ),
        (
            command(&["render", &cornell(), "--frames", "1..3", "--shard", "1/5", "-o", &frames, "--validate"]),
            "has no frames",
        ),
    ];
    for (run, expected) in runs {
        let (out, _) = finishes_within(run, PROMPTLY);
        let text = stderr(&out);
        assert!(out.status.success(), "{text}");
        assert!(text.contains(expected) && text.contains("nothing to do"), "{text}");
    }
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
}

/// Counts that 32 bits would wrap (problem 9): 2^32 frames, task 2^32.
#[test]
fn counts_do_not_wrap_in_messages() {
    let out = strata(&["render", "scene.gltf", "-o", "x.png", "--frames", "0..4294967295"]);
    assert!(stderr(&out).contains("4294967296 frames is more than one run renders (100000)"), "{}", stderr(&out));
    let mut run = command(&["render", &cornell(), "--shard", "auto/4", "-o", "x.exr"]);
    run.env("JOB_COMPLETION_INDEX", "4294967295");
    let (out, _) = finishes_within(run, PROMPTLY);
    refused(&out, &["Kubernetes's task 4294967296 is beyond its 4 tasks"]);
}
