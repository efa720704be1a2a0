//! Animation interpolation through the importer, on small glTFs written here: STEP and CUBICSPLINE
//! translation, and CUBICSPLINE rotation, sampled at several times against values computed by hand from
//! glTF 2.0 Appendix C.
mod common;
use base64::Engine as _;
use common::cli::{outcome, strata, temp_dir};
use glam::{Quat, Vec3};
use serde_json::json;
use strata::scene::animation::AnimationChoice;

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// One triangle on node 0, animated by one channel with `interpolation`, `path`, key `times` and `outputs`.
fn animated(
    path: &str,
    interpolation: &str,
    times: &[f32],
    outputs: &[f32],
    components: usize,
) -> strata::scene::Scene {
    let mut data = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let input_offset = data.len();
    data.extend(floats(times));
    let output_offset = data.len();
    data.extend(floats(outputs));
    let kind = if components == 4 { "VEC4" } else { "VEC3" };
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": data.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&data))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": input_offset, "byteLength": times.len() * 4},
            {"buffer": 0, "byteOffset": output_offset, "byteLength": outputs.len() * 4}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": times.len(), "type": "SCALAR",
             "min": [times[0]], "max": [times[times.len() - 1]]},
            {"bufferView": 2, "componentType": 5126, "count": outputs.len() / components, "type": kind}
        ],
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": path}}],
                        "samplers": [{"input": 1, "output": 2, "interpolation": interpolation}]}]
    });
    let dir = std::env::temp_dir().join(format!("strata-anim-{}-{path}-{interpolation}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("anim.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    strata::load_scene(&file).unwrap()
}

fn translation_at(scene: &strata::scene::Scene, t: f32) -> Vec3 {
    scene.instance_transforms_at(t)[0].w_axis.truncate()
}

#[test]
fn step_translation_holds_each_key_until_the_next() {
    let s = animated("translation", "STEP", &[0.0, 1.0, 2.0], &[0.0, 0.0, 0.0, 1.0, 2.0, 3.0, -1.0, 0.0, 5.0], 3);
    for (t, want) in [
        (-1.0, Vec3::ZERO),
        (0.0, Vec3::ZERO),
        (0.99, Vec3::ZERO),
        (1.0, Vec3::new(1.0, 2.0, 3.0)),
        (1.5, Vec3::new(1.0, 2.0, 3.0)),
        (2.0, Vec3::new(-1.0, 0.0, 5.0)),
        (9.0, Vec3::new(-1.0, 0.0, 5.0)),
    ] {
        assert_eq!(translation_at(&s, t), want, "t = {t}");
    }
}

#[test]
fn cubic_spline_translation_follows_the_hermite_formula() {
    // Keys at t = 1 and 3 (dt = 2): values 0 and 4 in x; out-tangent of key 0 = 1, in-tangent of key 1 = −2.
    // p(s) = (2s³−3s²+1)·0 + dt(s³−2s²+s)·1 + (−2s³+3s²)·4 + dt(s³−s²)·(−2).
    #[rustfmt::skip]
    let outputs = [
        9.0, 0.0, 0.0,   0.0, 0.0, 0.0,   1.0, 0.0, 0.0,   // key 0: in-tangent (unused), value, out-tangent
        -2.0, 0.0, 0.0,  4.0, 0.0, 0.0,   9.0, 0.0, 0.0,   // key 1: in-tangent, value, out-tangent (unused)
    ];
    let s = animated("translation", "CUBICSPLINE", &[1.0, 3.0], &outputs, 3);
    let by_hand = |t: f32| {
        let (dt, s) = (2.0, (t - 1.0) / 2.0);
        let (s2, s3) = (s * s, s * s * s);
        dt * (s3 - 2.0 * s2 + s) * 1.0 + (-2.0 * s3 + 3.0 * s2) * 4.0 + dt * (s3 - s2) * -2.0
    };
    for t in [1.0, 1.25, 1.5, 2.0, 2.7, 3.0] {
        let got = translation_at(&s, t).x;
        assert!((got - by_hand(t)).abs() < 1e-5, "t = {t}: {got} vs {}", by_hand(t));
    }
    // Before the first key and after the last: the key values (not the tangents).
    assert_eq!(translation_at(&s, 0.0).x, 0.0);
    assert_eq!(translation_at(&s, 5.0).x, 4.0);
}

#[test]
fn cubic_spline_rotation_is_normalised_and_hits_its_keys() {
    let q0 = Quat::IDENTITY;
    let q1 = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let zero = [0.0; 4];
    let outputs: Vec<f32> = [zero, q0.to_array(), zero, zero, q1.to_array(), zero].into_iter().flatten().collect();
    let s = animated("rotation", "CUBICSPLINE", &[0.0, 1.0], &outputs, 4);
    let rotation_at = |t: f32| s.instance_transforms_at(t)[0].to_scale_rotation_translation().1;
    assert!(rotation_at(0.0).abs_diff_eq(q0, 1e-6));
    assert!(rotation_at(1.0).dot(q1).abs() > 1.0 - 1e-6);
    // Zero tangents: the quaternion components follow smoothstep, then normalise (Appendix C).
    let s_mid = 0.3f32;
    let h = 3.0 * s_mid * s_mid - 2.0 * s_mid * s_mid * s_mid;
    let want = Quat::from_vec4(glam::Vec4::from(q0) * (1.0 - h) + glam::Vec4::from(q1) * h).normalize();
    let got = rotation_at(s_mid);
    assert!(got.dot(want).abs() > 1.0 - 1e-6, "{got} vs {want}");
    assert!((got.length() - 1.0).abs() < 1e-6);
}

#[test]
fn linear_rotation_uses_slerp() {
    let q1 = Quat::from_rotation_x(2.0);
    let outputs: Vec<f32> = [Quat::IDENTITY.to_array(), q1.to_array()].into_iter().flatten().collect();
    let s = animated("rotation", "LINEAR", &[0.0, 1.0], &outputs, 4);
    let got = s.instance_transforms_at(0.25)[0].to_scale_rotation_translation().1;
    // slerp at a quarter: exactly a quarter of the angle (nlerp would not be).
    let want = Quat::from_rotation_x(0.5);
    assert!(got.dot(want).abs() > 1.0 - 1e-6, "{got} vs {want}");
}

/// A triangle on node 0 and two clips: "Slide" moves it 1 m along x over 1 s, "Lift" 2 m along y over 2 s.
fn two_clips(dir: &std::path::Path) -> std::path::PathBuf {
    let mut data = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    data.extend(floats(&[0.0, 1.0, 0.0, 2.0])); // key times: slide, lift
    data.extend(floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0])); // slide
    data.extend(floats(&[0.0, 0.0, 0.0, 0.0, 2.0, 0.0])); // lift
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": data.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&data))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 8},
            {"buffer": 0, "byteOffset": 44, "byteLength": 8},
            {"buffer": 0, "byteOffset": 52, "byteLength": 24},
            {"buffer": 0, "byteOffset": 76, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [2]},
            {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"},
            {"bufferView": 4, "componentType": 5126, "count": 2, "type": "VEC3"}
        ],
        "animations": [
            {"name": "Slide", "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
             "samplers": [{"input": 1, "output": 3}]},
            {"name": "Lift", "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
             "samplers": [{"input": 2, "output": 4}]}
        ]
    });
    let file = dir.join("clips.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    file
}

/// One clip plays at a time: the first by default (with a note naming the others), or the one `--animation` or
/// the scene file's `animation` names, by name or index; an unknown clip is an error listing the file's clips.
#[test]
fn one_animation_clip_plays_the_first_unless_another_is_named() {
    let dir = temp_dir("clips");
    let file = two_clips(&dir);
    let load = |animation: Option<AnimationChoice>| {
        strata::load(&file, &strata::LoadOptions { animation, ..Default::default() })
    };
    let first = load(None).unwrap().scene;
    assert_eq!(first.animations.len(), 1);
    assert_eq!(translation_at(&first, 1.0), Vec3::X, "Slide plays by default");
    assert!(first.notes.iter().any(|n| n.contains("\"Slide\"") && n.contains("1 \"Lift\"")), "{:?}", first.notes);
    for choice in [AnimationChoice::Name("Lift".into()), AnimationChoice::Index(1)] {
        let lift = load(Some(choice.clone())).unwrap().scene;
        assert_eq!(translation_at(&lift, 1.0), Vec3::new(0.0, 1.0, 0.0), "{choice:?}");
        assert!(lift.notes.is_empty(), "a named clip needs no note");
    }
    for (choice, says) in [
        (AnimationChoice::Name("Jog".into()), "no animation clip \"Jog\""),
        (AnimationChoice::Index(2), "no animation clip 2"),
    ] {
        let error = format!("{:#}", load(Some(choice)).unwrap_err());
        assert!(
            error.contains(says)
                && error.contains("0 \"Slide\" (1.00 s), 1 \"Lift\" (2.00 s)")
                && error.contains("clips.gltf"),
            "{error}"
        );
    }
    // The scene file names a clip; the command line's wins over it.
    let toml = dir.join("clips.toml");
    std::fs::write(&toml, "gltf = \"clips.gltf\"\nanimation = \"Lift\"\n").unwrap();
    let from_file = strata::load(&toml, &Default::default()).unwrap().scene;
    assert_eq!(translation_at(&from_file, 2.0), Vec3::new(0.0, 2.0, 0.0));
    let options = strata::LoadOptions { animation: Some(AnimationChoice::Index(0)), ..Default::default() };
    assert_eq!(translation_at(&strata::load(&toml, &options).unwrap().scene, 1.0), Vec3::X);
    std::fs::write(&toml, "gltf = \"clips.gltf\"\nanimation = 1.5\n").unwrap();
    let error = format!("{:#}", strata::load(&toml, &Default::default()).unwrap_err());
    assert!(error.contains("clips.toml:2:13") && error.contains("a clip's name or its index"), "{error}");

    // The command line: `strata info FILE` lists the clips; a wrong --animation writes nothing.
    let info = strata(&["info".as_ref(), file.as_os_str()]);
    let listing = String::from_utf8_lossy(&info.stdout);
    assert!(info.status.success(), "{}", outcome(&info));
    assert!(
        listing.contains("[0] \"Slide\": 1.000 s, 1 channels strata plays")
            && listing.contains("[1] \"Lift\": 2.000 s"),
        "{listing}"
    );
    let out = dir.join("jog.png");
    let run = strata(&[
        "render".as_ref(),
        file.as_os_str(),
        "--animation".as_ref(),
        "Jog".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(!run.status.success() && !out.exists(), "{}", outcome(&run));
    assert!(outcome(&run).contains("no animation clip \"Jog\""), "{}", outcome(&run));
}
