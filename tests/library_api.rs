//! The library API a program holds (issue 33): one `Renderer` renders a `Scene` again and again, with changes
//! between renders and no reload, gives the same pixels as `strata render` for the same options, and says which
//! errors are the caller's.
use crate::common;
use common::cli::{outcome, repo_file, strata, temp_dir};
use common::RendererTest;
use glam::{Mat4, Vec2, Vec3, Vec4};
use strata::check::optics::{lambertian, ortho_down, plane_at};
use strata::render::aov::Aov;
use strata::renderer::{InputError, MaterialFactors};
use strata::scene::library::place;
use strata::scene::settings::SettingsOverrides;
use strata::{RenderRequest, Scene};

const SIZE: u32 = 64;
const PIXELS_PER_METRE: f32 = 32.0;

/// Two 0.5 m grey quads, "left" at x = −0.5 and "right" at x = +0.5, under an orthographic camera looking straight
/// down (image x is world +x, 32 pixels to the metre) and the default key light.
fn two_quads() -> Scene {
    let mut scene = strata::scene::Scene::default();
    let grey = lambertian(&mut scene, 0.5);
    for (name, x) in [("left", -0.5f32), ("right", 0.5)] {
        let (p, m) = plane_at(Vec2::splat(0.5), Vec3::new(x, 0.0, 0.0), false, grey);
        place(&mut scene, name, p, m);
    }
    scene.camera = Some(ortho_down(Vec3::ZERO, 2.0, 1.0));
    scene.add_default_light();
    Scene::from_scene(scene)
}

fn request(size: u32, spp: u32) -> RenderRequest {
    RenderRequest {
        settings: SettingsOverrides { width: Some(size), height: Some(size), spp: Some(spp), ..Default::default() },
        ..Default::default()
    }
}

fn no_progress() -> impl FnMut(u32, u32) -> bool {
    |_, _| true
}

/// The columns (image x) where the instance AOV shows `label` along the middle row.
fn columns_of(labels: &strata::output::Frame, label: usize) -> Vec<u32> {
    (0..labels.width).filter(|&x| labels.pixel(x, labels.height / 2)[0] == label as f32).collect()
}

/// Moving a node, changing a material and rendering again: the quad moves by exactly its translation in pixels,
/// its radiance follows the albedo, nothing is uploaded again (the device holds the same bytes between renders),
/// and the scene's own camera and lights are as they were after every render.
#[test]
fn changes_between_renders_show_without_a_reload() {
    let mut renderer = RendererTest::new();
    let mut scene = two_quads();
    let right = scene.node_index("right").unwrap();
    let ask = RenderRequest { aovs: vec![Aov::Instance], ..request(SIZE, 4) };
    let first = renderer.render(&mut scene, &ask, &mut no_progress()).unwrap();
    let held = renderer.device_bytes();
    let before = columns_of(&first.aovs[0].1, right + 1);
    assert_eq!(before.len() as f32, 0.5 * PIXELS_PER_METRE, "the right quad is 16 pixels wide: {before:?}");

    let moved = Mat4::from_translation(Vec3::new(0.25, 0.0, 0.0)) * scene.node_transform(right).unwrap();
    scene.set_node_transform(right, moved).unwrap();
    let material = scene.scene().meshes[0].primitives[0].material.unwrap();
    let half = MaterialFactors { base_color: Some(Vec4::new(0.25, 0.25, 0.25, 1.0)), ..Default::default() };
    scene.set_material(material, &half).unwrap();
    let second = renderer.render(&mut scene, &ask, &mut no_progress()).unwrap();
    assert_eq!(renderer.device_bytes(), held, "the second render kept the first one's uploads");
    let after = columns_of(&second.aovs[0].1, right + 1);
    let shift = 0.25 * PIXELS_PER_METRE;
    assert_eq!(after, before.iter().map(|x| x + shift as u32).collect::<Vec<_>>(), "moved 8 pixels right");
    // A directional light and a Lambertian quad: radiance is proportional to the albedo, halved to within the
    // G-buffer's 8-bit sRGB albedo (one step near 0.25 is 0.4% of it, near 0.5 0.8%).
    let inside = (before[8], SIZE / 2);
    let (r1, r2) = (first.color.pixel(inside.0, inside.1)[0], second.color.pixel(inside.0 + shift as u32, inside.1)[0]);
    assert!(r1 > 0.05 && (r2 / r1 - 0.5).abs() < 0.01, "radiance {r1} → {r2} for albedo 0.5 → 0.25");
    assert_eq!(scene.scene().lights.len(), 1, "the scene's one light, no default added");
    assert!(scene.scene().camera.is_some());
}

/// The same render twice in one renderer gives the same bits, and the command line gives those bits too: the
/// PNG's bytes and the EXR's radiance, for a scene file with a placed camera, auto exposure and an AOV.
#[test]
fn the_library_repeats_itself_and_matches_the_command_line() {
    let path = repo_file("scenes/cornell.toml");
    let mut renderer = RendererTest::new();
    let mut scene = Scene::load(&path, &Default::default()).unwrap();
    let camera = scene.scene().camera.clone();
    let orbit = strata::scene::camera::Orbit { theta_degrees: 20.0, phi_degrees: 10.0, distance: None };
    let ask = RenderRequest {
        auto_exposure: true,
        view: strata::scene::framing::View { orbit: Some(orbit), ..Default::default() },
        aovs: vec![Aov::Depth],
        ..request(40, 4)
    };
    let a = renderer.render(&mut scene, &ask, &mut no_progress()).unwrap();
    let b = renderer.render(&mut scene, &ask, &mut no_progress()).unwrap();
    assert_eq!(a.color.pixels, b.color.pixels);
    assert_eq!(a.display, b.display);
    assert_eq!(a.aovs[0].1.pixels, b.aovs[0].1.pixels);
    assert_eq!(scene.scene().camera, camera, "the orbit held for the render only");

    let dir = temp_dir("library-vs-cli");
    let (png, exr) = (dir.join("box.png"), dir.join("box.exr"));
    let args = ["render", path.to_str().unwrap(), "--size", "40x40", "--spp", "4", "--exposure", "auto"];
    let out = strata(
        &[&args[..], &["--orbit", "20,10", "-o", png.to_str().unwrap(), "--exr", exr.to_str().unwrap()]].concat(),
    );
    assert!(out.status.success(), "{}", outcome(&out));
    let decoded = image::open(&png).unwrap().to_rgba8();
    assert_eq!(decoded.as_raw(), &a.display, "the PNG holds the library's display bytes");
    let layers = exr::prelude::read_all_flat_layers_from_file(&exr).unwrap();
    let channel = |name: &str| -> Vec<f32> {
        let c = layers.layer_data[0].channel_data.list.iter().find(|c| c.name.to_string() == name).unwrap();
        match &c.sample_data {
            exr::prelude::FlatSamples::F32(v) => v.clone(),
            other => panic!("{name} is not f32: {other:?}"),
        }
    };
    for (k, name) in ["R", "G", "B"].into_iter().enumerate() {
        let library: Vec<f32> = a.color.pixels.iter().map(|p| p[k]).collect();
        assert_eq!(channel(name), library, "EXR channel {name}");
    }
}

/// What is the caller's to fix comes back as an `InputError` with the name and the choices; nothing renders.
#[test]
fn bad_input_is_an_input_error_that_says_what_to_fix() {
    let missing = Scene::load(std::path::Path::new("no/such/scene.gltf"), &Default::default()).unwrap_err();
    assert!(InputError::is_input(&missing) && format!("{missing:#}").contains("no/such/scene.gltf"), "{missing:#}");
    let mut scene = two_quads();
    let unknown = scene.node_index("middle").unwrap_err();
    assert!(InputError::is_input(&unknown), "{unknown:#}");
    assert!(format!("{unknown:#}").contains("\"left\", \"right\""), "{unknown:#}");
    let bad = scene.set_node_transform(0, Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0))).unwrap_err();
    assert!(InputError::is_input(&bad) && bad.to_string().contains("finite"), "{bad:#}");
    let out_of_range = scene.set_node_transform(7, Mat4::IDENTITY).unwrap_err();
    assert!(out_of_range.to_string().contains("no node 7"), "{out_of_range:#}");
    let too_bright = MaterialFactors { roughness: Some(1.5), ..Default::default() };
    assert!(InputError::is_input(&scene.set_material(0, &too_bright).unwrap_err()));

    let mut renderer = RendererTest::new();
    let zero_spp = renderer.render(&mut scene, &request(SIZE, 0), &mut no_progress()).unwrap_err();
    assert!(InputError::is_input(&zero_spp) && zero_spp.to_string().contains("spp 0"), "{zero_spp:#}");
    let background = RenderRequest {
        settings: SettingsOverrides {
            backdrop: Some(strata::scene::settings::Backdrop::Environment),
            ..request(SIZE, 1).settings
        },
        ..Default::default()
    };
    let no_environment = renderer.render(&mut scene, &background, &mut no_progress()).unwrap_err();
    assert!(InputError::is_input(&no_environment), "{no_environment:#}");
    assert!(no_environment.to_string().contains("needs an environment"), "{no_environment:#}");
    let missing_file = RenderRequest { environment: Some("no/such/sky.hdr".into()), ..request(SIZE, 1) };
    let error = renderer.render(&mut scene, &missing_file, &mut no_progress()).unwrap_err();
    assert!(InputError::is_input(&error) && format!("{error:#}").contains("no/such/sky.hdr"), "{error:#}");
    assert!(scene.scene().environment.is_none(), "a failed request leaves the scene as it was");
}

/// An environment set on the scene is uploaded before the next render and shows on the background; setting a
/// different one (an intensity) changes the background in proportion.
#[test]
fn a_changed_environment_is_uploaded_before_the_next_render() {
    let mut renderer = RendererTest::new();
    let mut scene = two_quads();
    let corner = |r: &strata::Rendered| r.color.pixel(0, 0);
    let plain = renderer.render(&mut scene, &request(16, 1), &mut no_progress()).unwrap();
    let mut studio = strata::scene::environment::Environment::studio(64, 32);
    scene.set_environment(Some(studio.clone()));
    let lit = renderer.render(&mut scene, &request(16, 1), &mut no_progress()).unwrap();
    studio.intensity = 2.0;
    scene.set_environment(Some(studio));
    let brighter = renderer.render(&mut scene, &request(16, 1), &mut no_progress()).unwrap();
    assert_ne!(corner(&plain), corner(&lit), "the background shows the environment");
    for c in 0..3 {
        let (a, b) = (corner(&lit)[c], corner(&brighter)[c]);
        assert!(a > 0.0 && (b / a - 2.0).abs() < 1e-4, "channel {c}: {a} → {b} at twice the intensity");
    }
}
