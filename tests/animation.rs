//! Animation interpolation through the importer, on small glTFs written here: STEP and CUBICSPLINE
//! translation, and CUBICSPLINE rotation, sampled at several times against values computed by hand from
//! glTF 2.0 Appendix C. Skins (§3.7.3) on the glTF tutorial's SimpleSkin: vertices and rendered pixels at keyframe
//! times against the tutorial's skinning worked by hand, identity joints against the unskinned mesh, and motion
//! blur confined to what the turning joint moves.
use crate::common;
use base64::Engine as _;
use common::cli::{outcome, strata, temp_dir};
use common::scenes::{render, settings};
use common::GpuTest;
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
        listing.contains("[0] \"Slide\": 1.000 s, 1 channel\n") && listing.contains("[1] \"Lift\": 2.000 s"),
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

// ---- Skins (glTF 2.0 §3.7.3) on the glTF tutorial's SimpleSkin: a strip of 4 quads over y = 0..2 whose rows weigh
// joint 1 by 0, ¼, ½, ¾, 1; joint 1 turns about z from 0° (t = 0) to 90° (t = 1) and back.

fn simple_skin() -> strata::scene::Scene {
    let mut scene = strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/SimpleSkin.gltf")).unwrap();
    scene.add_default_light();
    scene
}

/// The tutorial's skinning by hand at joint angle `theta`: J0 = T(−½, 0, 0) and J1 = T(0, 1, 0)·Rz(θ)·T(−½, −1, 0)
/// (the joints' world transforms times the file's inverse bind matrices), blended by the row's weight on J1.
fn hand_skinned(vertex: Vec3, theta: f32) -> Vec3 {
    let w1 = vertex.y / 2.0;
    let j0 = vertex + Vec3::new(-0.5, 0.0, 0.0);
    let j1 = Quat::from_rotation_z(theta) * (vertex - Vec3::new(0.5, 1.0, 0.0)) + Vec3::Y;
    j0 * (1.0 - w1) + j1 * w1
}

#[test]
fn simple_skin_vertices_at_its_keyframes_are_where_the_tutorial_puts_them() {
    let scene = simple_skin();
    let rest = &scene.meshes[0].primitives[0];
    assert_eq!(scene.deformed_instances(), vec![0], "the one instance is skinned");
    // At t = 1 (90°), worked through by hand, in the file's vertex order (before flat normals split them).
    let at_90 = [
        (-0.5, 0.0),
        (0.5, 0.0),
        (-0.25, 0.5),
        (0.5, 0.75),
        (-0.25, 0.75),
        (0.25, 1.25),
        (-0.5, 0.75),
        (-0.25, 1.5),
        (-1.0, 0.5),
        (-1.0, 1.5),
    ];
    let file_vertex = |i: usize| Vec3::new((i % 2) as f32, (i / 2) as f32 * 0.5, 0.0);
    for (t, theta) in [(0.0, 0.0), (0.5, std::f32::consts::FRAC_PI_4), (1.0, std::f32::consts::FRAC_PI_2)] {
        let node_world = scene.node_world_transforms(Some(t));
        let skinned = scene.deform_instance(0, &node_world, Some(t)).unwrap();
        for (p, &q) in rest.positions.iter().zip(&skinned[0].positions) {
            // The file's keys are rounded to 3 digits (0.383, 0.924, 0.707).
            let want = hand_skinned(*p, theta);
            assert!((q - want).length() < 2e-3, "t = {t}: vertex {p} skinned to {q}, by hand {want}");
        }
        if t == 1.0 {
            for (i, &(x, y)) in at_90.iter().enumerate() {
                let want = Vec3::new(x, y, 0.0);
                assert!((hand_skinned(file_vertex(i), theta) - want).length() < 1e-6, "vertex {i} by hand");
            }
        }
    }
    // Skinned instances are placed by their joints alone.
    assert_eq!(scene.instance_transforms_at(1.0)[0], glam::Mat4::IDENTITY);
}

/// An orthographic camera looking down −z at (`cx`, `cy`), seeing ±`half` metres.
fn facing_the_strip(cx: f32, cy: f32, half: f32) -> strata::scene::Camera {
    strata::scene::Camera {
        name: "facing the strip".into(),
        world_from_camera: strata::scene::camera::look_at(Vec3::new(cx, cy, 5.0), Vec3::new(cx, cy, 0.0), Vec3::Y),
        projection: strata::scene::Projection::Orthographic { xmag: half, ymag: half, znear: 0.1, zfar: 10.0 },
        lens: strata::scene::camera::Lens::PINHOLE,
    }
}

/// Whether `p` is inside triangle `abc` (either winding), and its distance to the triangle's nearest edge.
fn inside_and_edge_distance(p: glam::Vec2, [a, b, c]: [glam::Vec2; 3]) -> (bool, f32) {
    let edge = |u: glam::Vec2, v: glam::Vec2| {
        let d = v - u;
        let t = ((p - u).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        ((p - u).perp_dot(d), (p - (u + d * t)).length())
    };
    let sides = [edge(a, b), edge(b, c), edge(c, a)];
    let inside = sides.iter().all(|s| s.0 >= 0.0) || sides.iter().all(|s| s.0 <= 0.0);
    (inside, sides.iter().map(|s| s.1).fold(f32::INFINITY, f32::min))
}

#[test]
fn simple_skin_covers_the_pixels_of_its_hand_skinned_shape() {
    use strata::scene::settings::{Primary, RenderSettings, SamplerKind};
    let gpu = GpuTest::new();
    let (size, half, center) = (64u32, 1.0f32, glam::Vec2::new(-0.25, 0.75));
    let indices: Vec<u32> = vec![0, 1, 3, 0, 3, 2, 2, 3, 5, 2, 5, 4, 4, 5, 7, 4, 7, 6, 6, 7, 9, 6, 9, 8];
    let file_vertex = |i: u32| Vec3::new((i % 2) as f32, (i / 2) as f32 * 0.5, 0.0);
    for (t, theta) in [(0.5, std::f32::consts::FRAC_PI_4), (1.0, std::f32::consts::FRAC_PI_2)] {
        let mut scene = simple_skin();
        scene.camera = Some(facing_the_strip(center.x, center.y, half));
        scene.shutter = (t, t);
        // Both ways to the visible surface: the raster pass draws the deformed streams, primary rays hit the
        // BLAS rebuilt from them.
        for primary in [Primary::Raster, Primary::Rays] {
            let s = RenderSettings { primary, ..settings(size, size, 4, SamplerKind::Jittered) };
            let frame = render(gpu.device(), &scene, &s);
            let triangles: Vec<[glam::Vec2; 3]> = indices
                .chunks(3)
                .map(|c| [0, 1, 2].map(|k| hand_skinned(file_vertex(c[k]), theta).truncate()))
                .collect();
            let pixel = 2.0 * half / size as f32;
            let (mut checked, mut covered) = (0, 0);
            for y in 0..size {
                for x in 0..size {
                    // Image y runs down, world y up.
                    let p = center
                        + glam::Vec2::new(x as f32 + 0.5 - size as f32 / 2.0, size as f32 / 2.0 - y as f32 - 0.5)
                            * pixel;
                    let (inside, edge) = triangles
                        .iter()
                        .map(|&tri| inside_and_edge_distance(p, tri))
                        .fold((false, f32::INFINITY), |(i, e), (ti, te)| (i || ti, e.min(te)));
                    // Samples jitter within the pixel: only pixels a pixel and a half from every edge are decided.
                    if edge < 1.5 * pixel {
                        continue;
                    }
                    let coverage = frame.linear.pixels[(y * size + x) as usize][3];
                    assert_eq!(
                        coverage,
                        if inside { 1.0 } else { 0.0 },
                        "t = {t}, {primary:?}: pixel ({x}, {y}) at {p}"
                    );
                    checked += 1;
                    covered += usize::from(inside);
                }
            }
            assert!(checked > size * size / 2 && covered > 150, "t = {t}: {checked} pixels checked, {covered} covered");
        }
    }
    gpu.finish().unwrap();
}

/// The motion AOV of a skinned mesh is each point's own motion: between the keys at 45° and 90° (half a second
/// apart, one "frame" here) every pixel's flow is where the tutorial's hand skinning at 90° puts the point of the
/// same triangle, at the same barycentric coordinates, that the pixel sees at 45° (the strip lies in z = 0 and the
/// orthographic camera is still, so the flow is that displacement over the pixel size, y flipped).
#[test]
fn a_skinned_mesh_has_its_own_motion_in_the_motion_aov() {
    use strata::render::aov::Aov;
    let gpu = GpuTest::new();
    let (size, half, center) = (64u32, 1.0f32, glam::Vec2::new(-0.25, 0.75));
    let indices: Vec<u32> = vec![0, 1, 3, 0, 3, 2, 2, 3, 5, 2, 5, 4, 4, 5, 7, 4, 7, 6, 6, 7, 9, 6, 9, 8];
    let file_vertex = |i: u32| Vec3::new((i % 2) as f32, (i / 2) as f32 * 0.5, 0.0);
    let mut scene = simple_skin();
    scene.camera = Some(facing_the_strip(center.x, center.y, half));
    scene.shutter = (0.5, 0.5);
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    let aovs = [Aov::Motion, Aov::Instance];
    let frames = strata::render_aovs(gpu.device(), &scene, &on_gpu, (size, size), &aovs, 0.5).unwrap();
    let [(_, motion), (_, labels)] = <[_; 2]>::try_from(frames).ok().unwrap();
    let triangles_at = |theta: f32| -> Vec<[glam::Vec2; 3]> {
        indices.chunks(3).map(|c| [0, 1, 2].map(|k| hand_skinned(file_vertex(c[k]), theta).truncate())).collect()
    };
    // The joint's angle at each end as the file's keys give it (rounded to 3 digits: 44.98° and 89.99°), read off
    // its world transform T(0, 1, 0)·Rz(θ).
    let angle_at = |t: f32| {
        let joint = scene.node_world_transforms(Some(t))[2];
        joint.x_axis.y.atan2(joint.x_axis.x)
    };
    let (now, next) = (triangles_at(angle_at(0.5)), triangles_at(angle_at(1.0)));
    let pixel = 2.0 * half / size as f32;
    let (mut checked, mut moving, mut worst) = (0, 0, 0.0f32);
    for y in 0..size {
        for x in 0..size {
            let p = center
                + glam::Vec2::new(x as f32 + 0.5 - size as f32 / 2.0, size as f32 / 2.0 - y as f32 - 0.5) * pixel;
            let edge = now.iter().map(|&tri| inside_and_edge_distance(p, tri).1).fold(f32::INFINITY, f32::min);
            let Some(k) = now.iter().position(|&tri| inside_and_edge_distance(p, tri).0) else {
                if edge > 0.5 * pixel {
                    assert_eq!(motion.pixel(x, y), [0.0; 4], "background at ({x}, {y})");
                }
                continue;
            };
            // Rasterisation decides pixels whose centre is on an edge by its own rules: those are not checked.
            if edge < 0.5 * pixel {
                continue;
            }
            assert_eq!(labels.pixel(x, y)[0], 1.0, "the skinned node at ({x}, {y})");
            let [a, b, c] = now[k];
            let area = (b - a).perp_dot(c - a);
            let (wb, wc) = ((p - a).perp_dot(c - a) / area, (b - a).perp_dot(p - a) / area);
            let [a1, b1, c1] = next[k];
            let later = a1 + (b1 - a1) * wb + (c1 - a1) * wc;
            let expected = glam::Vec2::new(later.x - p.x, p.y - later.y) / pixel;
            let got = glam::Vec2::from_slice(&motion.pixel(x, y)[..2]);
            worst = worst.max((got - expected).length());
            checked += 1;
            moving += usize::from(expected.length() > 1.0);
        }
    }
    eprintln!("skinned flow at {checked} pixels against the hand skinning: worst {worst:.2e} px");
    // Most of the strip turns by several pixels: a flow from the (still) node transform alone would be zero.
    assert!(checked > 150 && moving > 100, "{checked} pixels checked, {moving} moving more than a pixel");
    // The rigid closed form's bound (data_capture.rs); measured 1.5e-5 px.
    assert!(worst < 2e-3, "skinned flow off the hand skinning by {worst} px");
    drop(on_gpu);
    gpu.finish().unwrap();
}

/// The motion AOV of a morphing mesh on a moving, turning node: each pixel's flow is where the same barycentric
/// point of the triangle it sees is one frame later — the morph at the later weights, placed by the node's
/// transform then, seen by the (moving) camera then — minus where it is now. The triangle and its coordinates
/// come from the position AOV; the vertices from `Scene::deform_instance` at both times.
#[test]
fn a_morphing_mesh_on_a_moving_node_has_its_own_motion_in_the_motion_aov() {
    use strata::math::lens::{camera_sample, project_to_pixel};
    use strata::render::aov::Aov;
    use strata::scene::{NodeMotion, RigidMotion};
    let gpu = GpuTest::new();
    let size = 64u32;
    let mut scene =
        strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    scene.add_default_light();
    let motion = RigidMotion { velocity: Vec3::new(0.1, 0.0, 0.0), angular_velocity: Vec3::new(0.0, 0.3, 0.0) };
    scene.node_motion.push(NodeMotion { node: 0, motion });
    scene.camera_motion = RigidMotion { velocity: Vec3::new(0.0, 0.05, 0.0), angular_velocity: Vec3::ZERO };
    // From halfway to the first key to the key whose weights differ most from the first's.
    let keys = morph_stress_keys(&scene);
    let change = |w: &[f32]| w.iter().zip(&keys[0].1).map(|(a, b)| (a - b).abs()).sum::<f32>();
    let far = keys.iter().max_by(|a, b| change(&a.1).total_cmp(&change(&b.1))).unwrap();
    let (now, next) = (0.5 * keys[1].0, far.0);
    scene.shutter = (now, now);
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    let aovs = [Aov::Motion, Aov::Position, Aov::Instance];
    let frames = strata::render_aovs(gpu.device(), &scene, &on_gpu, (size, size), &aovs, next - now).unwrap();
    let [(_, flow), (_, position), (_, labels)] = <[_; 3]>::try_from(frames).ok().unwrap();
    let world_triangles = |t: f32| -> Vec<[Vec3; 3]> {
        let nodes = scene.node_world_transforms(Some(t));
        let place = scene.instance_transforms_from(&nodes)[0];
        let deformed = scene.deform_instance(0, &nodes, Some(t)).unwrap();
        let mesh = &scene.meshes[scene.instances[0].mesh];
        mesh.primitives
            .iter()
            .zip(&deformed)
            .flat_map(|(p, v)| {
                p.indices.chunks(3).map(|c| [0, 1, 2].map(|k| place.transform_point3(v.positions[c[k] as usize])))
            })
            .collect()
    };
    let (triangles_now, triangles_next) = (world_triangles(now), world_triangles(next));
    let camera_at = |t: f32| {
        let mut camera = scene.camera_at(t);
        camera.lens.aperture_radius = 0.0;
        camera_sample(&camera, size, size, glam::Vec2::splat(0.5), glam::Vec2::ZERO)
    };
    let (camera_now, camera_next) = (camera_at(now), camera_at(next));
    let rigid = scene.instance_transforms_at(next)[0] * scene.instance_transforms_at(now)[0].inverse();
    let (mut checked, mut morphing, mut worst) = (0, 0, 0.0f32);
    for y in 0..size {
        for x in 0..size {
            let p = position.pixel(x, y);
            if p[3] == 0.0 {
                continue;
            }
            assert_eq!(labels.pixel(x, y)[0], 1.0, "the morphing node at ({x}, {y})");
            let point = Vec3::new(p[0], p[1], p[2]);
            // The triangle the point lies on, well inside it (rasterisation decides shared edges its own way).
            let found = triangles_now.iter().enumerate().find_map(|(k, &[a, b, c])| {
                let n = (b - a).cross(c - a);
                let off_plane = (point - a).dot(n.normalize()).abs();
                let (wb, wc) = (
                    (point - a).cross(c - a).dot(n) / n.length_squared(),
                    (b - a).cross(point - a).dot(n) / n.length_squared(),
                );
                (off_plane < 1e-4 && wb > 1e-3 && wc > 1e-3 && wb + wc < 1.0 - 1e-3).then_some((k, wb, wc))
            });
            let Some((k, wb, wc)) = found else { continue };
            let [a, b, c] = triangles_next[k];
            let later = a + (b - a) * wb + (c - a) * wc;
            let now_pixel = project_to_pixel(&camera_now, point, size, size);
            let expected = project_to_pixel(&camera_next, later, size, size) - now_pixel;
            let got = glam::Vec2::from_slice(&flow.pixel(x, y)[..2]);
            worst = worst.max((got - expected).length());
            checked += 1;
            let rigid_only = project_to_pixel(&camera_next, rigid.transform_point3(point), size, size) - now_pixel;
            morphing += usize::from((expected - rigid_only).length() > 0.5);
        }
    }
    eprintln!("morphing flow at {checked} pixels against the deformed triangles: worst {worst:.2e} px");
    // The morph moves part of the mesh by more than half a pixel beyond what the node's motion does (measured:
    // 32 of 498 pixels), where a flow from the node's transform alone would be off.
    assert!(checked > 400 && morphing >= 20, "{checked} pixels checked, {morphing} moved by the morph");
    assert!(worst < 2e-3, "morphing flow off by {worst} px");
    drop(on_gpu);
    gpu.finish().unwrap();
}

#[test]
fn identity_joint_matrices_render_exactly_as_the_unskinned_mesh() {
    use strata::scene::settings::SamplerKind;
    let gpu = GpuTest::new();
    let mut skinned = simple_skin();
    skinned.animations.clear();
    // Inverse bind matrices that undo the joints' rest transforms: every joint matrix is the identity.
    let rest = skinned.node_world_transforms(None);
    let joints = skinned.skins[0].joints.clone();
    skinned.skins[0].inverse_bind = joints.iter().map(|&j| rest[j].inverse()).collect();
    assert!(skinned.skins[0].joint_matrices(&rest).iter().all(|m| *m == glam::Mat4::IDENTITY));
    let mut unskinned = skinned.clone();
    unskinned.nodes[0].skin = None;
    for scene in [&mut skinned, &mut unskinned] {
        scene.camera = Some(facing_the_strip(0.0, 1.0, 1.2));
    }
    // Bounces, so that rays hit the deformed copy's records as well as the raster pass drawing it.
    let s = strata::scene::settings::RenderSettings { bounces: 2, ..settings(48, 48, 4, SamplerKind::MultiJittered) };
    let (a, b) = (render(gpu.device(), &skinned, &s), render(gpu.device(), &unskinned, &s));
    assert!(a.linear.pixels.iter().any(|p| p[3] == 1.0), "the strip is in view");
    assert!(a.linear == b.linear, "identity joints must render the unskinned mesh bit for bit");
    drop((a, b));
    gpu.finish().unwrap();
}

/// What the GPU writes into each slot of a scene's deformed streams for samples at `times` (one slot each): the
/// skinning pass's output for skinned instances, the host's morph for the others. Per slot, per deformed instance,
/// per primitive.
fn deformed_on_gpu(
    device: &std::sync::Arc<strata::vk::Device>,
    scene: &strata::scene::Scene,
    times: &[f32],
) -> Vec<Vec<Vec<strata::scene::skin::DeformedVertices>>> {
    use strata::render::deformed::DeformedStreams;
    let geometry = strata::render::gpu_scene::GpuScene::upload(device, scene).unwrap();
    let slots = times.len() as u32;
    let mut streams = DeformedStreams::new(device, scene, &geometry, slots).unwrap();
    for (slot, &t) in times.iter().enumerate() {
        streams.write_slot(slot as u32, scene, &scene.node_world_transforms(Some(t)), t).unwrap();
    }
    let mut graph = strata::vk::frame_graph::FrameGraph::new(device);
    strata::vk::commands::submit_and_wait(device, "skinning twin", |cmd| {
        (0..slots).for_each(|slot| streams.record_skinning(&mut graph, cmd, slot));
        Ok(())
    })
    .unwrap();
    (0..slots).map(|slot| streams.read_slot(device, slot).unwrap()).collect()
}

/// MorphStressTest (animated morph weights) with a skin of two joints on its own node, whose inverse bind matrices
/// turn, shear, scale and move it, and two influence sets per vertex whose weights vary over the mesh and sum to
/// one: a mesh that morphs and then skins, as glTF orders them (§3.7.2.2 before §3.7.3).
fn morph_stress_skinned() -> strata::scene::Scene {
    use glam::{Mat4, Vec4};
    use strata::scene::skin::{JointInfluences, Skin};
    let mut scene =
        strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    let sheared =
        Mat4::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.4, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    let a = Mat4::from_scale_rotation_translation(Vec3::new(1.5, 0.8, 1.2), Quat::from_rotation_y(0.7), Vec3::X);
    let b = sheared * Mat4::from_rotation_x(-0.9) * Mat4::from_translation(Vec3::new(0.0, -0.3, 0.5));
    scene.skins.push(Skin { name: "two joints".into(), joints: vec![0, 0], inverse_bind: vec![a, b] });
    scene.nodes[0].skin = Some(0);
    let influences = |positions: &[Vec3]| -> Vec<JointInfluences> {
        let share = |p: &Vec3| (p.x * 3.0).rem_euclid(1.0);
        let first = JointInfluences {
            joints: vec![[0, 1, 0, 0]; positions.len()],
            weights: positions.iter().map(|p| Vec4::new(0.5 * share(p), 0.5 * (1.0 - share(p)), 0.0, 0.0)).collect(),
        };
        let second = JointInfluences {
            joints: vec![[1, 0, 0, 0]; positions.len()],
            weights: vec![Vec4::X * 0.5; positions.len()],
        };
        vec![first, second]
    };
    for p in &mut scene.meshes[0].primitives {
        p.skin_influences = influences(&p.positions);
        if let Some(source) = &mut p.morph {
            source.unmorphed.skin_influences = influences(&source.unmorphed.positions);
        }
    }
    scene
}

/// The skinning pass is the GPU twin of `scene::skin`: on SimpleSkin at three times of its clip (three slots of one
/// batch), and on a MorphStressTest that morphs at the clip's weights and then skins through two joints and two
/// influence sets, every position, normal and surface derivative the GPU writes is the host's within 2e-6 of its
/// size (measured: 8e-8 and 2.2e-7, a few ulps, from the GPU's fused multiply-adds and summation order). A morphing mesh without a skin is written by the host: the same bits.
#[test]
fn the_gpu_skins_every_stream_as_the_host_does() {
    let gpu = GpuTest::new();
    let morphing = strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    let keys = morph_stress_keys(&morphing);
    let between = [0.5 * (keys[30].0 + keys[31].0), 0.5 * (keys[95].0 + keys[96].0)];
    let cases = [
        ("SimpleSkin", simple_skin(), vec![0.3, 1.25, 0.5]),
        ("MorphStressTest skinned", morph_stress_skinned(), between.to_vec()),
        ("MorphStressTest", morphing.clone(), between.to_vec()),
    ];
    for (name, scene, times) in &cases {
        let skinned = scene.instance_skin(0).is_some();
        let on_gpu = deformed_on_gpu(gpu.device(), scene, times);
        let (mut worst, mut moved) = (0.0f32, 0.0f32);
        for (slot, &t) in times.iter().enumerate() {
            let host = scene.deform_instance(0, &scene.node_world_transforms(Some(t)), Some(t)).unwrap();
            let rest = &scene.meshes[0].primitives;
            assert_eq!(on_gpu[slot].len(), 1, "{name}: one deformed instance");
            for (p, (got, want)) in on_gpu[slot][0].iter().zip(&host).enumerate() {
                moved = moved.max(
                    got.positions.iter().zip(&rest[p].positions).map(|(a, b)| (*a - *b).length()).fold(0.0, f32::max),
                );
                let streams = [
                    ("positions", &got.positions, &want.positions),
                    ("normals", &got.normals, &want.normals),
                    ("dpdu", &got.dpdu, &want.dpdu),
                    ("dpdv", &got.dpdv, &want.dpdv),
                ];
                for (stream, got, want) in streams {
                    // A stream the primitive lacks (SimpleSkin has no UVs, so no derivatives) is zeros on the GPU.
                    let mut want = want.clone();
                    want.resize(got.len(), Vec3::ZERO);
                    assert_eq!(got.len(), rest[p].positions.len(), "{name}, t = {t}, primitive {p}: {stream} count");
                    if !skinned {
                        assert!(
                            *got == want,
                            "{name}, t = {t}, primitive {p}: the host's {stream} are written as they are"
                        );
                        continue;
                    }
                    for (v, (g, w)) in got.iter().zip(&want).enumerate() {
                        let error = (*g - *w).abs().max_element() / w.abs().max_element().max(1.0);
                        worst = worst.max(error);
                        assert!(
                            error < 1e-5,
                            "{name}, t = {t}, primitive {p}, vertex {v}: {stream} {g} on the GPU, {w} on the host"
                        );
                    }
                }
            }
        }
        eprintln!("{name}: GPU against host, worst relative difference {worst:.2e}; vertices move up to {moved:.3} from the mesh's");
        assert!(moved > 0.1, "{name}: the deformation moves vertices (up to {moved})");
    }
    drop(cases);
    gpu.finish().unwrap();
}

#[test]
fn a_turning_joint_blurs_only_the_part_it_moves() {
    use strata::scene::settings::SamplerKind;
    let gpu = GpuTest::new();
    let mut scene = simple_skin();
    // The bottom two rows (y ≤ ½) on joint 0 alone, the rest on the turning joint 1 alone.
    let positions = scene.meshes[0].primitives[0].positions.clone();
    let influences = &mut scene.meshes[0].primitives[0].skin_influences[0];
    for (weights, p) in influences.weights.iter_mut().zip(&positions) {
        *weights = if p.y <= 0.5 { glam::Vec4::new(1.0, 0.0, 0.0, 0.0) } else { glam::Vec4::new(0.0, 1.0, 0.0, 0.0) };
    }
    let (size, half, center) = (80u32, 1.25f32, glam::Vec2::new(-0.25, 1.0));
    scene.camera = Some(facing_the_strip(center.x, center.y, half));
    let s = settings(size, size, 32, SamplerKind::Jittered);
    let mut still = scene.clone();
    still.shutter = (0.0, 0.0);
    // Joint 1 turns by 45° while the shutter is open.
    scene.shutter = (0.0, 0.5);
    let (blurred, sharp) = (render(gpu.device(), &scene, &s), render(gpu.device(), &still, &s));
    let pixel = 2.0 * half / size as f32;
    let world_y = |y: u32| center.y + (size as f32 / 2.0 - y as f32 - 0.5) * pixel;
    let partial = |f: &strata::render::frame::RenderedFrame, rows: &mut dyn Iterator<Item = u32>| {
        rows.flat_map(|y| (0..size).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                (0.0..1.0).contains(&f.linear.pixels[(y * size + x) as usize][3])
                    && f.linear.pixels[(y * size + x) as usize][3] > 0.0
            })
            .count()
    };
    // Below y = ½ (less a pixel for the jitter) nothing moves: the same bits as the still frame.
    for y in (0..size).filter(|&y| world_y(y) < 0.5 - pixel) {
        for x in 0..size {
            let i = (y * size + x) as usize;
            assert_eq!(blurred.linear.pixels[i], sharp.linear.pixels[i], "pixel ({x}, {y}) below the joint moved");
        }
    }
    // Above it, the strip sweeps ~0.9 m at its tip: many more partly covered pixels than the still frame's edges.
    let above = || (0..size).filter(|&y| world_y(y) > 0.5 + pixel);
    let (moving, edges) = (partial(&blurred, &mut above()), partial(&sharp, &mut above()));
    assert!(moving > 5 * edges, "{moving} partly covered pixels where the joint turns, {edges} in the still frame");
    drop((blurred, sharp));
    gpu.finish().unwrap();
}

#[test]
fn strata_info_lists_skins_and_morph_weight_channels() {
    let skin =
        strata(&["info".as_ref(), common::cli::repo_file("tests/data/gltf-samples/SimpleSkin.gltf").as_os_str()]);
    let text = String::from_utf8_lossy(&skin.stdout);
    assert!(skin.status.success() && text.contains("\"skin 0\" (2 joints; skins node 0)"), "{}", outcome(&skin));
    let morph =
        strata(&["info".as_ref(), common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf").as_os_str()]);
    let text = String::from_utf8_lossy(&morph.stdout);
    assert!(text.contains("\"Individuals\": 9.333 s, 1 channel (1 of them morph weights)"), "{}", outcome(&morph));
    assert!(!text.contains("warning"), "{}", outcome(&morph));
}

#[test]
fn a_skin_naming_a_joint_it_does_not_have_is_an_error_that_says_so() {
    let text = std::fs::read_to_string(common::cli::repo_file("tests/data/gltf-samples/SimpleSkin.gltf")).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    doc["skins"][0]["joints"] = json!([1]);
    let dir = temp_dir("skin-joint-out-of-range");
    let file = dir.join("bad-skin.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let err = format!("{:#}", strata::load_scene(&file).unwrap_err());
    assert!(err.contains("bad-skin.gltf") && err.contains("names joint 1, but the skin has 1"), "{err}");
    let out = strata(&["info".as_ref(), file.as_os_str()]);
    assert!(!out.status.success(), "{}", outcome(&out));
}

// ---- Animated morph weights (glTF 2.0 §3.7.2.2, §3.11) on MorphStressTest: one node, one mesh of two primitives
// with 8 targets each; its first clip (Individuals) drives the weights with 225 LINEAR keys.

/// MorphStressTest with the clip's weights at key `k` written as the mesh's static weights and no animations.
fn morph_stress_at_static_weights(weights: &[f32]) -> strata::scene::Scene {
    let text = std::fs::read_to_string(common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    doc["meshes"][0]["weights"] = json!(weights);
    doc.as_object_mut().unwrap().remove("animations");
    let dir = temp_dir(&format!("morph-static-{}", weights.iter().map(|w| w.to_bits()).sum::<u32>()));
    let file = dir.join("MorphStressTest-static.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    strata::load_scene(&file).unwrap()
}

fn morph_stress_keys(scene: &strata::scene::Scene) -> Vec<(f32, Vec<f32>)> {
    let channel = &scene.animations[0].channels[0];
    assert_eq!(channel.property, strata::scene::Property::Weights);
    channel.times.iter().map(|&t| (t, channel.sample_weights(t))).collect()
}

#[test]
fn animated_morph_weights_at_a_key_give_the_bits_of_those_weights_set_statically() {
    let animated = strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    assert!(animated.warnings.is_empty(), "{:?}", animated.warnings);
    assert_eq!(animated.deformed_instances(), vec![0]);
    let keys = morph_stress_keys(&animated);
    // Keys where several targets are partly on, and one where all are off.
    let chosen: Vec<usize> = [30, 95, 160, 0].into_iter().filter(|&k| k < keys.len()).collect();
    assert!(keys[30].1.iter().chain(&keys[95].1).any(|&w| w > 0.0 && w < 1.0), "{:?}", &keys[30]);
    for k in chosen {
        let (t, weights) = &keys[k];
        let fixed = morph_stress_at_static_weights(weights);
        let deformed = animated.deform_instance(0, &animated.node_world_transforms(Some(*t)), Some(*t)).unwrap();
        for (p, (d, f)) in deformed.iter().zip(&fixed.meshes[0].primitives).enumerate() {
            assert!(d.positions == f.positions, "key {k} (t = {t}), primitive {p}: positions differ");
            assert!(d.normals == f.normals, "key {k}, primitive {p}: normals differ");
            assert!(d.dpdu == f.dpdu && d.dpdv == f.dpdv, "key {k}, primitive {p}: surface derivatives differ");
        }
    }
    // Between keys the weights interpolate, and so do the vertices: not the rest pose.
    let (t0, t1) = (keys[30].0, keys[31].0);
    let between = animated.deform_instance(0, &animated.node_world_transforms(None), Some(0.5 * (t0 + t1))).unwrap();
    let rest = &animated.meshes[0].primitives;
    assert!(between.iter().zip(rest).any(|(d, r)| d.positions != r.positions), "the mesh moves between keys");
}

#[test]
fn a_morphing_mesh_renders_at_a_key_as_its_static_twin_and_blurs_between_keys() {
    use strata::scene::settings::SamplerKind;
    let gpu = GpuTest::new();
    let mut animated =
        strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    let (t, weights) = morph_stress_keys(&animated)[95].clone();
    let mut fixed = morph_stress_at_static_weights(&weights);
    // One camera and key light for both (a default camera would frame each one's rest pose, and those differ).
    animated.camera = Some(animated.camera_or_default());
    fixed.camera = animated.camera.clone();
    animated.add_default_light();
    fixed.add_default_light();
    animated.shutter = (t, t);
    let s = settings(48, 48, 2, SamplerKind::MultiJittered);
    let (a, b) = (render(gpu.device(), &animated, &s), render(gpu.device(), &fixed, &s));
    assert!(a.linear.pixels.iter().filter(|p| p[3] > 0.0).count() > 300, "the mesh is in view");
    assert!(a.linear == b.linear, "animated weights at a key must render as those weights set statically");
    // Over an open shutter the weights change, and the picture with them.
    animated.shutter = (t, t + 1.0);
    let c = render(gpu.device(), &animated, &s);
    assert!(c.linear != a.linear, "an open shutter over changing weights must not be the still frame");
    drop((a, b, c));
    gpu.finish().unwrap();
}

/// A morphing instance is placed by its node like any other: its bounds (what the default camera frames) move with
/// the node's translation.
#[test]
fn a_morphing_instance_is_bounded_where_its_node_puts_it() {
    let text = std::fs::read_to_string(common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let plain = strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/MorphStressTest.gltf")).unwrap();
    doc["nodes"][0]["translation"] = json!([10.0, 0.0, 0.0]);
    let file = temp_dir("morph-moved").join("MorphStressTest-moved.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let moved = strata::load_scene(&file).unwrap();
    assert_eq!(moved.deformed_instances(), vec![0]);
    let ((lo, hi), (plain_lo, plain_hi)) = (moved.bounds().unwrap(), plain.bounds().unwrap());
    assert!((lo - plain_lo - Vec3::X * 10.0).length() < 1e-4 && (hi - plain_hi - Vec3::X * 10.0).length() < 1e-4);
}
