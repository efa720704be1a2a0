//! The `strata` command as a user runs it: `info`, a real render of the shared Box sample checked against
//! geometry and a CPU twin of the preview shading, and bad input that must fail cleanly without writing.
use crate::common;
use common::cli::{outcome, stderr, strata, temp_dir};
use glam::Vec4Swizzles;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn samples() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf-samples");
    assert!(dir.is_dir(), "the shared glTF samples are missing at {}", dir.display());
    dir
}

#[test]
fn info_lists_a_ray_query_device_and_the_layer() {
    let out = strata(&["info"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "strata info failed: {}\n{text}", outcome(&out));
    assert!(text.contains("Validation layer: VK_LAYER_KHRONOS_validation"), "{text}");
    assert!(text.contains("ray query: yes"), "{text}");
    assert!(text.contains("pipeline:  yes"), "{text}");
    assert!(text.contains("strata:    usable; --trace auto takes query"), "{text}");
}

#[test]
fn box_renders_where_its_geometry_projects_with_the_expected_shading() {
    let dir = temp_dir("box");
    let scene_path = samples().join("Box.gltf");
    let png = dir.join("box.png");
    let (width, height) = (320u32, 240u32);
    let out = strata(&[
        "render",
        scene_path.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        &format!("{width}x{height}"),
        "--background",
        "0,0,1",
        "--preview",
        "--validate",
    ]);
    assert!(out.status.success(), "render failed: {}", outcome(&out));
    let image = image::open(&png).unwrap().to_rgba8();
    assert_eq!(image.dimensions(), (width, height));

    // Where the box must land: project its world-space vertices with the same camera.
    let scene = strata::load_scene(&scene_path).unwrap();
    let camera = scene.camera_or_default();
    let view_from_world = camera.view_from_world();
    let clip_from_world = camera.clip_from_view(width as f32 / height as f32) * view_from_world;
    let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
    let mut face_colors = Vec::new();
    let base = scene.materials[0].base_color.xyz();
    for instance in &scene.instances {
        for p in &scene.meshes[instance.mesh].primitives {
            for (&v, &n) in p.positions.iter().zip(&p.normals) {
                let clip = clip_from_world * instance.world_from_object.transform_point3(v).extend(1.0);
                let ndc = clip.xy() / clip.w;
                let px = (ndc + 1.0) * 0.5 * glam::Vec2::new(width as f32, height as f32);
                lo = lo.min(px);
                hi = hi.max(px);
                let view_normal = (view_from_world * instance.world_from_object).transform_vector3(n).normalize();
                face_colors.push(strata::render::preview::preview_shade(base, view_normal));
            }
        }
    }
    // Covered pixels: anything not the pure-blue background.
    let (mut cmin, mut cmax) = ((u32::MAX, u32::MAX), (0u32, 0u32));
    let encode = |v: f32| (strata::output::linear_to_srgb(v) * 255.0 + 0.5).floor() as i32;
    for (x, y, px) in image.enumerate_pixels() {
        if px.0 == [0, 0, 255, 255] {
            continue;
        }
        cmin = (cmin.0.min(x), cmin.1.min(y));
        cmax = (cmax.0.max(x), cmax.1.max(y));
        // Box.gltf's material is (0.8, 0, 0): green and blue stay exactly zero, red is one of the faces' shades.
        assert_eq!((px[1], px[2], px[3]), (0, 0, 255), "pixel ({x},{y}) = {:?}", px.0);
        let r = px[0] as i32;
        assert!(
            face_colors.iter().any(|c| (encode(c.x) - r).abs() <= 1),
            "pixel ({x},{y}) red {r} is no face's shade {:?}",
            face_colors.iter().map(|c| encode(c.x)).collect::<Vec<_>>()
        );
    }
    // A pixel is covered when its centre (x + ½) is inside: the covered range matches the projection within 1 px.
    for (axis, got_lo, got_hi) in [(0, cmin.0, cmax.0), (1, cmin.1, cmax.1)] {
        assert!(
            (got_lo as f32 + 0.5 - lo[axis]).abs() <= 1.0,
            "axis {axis}: first covered {got_lo}, edge {}",
            lo[axis]
        );
        assert!((got_hi as f32 + 0.5 - hi[axis]).abs() <= 1.0, "axis {axis}: last covered {got_hi}, edge {}", hi[axis]);
    }
}

#[test]
fn exr_output_holds_linear_radiance() {
    let dir = temp_dir("exr");
    let exr_path = dir.join("box.exr");
    let scene_path = samples().join("Box.gltf");
    let out = strata(&[
        "render",
        scene_path.to_str().unwrap(),
        "-o",
        exr_path.to_str().unwrap(),
        "--size",
        "64x48",
        "--preview",
    ]);
    assert!(out.status.success(), "{}", outcome(&out));
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &exr_path,
        |size, _| (size.width(), vec![[0f32; 4]; size.width() * size.height()]),
        |(w, px), pos, (r, g, b, a): (f32, f32, f32, f32)| px[pos.y() * *w + pos.x()] = [r, g, b, a],
    )
    .unwrap();
    let pixels = &image.layer_data.channel_data.pixels.1;
    // Linear: the reddest pixel is at most the base colour 0.8 (not its sRGB encoding 0.906).
    let max_red = pixels.iter().map(|p| p[0]).fold(0.0, f32::max);
    assert!(max_red > 0.3 && max_red <= 0.8 + 1e-6, "max red {max_red}");
}

#[test]
fn bad_input_fails_clearly_and_writes_nothing() {
    let dir = temp_dir("bad");
    let box_gltf = samples().join("Box.gltf");
    let box_gltf = box_gltf.to_str().unwrap();
    let broken = dir.join("broken.gltf");
    std::fs::write(&broken, "{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ ").unwrap();
    let png = dir.join("out.png");
    let png_s = png.to_str().unwrap();
    let jpg = dir.join("out.jpg");
    let no_dir = dir.join("missing/out.png");
    let obj = dir.join("scene.obj");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["render", "does-not-exist.gltf", "-o", png_s], "does-not-exist.gltf: no such file"),
        (vec!["render", broken.to_str().unwrap(), "-o", png_s], "broken.gltf: not a valid glTF"),
        (vec!["render", box_gltf, "-o", jpg.to_str().unwrap()], "unknown output extension \".jpg\""),
        (vec!["render", box_gltf, "-o", no_dir.to_str().unwrap()], "does not exist"),
        (vec!["render", box_gltf, "-o", png_s, "--size", "0x10"], "outside 1..=16384"),
        (vec!["render", box_gltf, "-o", png_s, "--size", "99999x10"], "outside 1..=16384"),
        (vec!["render", box_gltf, "-o", png_s, "--device", "no-such-gpu"], "matches no Vulkan device"),
        (vec!["render", box_gltf, "-o", png_s, "--device", "7"], "matches no Vulkan device"),
        (vec!["render", obj.to_str().unwrap(), "-o", png_s], "unknown scene extension"),
    ];
    for (args, expected) in cases {
        let out = strata(&args);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr(&out).contains(expected), "{args:?}: stderr does not say {expected:?}:\n{}", stderr(&out));
    }
    let leftovers: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers, vec![std::ffi::OsString::from("broken.gltf")], "files were written");
}

#[test]
fn a_missing_validation_layer_or_driver_says_to_run_setup() {
    let box_gltf = samples().join("Box.gltf");
    let dir = temp_dir("env");
    let png = dir.join("out.png");
    let empty_layers = dir.join("no-layers");
    std::fs::create_dir_all(&empty_layers).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["render", box_gltf.to_str().unwrap(), "-o", png.to_str().unwrap(), "--validate"])
        .env("VK_LAYER_PATH", &empty_layers)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(stderr(&out).contains("scripts/setup.sh"), "{}", stderr(&out));
    let out = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["info"])
        .env("VK_DRIVER_FILES", dir.join("no-driver.json"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(stderr(&out).contains("scripts/setup.sh"), "{}", stderr(&out));
    assert!(!png.exists());
}

#[test]
fn help_teaches_every_command() {
    for args in [vec!["--help"], vec!["render", "--help"], vec!["info", "--help"]] {
        let out = strata(&args);
        assert!(out.status.success());
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains("Usage:") && text.contains("Examples:") || args[0] == "info", "{args:?}:\n{text}");
    }
    let render_help = String::from_utf8_lossy(&strata(&["render", "--help"]).stdout).into_owned();
    for option in ["--output", "--size", "--validate", "--device", "--background", "atomically"] {
        assert!(render_help.contains(option), "render --help lacks {option}");
    }
}

#[test]
fn aovs_are_written_as_exr_layers_and_png_siblings() {
    let dir = temp_dir("aov");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml");
    let exr_path = dir.join("cornell.exr");
    let out = strata(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        exr_path.to_str().unwrap(),
        "--size",
        "48x48",
        "--aov",
        "normal,depth,height",
        "--validate",
    ]);
    assert!(out.status.success(), "{}", outcome(&out));
    let image = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
    let channels = &image.layer_data[0].channel_data.list;
    let get = |name: &str| match &channels.iter().find(|c| c.name.to_string() == name).unwrap().sample_data {
        exr::prelude::FlatSamples::F32(v) => v.clone(),
        other => panic!("{name}: {other:?}"),
    };
    let (nx, ny, nz, covered) = (get("normal.R"), get("normal.G"), get("normal.B"), get("normal.A"));
    let depth = get("depth.R");
    let mut seen = 0;
    for i in 0..nx.len() {
        if covered[i] > 0.0 {
            seen += 1;
            let length = (nx[i] * nx[i] + ny[i] * ny[i] + nz[i] * nz[i]).sqrt();
            assert!((length - 1.0).abs() < 1e-4, "pixel {i}: |n| = {length}");
            // The box spans 2 m in front of a camera 3.9 m away: depths between 2.9 and 4.9 m.
            assert!(depth[i] > 2.8 && depth[i] < 5.0, "pixel {i}: depth {}", depth[i]);
        }
    }
    // The box fills most of the frame; its open front edge shows a border of background.
    assert!(seen > 48 * 48 * 8 / 10, "only {seen} of {} pixels covered", 48 * 48);
    // The height channel varies where walls are bumped.
    let height = get("height.R");
    assert!(height.iter().any(|&h| h != 0.0));
    // PNG output puts each AOV beside the picture.
    let png = dir.join("cornell.png");
    let out = strata(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "32x32",
        "--aov",
        "albedo,normal",
    ]);
    assert!(out.status.success(), "{}", outcome(&out));
    for name in ["cornell.png", "cornell.albedo.png", "cornell.normal.png"] {
        assert!(dir.join(name).is_file(), "{name} missing");
    }
    let bad = strata(&["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--aov", "normals"]);
    assert!(!bad.status.success() && stderr(&bad).contains("unknown AOV \"normals\""));
}

#[test]
fn a_render_prints_a_json_summary_and_writes_png_and_exr() {
    let dir = temp_dir("json");
    let png = dir.join("soft.png");
    let exr = dir.join("soft.exr");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/soft-shadows.toml");
    let out = strata(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--exr",
        exr.to_str().unwrap(),
        "--size",
        "64x40",
        "--spp",
        "4",
        "--json",
        "--quiet",
        "--validate",
    ]);
    assert!(out.status.success(), "{}", outcome(&out));
    assert!(stderr(&out).trim().is_empty(), "--quiet prints nothing on stderr: {}", stderr(&out));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    assert_eq!(summary["spp"], 4);
    assert_eq!(summary["width"], 64);
    let shadow = summary["shadow_rays"].as_u64().unwrap();
    // Every covered pixel of every sample casts at most one shadow ray per path vertex; the floor fills most.
    assert!(shadow > 64 * 40 && shadow <= 64 * 40 * 4 * 4, "shadow rays {shadow}");
    assert!(summary["rays_per_second"].as_f64().unwrap() > 0.0);
    assert_eq!(summary["primary"], "raster");
    assert_eq!(summary["indirect"], false);
    assert_eq!(summary["camera_rays"], 0, "the G-buffer pass rasterises primary visibility");
    assert_eq!(image::open(&png).unwrap().to_rgba8().dimensions(), (64, 40));
    assert!(exr.is_file());

    // --indirect: the diffuse floor now sends paths on, and the summary says so.
    let (scene, png) = (scene.to_str().unwrap(), png.to_str().unwrap());
    let args = ["render", scene, "-o", png, "--size", "64x40", "--spp", "4", "--json", "--quiet", "--validate"];
    let out = strata(&[&args[..], &["--indirect"]].concat());
    assert!(out.status.success(), "{}", outcome(&out));
    let indirect: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    assert_eq!((&indirect["indirect"], &indirect["bounces"]), (&serde_json::json!(true), &serde_json::json!(3)));
    let (with, without) = (indirect["secondary_rays"].as_u64().unwrap(), summary["secondary_rays"].as_u64().unwrap());
    assert!(with > without + 64 * 40, "secondary rays: {with} with --indirect, {without} without");

    // A scene file that turns it on; --no-indirect turns it off again, and the last of the two flags wins.
    let dir_scene = dir.join("indirect.toml");
    let text = std::fs::read_to_string(scene).unwrap();
    let gltf = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/soft-shadows.gltf");
    let text = text.replace("\"soft-shadows.gltf\"", &format!("{:?}", gltf.to_str().unwrap()));
    std::fs::write(&dir_scene, text.replace("[render]", "[render]\nindirect = true")).unwrap();
    let args = ["render", dir_scene.to_str().unwrap(), "-o", png, "--size", "64x40", "--spp", "4", "--json", "--quiet"];
    for (flags, expected) in [(&[][..], true), (&["--no-indirect"], false), (&["--no-indirect", "--indirect"], true)] {
        let out = strata(&[&args[..], flags].concat());
        assert!(out.status.success(), "{flags:?}: {}", outcome(&out));
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
        assert_eq!(summary["indirect"], expected, "{flags:?}");
    }
}

#[test]
fn primary_rays_are_traced_per_pixel_when_asked_and_a_wrong_mode_is_named() {
    let dir = temp_dir("primary");
    let png = dir.join("traced.png");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dof.toml");
    let (scene, png_arg) = (scene.to_str().unwrap(), png.to_str().unwrap());
    let run = |mode: &str| {
        strata(&[
            "render",
            scene,
            "-o",
            png_arg,
            "--size",
            "48x30",
            "--spp",
            "3",
            "--json",
            "--quiet",
            "--validate",
            "--primary",
            mode,
        ])
    };
    let out = run("rays");
    assert!(out.status.success(), "{}", outcome(&out));
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    assert_eq!(summary["primary"], "rays");
    assert_eq!(summary["camera_rays"], 48 * 30 * 3, "one camera ray per pixel and sample");
    assert_eq!(image::open(&png).unwrap().to_rgba8().dimensions(), (48, 30));
    std::fs::remove_file(&png).unwrap();
    let out = run("pathtraced");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("pathtraced") && stderr(&out).contains("raster, rays"), "{}", stderr(&out));
    assert!(!png.exists(), "a refused render writes nothing");
}

/// `--trace query` and `--trace pipeline` write the same PNG bytes of the showcase on lavapipe (one traversal
/// code under both), the summary names the way, `[render] trace` is read, and a wrong word is named.
#[test]
fn both_ways_to_trace_write_the_same_showcase_and_a_wrong_way_is_named() {
    let dir = temp_dir("trace");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let showcase = repo.join("scenes/showcase.toml");
    let render = |scene: &Path, png: &Path, extra: &[&str]| {
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap()];
        args.extend(["--size", "96x54", "--spp", "4", "--json", "--quiet", "--validate"]);
        args.extend(extra);
        strata(&args)
    };
    let mut bytes = Vec::new();
    for way in ["query", "pipeline"] {
        let png = dir.join(format!("{way}.png"));
        let out = render(&showcase, &png, &["--trace", way]);
        assert!(out.status.success(), "--trace {way}: {}", outcome(&out));
        let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
        assert_eq!(summary["trace"], way);
        bytes.push(std::fs::read(&png).unwrap());
    }
    assert!(bytes[0] == bytes[1], "--trace query and --trace pipeline wrote different PNGs");

    // The scene file's [render] table chooses too; the command line wins over it.
    let text = std::fs::read_to_string(&showcase).unwrap().replace("[render]", "[render]\ntrace = \"pipeline\"");
    for file in ["showcase.gltf", "showcase.bin"] {
        std::fs::copy(repo.join("scenes").join(file), dir.join(file)).unwrap();
    }
    let scene = dir.join("trace-in-file.toml");
    std::fs::write(&scene, &text).unwrap();
    let from_file = render(&scene, &dir.join("file.png"), &[]);
    let overridden = render(&scene, &dir.join("cli.png"), &["--trace", "query"]);
    std::fs::write(&scene, text.replace("trace = \"pipeline\"", "trace = \"rtx\"")).unwrap();
    let wrong_in_file = render(&scene, &dir.join("wrong.png"), &[]);
    let trace_of = |o: &Output| {
        assert!(o.status.success(), "{}", outcome(o));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["trace"].clone()
    };
    assert_eq!(trace_of(&from_file), "pipeline");
    assert_eq!(trace_of(&overridden), "query");
    let err = stderr(&wrong_in_file);
    assert!(!wrong_in_file.status.success() && err.contains("trace-") && err.contains("\"rtx\""), "{err}");
    assert!(err.contains("auto, query, pipeline"), "{err}");

    let out = render(&showcase, &dir.join("bad.png"), &["--trace", "rtx"]);
    assert!(!out.status.success() && stderr(&out).contains("auto, query, pipeline"), "{}", outcome(&out));
    assert!(!dir.join("bad.png").exists() && !dir.join("wrong.png").exists(), "a refused render writes nothing");
}

/// Starts a long showcase render into a fresh directory, lets it load, upload and start sampling, then sends it
/// `signal` (a `kill` option); returns how it ended and the directory, which should stay empty. `env`: variables
/// the render runs with besides the suite's.
fn signal_a_long_render(tag: &str, signal: &str, env: &[(&str, &std::ffi::OsStr)]) -> (Output, PathBuf) {
    let dir = temp_dir(tag);
    let png = dir.join("never.png");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.toml");
    let child = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "--size", "320x180", "--spp", "4096"])
        .envs(env.iter().copied())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run strata");
    std::thread::sleep(std::time::Duration::from_secs(3));
    let kill = Command::new("kill").args([signal, &child.id().to_string()]).status().expect("kill");
    assert!(kill.success());
    (child.wait_with_output().expect("wait"), dir)
}

#[test]
fn ctrl_c_stops_the_render_and_writes_nothing() {
    // SIGINT, as a terminal's Ctrl-C sends it.
    let (out, dir) = signal_a_long_render("interrupt", "-INT", &[]);
    assert_eq!(out.status.code(), Some(130), "stderr: {}", stderr(&out));
    assert!(stderr(&out).contains("interrupted"), "{}", stderr(&out));
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "nothing may be left in {}", dir.display());
}

/// A crash in native code (the driver, a layer) is named on stderr, and the signal still ends the process, so the
/// exit status says so too. A real driver crash cannot be had on demand; the signal a crash raises can.
#[test]
fn a_fatal_signal_is_named_on_stderr_and_still_ends_the_process() {
    use std::os::unix::process::ExitStatusExt as _;
    let (out, dir) = signal_a_long_render("crash", "-SEGV", &[]);
    assert_eq!(out.status.signal(), Some(11), "{}", outcome(&out));
    assert!(stderr(&out).contains("strata: crashed with SIGSEGV"), "{}", outcome(&out));
    if std::env::var_os("LP_NATIVE_VECTOR_WIDTH").is_none() {
        assert!(!stderr(&out).contains("LP_NATIVE_VECTOR_WIDTH"), "a hint about a variable not set: {}", outcome(&out));
    }
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "nothing may be left in {}", dir.display());
}

/// Where the user set lavapipe's vector width, a crash message says what Mesa's cache does with it: code cached at
/// another width crashes lavapipe (docs/performance.md, "lavapipe's vector width and Mesa's cache"). The render
/// gets a shader cache of its own, so that it compiles at this width rather than run what the suite cached.
#[test]
fn a_crash_with_lavapipe_s_vector_width_set_names_the_cache_that_crashes_across_widths() {
    use std::os::unix::process::ExitStatusExt as _;
    let cache = temp_dir("crash-width-cache");
    let env = [("LP_NATIVE_VECTOR_WIDTH", std::ffi::OsStr::new("128")), ("MESA_SHADER_CACHE_DIR", cache.as_os_str())];
    let (out, dir) = signal_a_long_render("crash-width", "-SEGV", &env);
    assert_eq!(out.status.signal(), Some(11), "{}", outcome(&out));
    let err = stderr(&out);
    assert!(err.contains("strata: crashed with SIGSEGV"), "{}", outcome(&out));
    assert!(err.contains("LP_NATIVE_VECTOR_WIDTH is set (to 128)") && err.contains("MESA_SHADER_CACHE_DIR"), "{err}");
    assert!(std::fs::read_dir(&dir).unwrap().next().is_none(), "nothing may be left in {}", dir.display());
}

/// The deform benchmark runs end to end under the validation layer (every deformed BLAS rebuild and vertex stream
/// with it) and prints, for both of its scenes, the host's time per sample and its twin's, the GPU's time before
/// the G-buffer deformed and frozen, and both wall times, each a finite positive number.
#[test]
fn the_deform_benchmark_runs_clean_and_prints_every_figure() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(env!("CARGO_BIN_EXE_strata"))
        .current_dir(repo)
        .args(["bench", "--only", "deform", "--size", "32x32", "--spp", "4", "--validate"])
        .output()
        .expect("run strata bench");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "strata bench failed: {}\n{text}", outcome(&out));
    let numbers = |line: &str| -> Vec<f64> {
        line.split(|c: char| !(c.is_ascii_digit() || c == '.')).filter_map(|t| t.parse::<f64>().ok()).collect()
    };
    for scene in ["skinned tube", "MorphStressTest.gltf"] {
        let start = text.find(scene).unwrap_or_else(|| panic!("no {scene} section in:\n{text}"));
        let section: Vec<&str> = text[start..].lines().take(4).collect();
        for (line, label, count) in [(1, "host per sample", 2), (2, "GPU per sample", 2), (3, "frame wall time", 3)] {
            let l = section.get(line).unwrap_or_else(|| panic!("{scene}: no line {line} in:\n{text}"));
            assert!(l.contains(label), "{scene}: {l:?} is not the {label} line");
            let found = numbers(l);
            assert!(found.len() >= count && found.iter().take(count).all(|v| v.is_finite() && *v > 0.0), "{l}");
        }
    }
}

/// The frame benchmark runs end to end under the validation layer on a tiny image and prints every figure it
/// promises, each a finite positive number: per-pass times, both probe ratios, memory and the scaling fits.
#[test]
fn the_frame_benchmark_runs_clean_and_prints_every_figure() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(env!("CARGO_BIN_EXE_strata"))
        .current_dir(repo)
        .args(["bench", "--only", "frame", "--size", "48x32", "--spp", "2", "--validate"])
        .output()
        .expect("run strata bench");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "strata bench failed: {}\n{text}", outcome(&out));
    // Every number after one of these labels, per scene.
    let number_after = |line: &str, label: &str| -> f64 {
        let rest = &line[line.find(label).unwrap_or_else(|| panic!("no {label:?} in {line:?}")) + label.len()..];
        let token: String = rest.trim_start().chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
        token.parse().unwrap_or_else(|_| panic!("no number after {label:?} in {line:?}"))
    };
    for scene in ["scenes/cornell.toml:", "scenes/showcase.toml:"] {
        let start = text.find(scene).unwrap_or_else(|| panic!("no {scene} section in:\n{text}"));
        let section: Vec<&str> = text[start..].lines().skip(1).take(9).collect();
        let find = |prefix: &str| {
            *section
                .iter()
                .find(|l| l.trim_start().starts_with(prefix))
                .unwrap_or_else(|| panic!("{scene} has no {prefix:?} line:\n{text}"))
        };
        let times = find("GPU ms per sample");
        for label in ["TLAS", "G-buffer", "accumulate", "resolve"] {
            assert!(number_after(times, label) > 0.0, "{scene} {label} time in {times:?}");
        }
        let probe = find("accumulate ");
        assert!(number_after(probe, "batches):") > 0.0, "{probe}");
        let replay = find("accumulate vs the probe replaying");
        assert!(number_after(replay, "M rays/s,") > 0.0, "{replay}");
        assert!(number_after(find("reference mode"), "frame") > 0.0);
        assert!(number_after(find("device memory"), "=") > 0.0);
        for mode in ["raster", "rays"] {
            let line = find(&format!("ways to trace, --primary {mode}:"));
            assert!(number_after(line, "query") > 0.0 && number_after(line, "pipeline") > 0.0, "{line}");
            // A ratio, printed to two places: on a loaded machine one frame's figure can dwarf the other's.
            assert!(number_after(line, "pipeline/query").is_finite(), "{line}");
        }
    }
    let creation = text.lines().find(|l| l.starts_with("accumulate pipeline creation")).expect("a creation line");
    assert!(number_after(creation, ": query") > 0.0 && number_after(creation, ", pipeline") > 0.0, "{creation}");
    let scaling = text.lines().find(|l| l.starts_with("scaling")).unwrap_or_else(|| panic!("no scaling line:\n{text}"));
    for label in ["spp^", "pixels^"] {
        let rest = &scaling[scaling.find(label).unwrap() + label.len()..];
        let token: String = rest.chars().take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-').collect();
        assert!(token.parse::<f64>().is_ok_and(f64::is_finite), "{label} in {scaling:?}");
    }
}

#[test]
fn an_environment_and_a_transparent_background_from_the_command_line() {
    let dir = temp_dir("environment");
    let png = dir.join("thumb.png");
    let box_gltf = samples().join("Box.gltf");
    let args = |extra: &[&'static str]| -> Vec<String> {
        let base = ["render", box_gltf.to_str().unwrap(), "-o", png.to_str().unwrap(), "--size", "48x48", "--spp", "4"];
        base.iter().chain(extra).map(|s| s.to_string()).collect()
    };
    let strata = |a: Vec<String>| strata(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let out = strata(args(&["--environment", "studio", "--background", "transparent", "--validate", "--quiet"]));
    assert!(out.status.success(), "{}", outcome(&out));
    let image = image::open(&png).unwrap().to_rgba8();
    assert_eq!(image.get_pixel(0, 0)[3], 0, "nothing covers the corner");
    assert_eq!(image.get_pixel(24, 24)[3], 255, "the box covers the centre");
    assert!(!stderr(&out).contains("default key light"), "the environment lights the scene");
    std::fs::remove_file(&png).unwrap();
    for (extra, says) in [
        (vec!["--environment", "nope.hdr"], "nope.hdr: no such file"),
        (vec!["--background", "environment"], "--background environment needs an environment"),
        (vec!["--environment-rotation", "90"], "need an environment"),
        (vec!["--background", "sky"], "or say environment or transparent"),
    ] {
        let out = strata(args(&extra));
        assert!(!out.status.success(), "{extra:?} must fail");
        assert!(stderr(&out).contains(says), "{extra:?}: {}", stderr(&out));
        assert!(!png.exists(), "{extra:?} wrote a file");
    }
}

/// Runs strata with owned arguments.
#[test]
fn turntables_and_animation_frames_write_their_sequences_and_equal_single_renders() {
    let dir = temp_dir("sequences");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let run = |scene: &str, extra: &[&str], out: &str| {
        let mut args: Vec<String> =
            ["render", scene, "--size", "40x30", "--spp", "2", "--quiet", "-o"].iter().map(|s| s.to_string()).collect();
        args.push(path(out));
        args.extend(extra.iter().map(|s| s.to_string()));
        let out = strata(&args);
        assert!(out.status.success(), "{args:?}: {}", outcome(&out));
    };
    let textured = samples().join("BoxTextured.gltf");
    let textured = textured.to_str().unwrap();
    // A turntable's first view is the orbit render at its azimuth, bit for bit; `#`s set the digits.
    run(textured, &["--turntable", "3", "--orbit", "30,20", "--environment", "studio"], "turn.##.exr");
    run(textured, &["--orbit", "30,20", "--environment", "studio"], "orbit.exr");
    for k in 1..=3 {
        assert!(dir.join(format!("turn.{k:02}.exr")).is_file(), "view {k}");
    }
    assert_eq!(std::fs::read(dir.join("turn.01.exr")).unwrap(), std::fs::read(dir.join("orbit.exr")).unwrap());
    assert_ne!(std::fs::read(dir.join("turn.02.exr")).unwrap(), std::fs::read(dir.join("orbit.exr")).unwrap());
    // Frame k of --frames is the --time render of k / fps, bit for bit, with the same shutter. AnimatedTriangle
    // turns in full view all the time (BoxAnimated's bar rises out of the frame, so its frames can look alike).
    let animated = samples().join("AnimatedTriangle.gltf");
    let animated = animated.to_str().unwrap();
    run(animated, &["--frames", "10..12", "--fps", "25"], "anim.exr");
    run(animated, &["--time", "0.44", "--fps", "25"], "at.exr");
    for k in 10..=12 {
        assert!(dir.join(format!("anim.{k:04}.exr")).is_file(), "frame {k}");
    }
    assert_eq!(std::fs::read(dir.join("anim.0011.exr")).unwrap(), std::fs::read(dir.join("at.exr")).unwrap());
    assert_ne!(std::fs::read(dir.join("anim.0010.exr")).unwrap(), std::fs::read(dir.join("at.exr")).unwrap());
    // Conflicting or absurd requests fail before anything is written.
    for (extra, says) in [
        (vec!["--frames", "5..2"], "the last frame 2 comes before the first 5"),
        (vec!["--time", "1", "--turntable", "4"], "give one of them"),
        (vec!["--frames", "1..2", "--shutter", "0:0.1"], "use --shutter-angle"),
        (vec!["--orbit", "10,95"], "between -90 and 90"),
        (vec!["--shutter-angle", "400", "--time", "0"], "from 0 to 360"),
    ] {
        let mut args: Vec<String> = ["render", animated, "-o"].iter().map(|s| s.to_string()).collect();
        args.push(path("bad.png"));
        args.extend(extra.iter().map(|s| s.to_string()));
        let out = strata(&args);
        assert!(!out.status.success(), "{extra:?} must fail");
        assert!(stderr(&out).contains(says), "{extra:?}: {}", stderr(&out));
    }
    assert!(!std::fs::read_dir(&dir).unwrap().any(|e| e.unwrap().file_name().to_string_lossy().starts_with("bad")));
}

#[test]
fn every_sample_model_without_a_camera_fits_the_image_with_the_default_camera() {
    let dir = temp_dir("framing");
    let mut checked = 0;
    for entry in std::fs::read_dir(samples()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "gltf") || strata::load_scene(&path).unwrap().camera.is_some() {
            continue;
        }
        for (w, h) in [(48u32, 32u32), (32, 48)] {
            let png = dir.join(format!("{}-{w}x{h}.png", path.file_stem().unwrap().to_string_lossy()));
            let out = strata(&[
                "render",
                path.to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
                "--size",
                &format!("{w}x{h}"),
                "--spp",
                "1",
                "--background",
                "transparent",
                "--quiet",
            ]);
            assert!(out.status.success(), "{}: {}", path.display(), outcome(&out));
            let image = image::open(&png).unwrap().to_rgba8();
            let border = (0..w).flat_map(|x| [(x, 0), (x, h - 1)]).chain((0..h).flat_map(|y| [(0, y), (w - 1, y)]));
            let touching: Vec<(u32, u32)> = border.filter(|&(x, y)| image.get_pixel(x, y)[3] > 0).collect();
            assert!(touching.is_empty(), "{} at {w}x{h} touches the image's edge at {touching:?}", path.display());
            let covered = image.pixels().filter(|p| p[3] > 0).count();
            assert!(covered > (w * h / 20) as usize, "{} at {w}x{h} covers only {covered} pixels", path.display());
        }
        checked += 1;
    }
    assert!(checked >= 8, "only {checked} samples have no camera");
}

#[test]
fn auto_exposure_maps_the_log_average_to_middle_grey_whatever_the_light_level() {
    let dir = temp_dir("auto-exposure");
    let box_gltf = samples().join("Box.gltf");
    let render = |intensity: &str, name: &str| {
        let png = dir.join(format!("{name}.png"));
        let exr = dir.join(format!("{name}.exr"));
        let out = strata(&[
            "render",
            box_gltf.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--exr",
            exr.to_str().unwrap(),
            "--size",
            "40x30",
            "--spp",
            "4",
            "--environment",
            "studio",
            "--environment-intensity",
            intensity,
            "--exposure",
            "auto",
            "--json",
            "--quiet",
        ]);
        assert!(out.status.success(), "{}", outcome(&out));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(json["auto_exposure"], true);
        (json["exposure"].as_f64().unwrap() as f32, image::open(&png).unwrap().to_rgba8(), exr)
    };
    let (dim_ev, dim_png, dim_exr) = render("1", "dim");
    let (bright_ev, bright_png, _) = render("1024", "bright");
    // The exposure is log2(0.18 / exp(mean ln(1e-4 + L))) over the linear picture.
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &dim_exr,
        |size, _| vec![[0f32; 4]; size.width() * size.height()],
        |pixels: &mut Vec<[f32; 4]>, position, (r, g, b, a): (f32, f32, f32, f32)| {
            pixels[position.y() * 40 + position.x()] = [r, g, b, a];
        },
    )
    .unwrap();
    let pixels = &image.layer_data.channel_data.pixels;
    let mean_log = pixels
        .iter()
        .map(|p| (1e-4 + 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])).ln())
        .sum::<f64>()
        / pixels.len() as f64;
    let expected = (0.18 / mean_log.exp()).log2() as f32;
    assert!((dim_ev - expected).abs() < 1e-3, "auto exposure {dim_ev}, the log-average asks for {expected}");
    // 1024 times the light: 10 stops less exposure, and the same picture.
    assert!((dim_ev - bright_ev - 10.0).abs() < 0.01, "{dim_ev} and {bright_ev}");
    let differing = dim_png
        .pixels()
        .zip(bright_png.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0.iter()).any(|(x, y)| x.abs_diff(*y) > 1))
        .count();
    assert_eq!(differing, 0, "the exposed pictures differ at {differing} pixels");
}

#[test]
fn several_scenes_render_in_one_run_and_a_broken_one_does_not_stop_the_others() {
    let dir = temp_dir("several");
    let pattern = dir.join("{name}.png");
    let (a, b) = (samples().join("Box.gltf"), samples().join("BoxTextured.gltf"));
    let broken = dir.join("broken.gltf");
    std::fs::write(&broken, "{ not json").unwrap();
    let out = strata(&[
        "render",
        a.to_str().unwrap(),
        broken.to_str().unwrap(),
        b.to_str().unwrap(),
        "-o",
        pattern.to_str().unwrap(),
        "--size",
        "32x24",
        "--spp",
        "2",
        "--validate",
        "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(1), "one scene failed: {}", outcome(&out));
    assert!(dir.join("Box.png").is_file() && dir.join("BoxTextured.png").is_file());
    assert!(!dir.join("broken.png").exists());
    let text = stderr(&out);
    assert!(text.contains(&format!("error: {}", broken.display())), "{text}");
    assert!(text.contains("1 of 3 scenes failed"), "{text}");
    // Without {name} several scenes would write one file: refused before any work.
    let out = strata(&["render", a.to_str().unwrap(), b.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!out.status.success() && stderr(&out).contains("need {name} in -o"), "{}", stderr(&out));
    assert!(!dir.join("x.png").exists());
}
