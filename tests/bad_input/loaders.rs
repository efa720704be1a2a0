//! Bad scenes, as a table: each case is a file that differs from a valid one by one defect, and the error it
//! must give. Every error names the file; nothing panics. The command-line cases also check the exit status
//! and that no output file appears.
use crate::common::cli::temp_dir;
use base64::Engine as _;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

fn b64(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// A valid one-triangle glTF: three positions then three u16 indices in one embedded buffer.
fn triangle_bytes(positions: [[f32; 3]; 3], indices: [u16; 3]) -> Vec<u8> {
    let mut bytes: Vec<u8> = positions.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    bytes.extend([0, 0]); // pad to 4
    bytes
}

fn triangle_gltf() -> Value {
    let bytes = triangle_bytes([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0, 1, 2]);
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "tri"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": b64(&bytes), "byteLength": bytes.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ]
    })
}

/// A `.glb` of `json` with an empty binary chunk.
fn glb(json: &Value) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn gltf_with(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let mut doc = triangle_gltf();
    edit(&mut doc);
    write(dir, name, &serde_json::to_vec_pretty(&doc).unwrap())
}

/// A scene file naming a valid triangle glTF, with `body` appended.
fn scene_file(dir: &Path, name: &str, body: &str) -> PathBuf {
    gltf_with(dir, "base.gltf", |_| {});
    write(dir, name, format!("gltf = \"base.gltf\"\n{body}").as_bytes())
}

#[test]
fn every_bad_input_gives_its_error() {
    let dir = temp_dir("table");
    let nan_bytes = triangle_bytes([[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0, 1, 2]);
    let bad_index_bytes = triangle_bytes([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0, 1, 7]);
    let valid_glb = glb(&triangle_gltf());
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let cases: Vec<(PathBuf, &str)> = vec![
        (dir.join("missing.gltf"), "no such file"),
        (write(&dir, "malformed.gltf", b"{ \"asset\": { \"version\": \"2.0\" "), "not a valid glTF"),
        (write(&dir, "not-json.gltf", b"\x00\x01binary garbage"), "not a valid glTF"),
        (write(&dir, "truncated.glb", &valid_glb[..valid_glb.len() / 2]), "truncated .glb"),
        (write(&dir, "header-only.glb", &valid_glb[..14]), "truncated .glb"),
        (
            gltf_with(&dir, "short-buffer.gltf", |d| {
                d["accessors"][0]["count"] = json!(30);
                d["accessors"][0]["max"] = json!([1, 1, 0]);
            }),
            "need 360 bytes",
        ),
        (gltf_with(&dir, "view-overrun.gltf", |d| d["bufferViews"][0]["byteLength"] = json!(400)), "overruns buffer 0"),
        (
            gltf_with(&dir, "byte-length.gltf", |d| d["buffers"][0]["byteLength"] = json!(400)),
            "declares byteLength 400",
        ),
        (
            gltf_with(&dir, "bad-index.gltf", |d| {
                d["buffers"][0]["uri"] = json!(b64(&bad_index_bytes));
            }),
            "index 7 is out of range",
        ),
        (gltf_with(&dir, "nan.gltf", |d| d["buffers"][0]["uri"] = json!(b64(&nan_bytes))), "is not finite"),
        (gltf_with(&dir, "points.gltf", |d| d["meshes"][0]["primitives"][0]["mode"] = json!(0)), "only TRIANGLES"),
        (
            gltf_with(&dir, "required-ext.gltf", |d| {
                d["extensionsUsed"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
                d["extensionsRequired"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
            }),
            "requires extension(s) strata does not implement: KHR_materials_pbrSpecularGlossiness",
        ),
        (
            gltf_with(&dir, "parent-dir.gltf", |d| d["buffers"][0]["uri"] = json!("../secret.bin")),
            "leave the glTF's directory",
        ),
        (
            gltf_with(&dir, "absolute.gltf", |d| d["buffers"][0]["uri"] = json!("/etc/hostname")),
            "absolute paths are refused",
        ),
        (
            gltf_with(&dir, "network.gltf", |d| d["buffers"][0]["uri"] = json!("https://example.invalid/t.bin")),
            "not fetched",
        ),
        (gltf_with(&dir, "missing-bin.gltf", |d| d["buffers"][0]["uri"] = json!("sub/none.bin")), "cannot read"),
        (
            gltf_with(&dir, "bad-base64.gltf", |d| d["buffers"][0]["uri"] = json!("data:;base64,@@@@")),
            "not valid base64",
        ),
        (
            gltf_with(&dir, "bad-image.gltf", |d| {
                d["images"] = json!([{"uri": b64(b"\x89PNG\r\n\x1a\nnot really a png")}]);
            }),
            "does not decode",
        ),
        (
            gltf_with(&dir, "cycle.gltf", |d| {
                d["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
            }),
            "cycle",
        ),
        (
            gltf_with(&dir, "two-parents.gltf", |d| {
                d["nodes"] = json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]);
                d["scenes"] = json!([{"nodes": [0, 1]}]);
            }),
            "has two parents",
        ),
        (
            gltf_with(&dir, "bad-camera.gltf", |d| {
                d["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 4.0, "znear": 0.1}}]);
                d["nodes"][0]["camera"] = json!(0);
            }),
            "yfov 4 must be in (0, π)",
        ),
        (write(&dir, "scene.obj", b"v 0 0 0"), "unknown scene extension \".obj\""),
        (scene_file(&dir, "unknown-key.toml", "[render]\nwidht = 100\n"), "unknown field `widht`"),
        (scene_file(&dir, "wrong-type.toml", "[render]\nspp = \"many\"\n"), "invalid type"),
        (scene_file(&dir, "zero-spp.toml", "[render]\nspp = 0\n"), "spp = 0 is out of range"),
        (scene_file(&dir, "absurd-spp.toml", "[render]\nspp = 100000000\n"), "spp = 100000000 is out of range"),
        (scene_file(&dir, "zero-width.toml", "[render]\nwidth = 0\n"), "width = 0 is out of range"),
        (scene_file(&dir, "huge-height.toml", "[render]\nheight = 99999\n"), "height = 99999 is out of range"),
        (scene_file(&dir, "deep-paths.toml", "[render]\nbounces = 99\n"), "bounces = 99 is out of range (0 to 16)"),
        (scene_file(&dir, "bad-toml.toml", "[render\nspp = 4\n"), "bad-toml.toml:2:"),
        (write(&dir, "no-gltf.toml", b"gltf = \"nowhere.gltf\"\n"), "nowhere.gltf does not exist"),
        (
            scene_file(&dir, "bad-sampler.toml", "[render]\nsampler = \"stratified\"\n"),
            "unknown sampler \"stratified\"",
        ),
        (
            scene_file(&dir, "bad-primary.toml", "[render]\nprimary = \"path\"\n"),
            "unknown primary visibility \"path\" (one of: raster, rays)",
        ),
        (scene_file(&dir, "bad-material.toml", "[[bump]]\nmaterial = \"marble\"\n"), "no material is named \"marble\""),
        (
            scene_file(&dir, "bad-node.toml", "[[motion]]\nnode = \"ghost\"\nvelocity = [1, 0, 0]\n"),
            "no node is named \"ghost\"",
        ),
        (scene_file(&dir, "bad-shutter.toml", "[camera]\nshutter = [1.0, 0.5]\n"), "must satisfy 0 ≤ open ≤ close"),
        (
            scene_file(&dir, "dark-light.toml", "[[light]]\ntype = \"quad\"\nposition = [0, 2, 0]\nsize = [1, 1]\n"),
            "give exactly one of radiance, power or intensity",
        ),
        (
            scene_file(&dir, "bad-light.toml", "[[light]]\ntype = \"laser\"\nposition = [0, 2, 0]\npower = 1\n"),
            "unknown light type",
        ),
        (
            scene_file(
                &dir,
                "quad-range.toml",
                "[[light]]\ntype = \"quad\"\nposition = [0, 2, 0]\nsize = [1, 1]\nradiance = 1\nrange = 3\n",
            ),
            "a quad light has no range",
        ),
        (
            scene_file(
                &dir,
                "zero-range.toml",
                "[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = 1\nrange = 0\n",
            ),
            "range = 0 must be a positive number",
        ),
        (
            scene_file(&dir, "nan-position.toml", "[camera]\nposition = [nan, 0, 0]\nlook_at = [0, 0, -1]\n"),
            "must be finite",
        ),
        (scene_file(&dir, "bad-octaves.toml", "[[bump]]\noctaves = 40\n"), "octaves = 40 is out of range"),
        (scene_file(&dir, "gltf-camera.toml", "[camera]\ngltf_camera = \"main\"\n"), "no camera is named \"main\""),
        (scene_file(&dir, "aperture-no-focus.toml", "[camera]\naperture_radius = 0.1\n"), "needs focus_distance"),
    ];
    assert!(cases.len() >= 20);
    let mut failures = Vec::new();
    for (path, expected) in &cases {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        match std::panic::catch_unwind(|| strata::load(path, &Default::default())) {
            Err(_) => failures.push(format!("{name}: panicked")),
            Ok(Ok(_)) => failures.push(format!("{name}: loaded without error")),
            Ok(Err(e)) => {
                let message = format!("{e:#}");
                if !message.contains(expected) || !message.contains(&name) {
                    failures.push(format!("{name}: expected {expected:?} and the file name, got: {message}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{} of {} cases wrong:\n{}", failures.len(), cases.len(), failures.join("\n"));
}

#[test]
fn scene_file_errors_point_at_line_and_column() {
    let dir = temp_dir("position");
    let path = scene_file(&dir, "positioned.toml", "\n[render]\nwidth = 64\nspp = 0\n");
    let message = format!("{:#}", strata::load(&path, &Default::default()).unwrap_err());
    // gltf on line 1, blank line 2, [render] line 3, width line 4, spp line 5; the value starts at column 7.
    assert!(message.contains("positioned.toml:5:7: spp = 0"), "{message}");
}

#[test]
fn a_valid_glb_and_explicit_permission_load() {
    let dir = temp_dir("valid");
    let glb_path = write(&dir, "tri.glb", &glb(&triangle_gltf()));
    assert_eq!(strata::load_scene(&glb_path).unwrap().triangle_count(), 1);
    // A buffer one directory up loads only with --allow-any-uri.
    let bytes = triangle_bytes([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0, 1, 2]);
    std::fs::write(dir.join("outside.bin"), &bytes).unwrap();
    std::fs::create_dir_all(dir.join("inner")).unwrap();
    let path = gltf_with(&dir.join("inner"), "up.gltf", |d| d["buffers"][0]["uri"] = json!("../outside.bin"));
    assert!(strata::load(&path, &Default::default()).is_err());
    let allowed =
        strata::load(&path, &strata::LoadOptions { allow_any_uri: Some(true), ..Default::default() }).unwrap();
    assert_eq!(allowed.scene.triangle_count(), 1);
}

#[test]
fn zero_area_triangles_and_degenerate_uvs_load_without_nan() {
    let dir = temp_dir("degenerate");
    let bytes = triangle_bytes([[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]], [0, 1, 2]);
    let uv: Vec<u8> = [0.5f32; 6].iter().flat_map(|f| f.to_le_bytes()).collect();
    let path = gltf_with(&dir, "flat.gltf", |d| {
        d["buffers"] = json!([{"uri": b64(&bytes), "byteLength": bytes.len()}, {"uri": b64(&uv), "byteLength": 24}]);
        d["bufferViews"].as_array_mut().unwrap().push(json!({"buffer": 1, "byteLength": 24}));
        d["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}));
        d["accessors"][0]["min"] = json!([1, 1, 1]);
        d["accessors"][0]["max"] = json!([1, 1, 1]);
        d["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(2);
    });
    let scene = strata::load_scene(&path).unwrap();
    let p = &scene.meshes[0].primitives[0];
    assert!(p.normals.iter().chain(&p.dpdu).chain(&p.dpdv).all(|v| v.is_finite()));
}

#[test]
fn the_command_line_fails_without_writing_on_bad_scenes() {
    let dir = temp_dir("cli");
    let scene = scene_file(&dir, "bad.toml", "[render]\nspp = 0\n");
    let out_path = dir.join("out.png");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["render", scene.to_str().unwrap(), "-o", out_path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bad.toml:3:7: spp = 0 is out of range"), "{stderr}");
    assert!(!out_path.exists());
    // No output anywhere: neither -o nor render.output.
    let good = scene_file(&dir, "good.toml", "");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["render", good.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no output file"));
}
