//! What dataset tools read beside each frame (issue 33): instance labels, forward motion and the camera. A row of
//! three quads under an orthographic camera looking straight down, so that every expected value follows from
//! the layout: image x is world +x, image y world +z, 32 pixels to the metre.
use crate::common;
use common::cli::{outcome, strata, temp_dir};
use common::GpuTest;
use glam::{Mat4, Quat, Vec2, Vec3};
use strata::check::optics::{lambertian, ortho_down, plane_at};
use strata::render::aov::Aov;
use strata::scene::library::place;
use strata::scene::{NodeMotion, RigidMotion, Scene};

const SIZE: u32 = 64;
const PIXELS_PER_METRE: f32 = 32.0;
const FPS: f32 = 24.0;

/// The pixel (x right, y down) that sees world point (x, 0, z).
fn pixel_of(x: f32, z: f32) -> (u32, u32) {
    (((x + 1.0) * PIXELS_PER_METRE) as u32, ((z + 1.0) * PIXELS_PER_METRE) as u32)
}

/// Three 0.5 m quads, "left", "middle" and "right", centred at x = −0.6, 0 and 0.6; returns the scene and their
/// nodes.
fn row_of_quads() -> (Scene, [usize; 3]) {
    let mut scene = Scene::default();
    let grey = lambertian(&mut scene, 0.5);
    let nodes = [("left", -0.6f32), ("middle", 0.0), ("right", 0.6)].map(|(name, x)| {
        let (p, m) = plane_at(Vec2::splat(0.5), Vec3::new(x, 0.0, 0.0), false, grey);
        place(&mut scene, name, p, m)
    });
    scene.camera = Some(ortho_down(Vec3::ZERO, 2.0, 1.0));
    scene.add_default_light();
    (scene, nodes)
}

/// The instance labels are each quad's node + 1 under its pixels and 0 on the background; the motion AOV is the
/// closed form of each motion over one frame (1/24 s): the middle quad sliding +x at 0.48 m/s moves 0.64 px,
/// the right one spinning about its own centre at 2.4 rad/s turns 0.1 rad, and the camera moving +z at 0.24 m/s
/// shifts everything 0.32 px up the image; the background does not move.
#[test]
fn instance_labels_and_motion_follow_the_layout_and_the_closed_form() {
    let gpu = GpuTest::new();
    let (mut scene, nodes) = row_of_quads();
    scene.node_motion.push(NodeMotion {
        node: nodes[1],
        motion: RigidMotion { velocity: Vec3::new(0.48, 0.0, 0.0), angular_velocity: Vec3::ZERO },
    });
    scene.node_motion.push(NodeMotion {
        node: nodes[2],
        motion: RigidMotion { velocity: Vec3::ZERO, angular_velocity: Vec3::new(0.0, 2.4, 0.0) },
    });
    scene.camera_motion = RigidMotion { velocity: Vec3::new(0.0, 0.0, 0.24), angular_velocity: Vec3::ZERO };
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    let aovs = [Aov::Instance, Aov::Motion, Aov::Position];
    let frames = strata::render_aovs(gpu.device(), &scene, &on_gpu, (SIZE, SIZE), &aovs, 1.0 / FPS).unwrap();
    let [(_, labels), (_, motion), (_, position)] = <[_; 3]>::try_from(frames).ok().unwrap();
    for (q, x) in [-0.6f32, 0.0, 0.6].into_iter().enumerate() {
        let (px, py) = pixel_of(x, 0.0);
        assert_eq!(labels.pixel(px, py)[0], (nodes[q] + 1) as f32, "quad {q} at pixel ({px}, {py})");
    }
    for (px, py) in [(0, 0), (SIZE - 1, SIZE - 1), (SIZE / 2, 2)] {
        assert_eq!(labels.pixel(px, py), [0.0; 4], "background at ({px}, {py})");
        assert_eq!(motion.pixel(px, py), [0.0; 4], "background at ({px}, {py})");
    }
    let camera_shift = Vec2::new(0.0, -0.24 / FPS * PIXELS_PER_METRE);
    let spin = Quat::from_rotation_y(2.4 / FPS);
    let centre = Vec3::new(0.6, 0.0, 0.0);
    let (mut checked, mut worst) = (0, 0.0f32);
    for py in 0..SIZE {
        for px in 0..SIZE {
            let label = labels.pixel(px, py)[0] as usize;
            let Some(q) = nodes.iter().position(|&n| n + 1 == label) else { continue };
            let p = Vec3::from_slice(&position.pixel(px, py)[..3]);
            let moved = match q {
                1 => p + Vec3::new(0.48 / FPS, 0.0, 0.0),
                2 => centre + spin * (p - centre),
                _ => p,
            };
            let expected = Vec2::new(moved.x - p.x, moved.z - p.z) * PIXELS_PER_METRE + camera_shift;
            let got = Vec2::from_slice(&motion.pixel(px, py)[..2]);
            worst = worst.max((got - expected).length());
            checked += 1;
        }
    }
    eprintln!("motion of {checked} pixels against the closed form: worst {worst:.2e} px");
    assert!(checked > 3 * 200, "the quads cover too few pixels: {checked}");
    assert!(worst < 2e-3, "motion off the closed form by {worst} px");
    drop(on_gpu);
    gpu.finish().unwrap();
}

/// `--camera-json` writes each frame's camera: K and the OpenCV pose take every surface point the position AOV
/// holds back onto the centre of the pixel that drew it; a sequence numbers its files as -o does.
#[test]
fn camera_json_reprojects_what_each_pixel_sees_onto_it() {
    let dir = temp_dir("camera-json");
    let gltf = dir.join("box.gltf");
    let box_scene = {
        let mut scene = Scene::default();
        let grey = lambertian(&mut scene, 0.5);
        let cube = strata::scene::shapes::cuboid(Vec3::new(0.4, 0.3, 0.5), Some(grey));
        place(&mut scene, "box", cube, Mat4::from_rotation_y(0.5));
        scene.camera = Some(strata::scene::Camera {
            name: "view".into(),
            world_from_camera: strata::scene::camera::look_at(Vec3::new(1.0, 1.2, 2.5), Vec3::ZERO, Vec3::Y),
            projection: strata::scene::Projection::Perspective { yfov: 0.8, znear: 0.05, zfar: Some(100.0) },
            lens: strata::scene::camera::Lens::PINHOLE,
        });
        scene
    };
    let (json_text, bin) = strata::scene::gltf_export::to_gltf(&box_scene, "box.bin").unwrap();
    std::fs::write(&gltf, json_text).unwrap();
    std::fs::write(dir.join("box.bin"), bin).unwrap();
    let (png, json) = (dir.join("box.png"), dir.join("box.json"));
    let exr = dir.join("box.exr");
    let run = strata(&[
        "render",
        gltf.to_str().unwrap(),
        "--size",
        "48x32",
        "--spp",
        "1",
        "--aov",
        "position",
        "--exr",
        exr.to_str().unwrap(),
        "--camera-json",
        json.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(run.status.success(), "{}", outcome(&run));
    let camera: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!((camera["width"].as_u64(), camera["height"].as_u64()), (Some(48), Some(32)));
    assert!((camera["yfov"].as_f64().unwrap() - 0.8).abs() < 1e-6, "{camera}");
    let rows = |key: &str, n: usize| -> Vec<Vec<f32>> {
        (0..n).map(|r| (0..n).map(|c| camera[key][r][c].as_f64().unwrap() as f32).collect()).collect()
    };
    let (k, pose) = (rows("K", 3), rows("camera_from_world_opencv", 4));
    // One EXR part: the beauty as R, G, B, A and each AOV as `name.R` ... (output.rs).
    let image = exr::prelude::read_all_flat_layers_from_file(&exr).unwrap();
    let channel = |name: &str| -> Vec<f32> {
        let list = &image.layer_data[0].channel_data.list;
        let found = list.iter().find(|c| c.name.to_string() == name).unwrap_or_else(|| panic!("no channel {name}"));
        found.sample_data.values_as_f32().collect()
    };
    let (xs, ys, zs, alpha) =
        (channel("position.R"), channel("position.G"), channel("position.B"), channel("position.A"));
    let (mut checked, mut worst) = (0, 0.0f32);
    for i in 0..xs.len() {
        if alpha[i] == 0.0 {
            continue;
        }
        let p = [xs[i], ys[i], zs[i], 1.0];
        let c: Vec<f32> = (0..3).map(|r| (0..4).map(|j| pose[r][j] * p[j]).sum()).collect();
        let u = (k[0][0] * c[0] + k[0][2] * c[2]) / c[2];
        let v = (k[1][1] * c[1] + k[1][2] * c[2]) / c[2];
        let (px, py) = ((i % 48) as f32 + 0.5, (i / 48) as f32 + 0.5);
        worst = worst.max((u - px).abs().max((v - py).abs()));
        checked += 1;
    }
    eprintln!("{checked} pixels reprojected through K: worst {worst:.2e} px");
    assert!(checked > 100, "the box covers too few pixels: {checked}");
    assert!(worst < 1e-2, "K and the pose put a surface point {worst} px off the pixel that drew it");

    let run = strata(&[
        "render",
        gltf.to_str().unwrap(),
        "--size",
        "16x16",
        "--spp",
        "1",
        "--frames",
        "0..1",
        "--camera-json",
        dir.join("cam.#.json").to_str().unwrap(),
        "-o",
        dir.join("f.#.png").to_str().unwrap(),
        "--quiet",
    ]);
    assert!(run.status.success(), "{}", outcome(&run));
    for (n, t) in [(0, 0.0), (1, 1.0 / 24.0)] {
        let frame: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join(format!("cam.{n}.json"))).unwrap()).unwrap();
        assert!((frame["time"].as_f64().unwrap() - t).abs() < 1e-6, "frame {n}: {frame}");
    }
    let run = strata(&[
        "render",
        gltf.to_str().unwrap(),
        "--camera-json",
        dir.join("cam.txt").to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(!run.status.success() && outcome(&run).contains("must end in .json"), "{}", outcome(&run));
}

/// `--aov semantic`: each node's class comes from its glTF `extras.category_id` or a scene file's `[[semantic]]`
/// table (patterns with `*` and `?`; the later table wins), a node without one takes its nearest ancestor's, and
/// each pixel shows the class of the node it sees; a pattern that matches no node is an error naming the file
/// and line.
#[test]
fn semantic_classes_come_from_node_extras_and_scene_file_patterns() {
    let gpu = GpuTest::new();
    let dir = temp_dir("semantic");
    let (row, _) = row_of_quads();
    let (text, bin) = strata::scene::gltf_export::to_gltf(&row, "row.bin").unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let left = doc["nodes"].as_array().unwrap().iter().position(|n| n["name"] == "left").unwrap();
    doc["nodes"][left]["extras"] = serde_json::json!({"category_id": 5});
    std::fs::write(dir.join("row.gltf"), serde_json::to_vec(&doc).unwrap()).unwrap();
    std::fs::write(dir.join("row.bin"), bin).unwrap();
    let toml = dir.join("row.toml");
    let tables = "[[semantic]]\nnodes = \"*i*\"\ncategory_id = 3\n[[semantic]]\nnodes = \"mid*\"\ncategory_id = 7\n";
    std::fs::write(&toml, format!("gltf = \"row.gltf\"\n{tables}")).unwrap();
    let loaded = strata::load(&toml, &Default::default()).unwrap().scene;
    let class_of = |name: &str| loaded.nodes.iter().find(|n| n.name == name).and_then(|n| n.category);
    // "*i*" matches middle and right; "mid*" then gives middle its own; left keeps its extras.
    assert_eq!([class_of("left"), class_of("middle"), class_of("right")], [Some(5), Some(7), Some(3)]);
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &loaded).unwrap();
    let frames =
        strata::render_aovs(gpu.device(), &loaded, &on_gpu, (SIZE, SIZE), &[Aov::Semantic], 1.0 / FPS).unwrap();
    let semantic = &frames[0].1;
    for (x, class) in [(-0.6f32, 5.0), (0.0, 7.0), (0.6, 3.0)] {
        let (px, py) = pixel_of(x, 0.0);
        assert_eq!(semantic.pixel(px, py)[0], class, "the quad at x = {x}");
    }
    assert_eq!(semantic.pixel(0, 0), [0.0; 4], "the background is unlabelled");
    drop(on_gpu);

    // A child without a class of its own takes its parent's.
    let (mut family, nodes) = row_of_quads();
    family.nodes[nodes[0]].category = Some(11);
    family.nodes[nodes[1]].parent = Some(nodes[0]);
    family.nodes[nodes[0]].children.push(nodes[1]);
    assert_eq!(family.node_categories(), vec![11, 11, 0]);

    std::fs::write(&toml, "gltf = \"row.gltf\"\n[[semantic]]\nnodes = \"wheel*\"\ncategory_id = 2\n").unwrap();
    let error = format!("{:#}", strata::load(&toml, &Default::default()).unwrap_err());
    assert!(error.contains("row.toml:3:9") && error.contains("no node name matches \"wheel*\""), "{error}");
    gpu.finish().unwrap();
}
