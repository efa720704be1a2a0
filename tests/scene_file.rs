//! The scene file's meaning: each key of the committed scene files lands where the renderer reads it, and the
//! settings layer defaults < scene file < command line.
use glam::Vec3;
use std::path::Path;
use strata::scene::settings::{Primary, RenderSettings, SamplerKind, SettingsOverrides, ToneMap};
use strata::scene::{LightShape, NoiseKind};

fn load(name: &str) -> strata::LoadedScene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    strata::load(&path, &Default::default()).unwrap_or_else(|e| panic!("{name}: {e:#}"))
}

#[test]
fn every_committed_scene_file_loads() {
    for (name, _) in strata::scene::library::all() {
        let loaded = load(&format!("{name}.toml"));
        assert!(loaded.scene.triangle_count() > 0, "{name}");
        assert!(loaded.scene.warnings.is_empty(), "{name}: {:?}", loaded.scene.warnings);
    }
}

#[test]
fn cornell_bumps_reach_their_materials() {
    let s = load("cornell.toml").scene;
    let bump = |name: &str| s.materials.iter().find(|m| m.name == name).unwrap().bump;
    let white = bump("white wall").unwrap();
    assert_eq!((white.kind, white.amplitude, white.frequency, white.octaves), (NoiseKind::Fbm, 0.004, 6.0, 4));
    assert_eq!(white.epsilon, 1.0 / 64.0, "ε defaults to 1/64");
    // No `derivative` key: the exact gradient (central differences lose the finest octaves).
    assert_eq!(
        white.derivative,
        strata::scene::material::BumpDerivative::Analytic,
        "the derivative defaults to analytic"
    );
    assert_eq!(bump("red wall").unwrap().kind, NoiseKind::Turbulence);
    assert_eq!(bump("green wall").unwrap().derivative, strata::scene::material::BumpDerivative::Analytic);
    assert!(bump("ceiling light").is_none());
    // The emissive ceiling square is the light: emissiveFactor × KHR_materials_emissive_strength survives.
    let lamp = s.materials.iter().find(|m| m.name == "ceiling light").unwrap();
    assert!((lamp.emissive - Vec3::new(17.0, 12.0, 4.0)).length() < 1e-4, "{}", lamp.emissive);
}

#[test]
fn every_bump_kind_the_scene_format_lists_is_read_and_others_are_named_errors() {
    // docs/scene-format.md's `[[bump]]` table lists four kinds; each must load, into the kind the shader draws.
    let dir = crate::common::cli::temp_dir("bump-kinds");
    let gltf = crate::common::cli::repo_file("scenes/cornell.gltf");
    let scene_with = |kind: &str| {
        let path = dir.join(format!("{kind}.toml"));
        let text = format!("gltf = {:?}\n\n[[bump]]\nmaterial = \"white wall\"\nkind = \"{kind}\"\n", gltf);
        std::fs::write(&path, text).unwrap();
        path
    };
    for (name, kind) in [
        ("noise", NoiseKind::Noise),
        ("fbm", NoiseKind::Fbm),
        ("turbulence", NoiseKind::Turbulence),
        ("sine", NoiseKind::Sine),
    ] {
        let path = scene_with(name);
        let s = strata::load(&path, &Default::default()).unwrap_or_else(|e| panic!("{name}: {e:#}")).scene;
        let white = s.materials.iter().find(|m| m.name == "white wall").unwrap().bump.unwrap();
        assert_eq!(white.kind, kind, "{name}");
    }
    let path = scene_with("ripple");
    let err = format!("{:#}", strata::load(&path, &Default::default()).expect_err("an unknown kind must fail"));
    assert!(
        err.contains("ripple.toml") && err.contains("unknown noise kind \"ripple\"") && err.contains("sine"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn dof_lens_and_f_number_follow_the_thin_lens_model() {
    let s = load("dof.toml").scene;
    let lens = s.camera.as_ref().unwrap().lens;
    assert_eq!((lens.aperture_radius, lens.focus_distance), (0.06, 6.0));
    // Circle of confusion 2A·|d − f|/d: zero at the focus plane; 2·0.06·4/2 = 0.24 m for the sphere at 2 m.
    assert_eq!(lens.circle_of_confusion(6.0), 0.0);
    assert!((lens.circle_of_confusion(2.0) - 0.24).abs() < 1e-6);
    // showcase.toml gives f/5.6 with a 40° field of view: focal length 12 mm / tan 20° = 32.97 mm,
    // aperture radius = focal / (2N) = 2.943 mm; focus at the look_at point.
    let show = load("showcase.toml").scene;
    let lens = show.camera.as_ref().unwrap().lens;
    let focal = 0.012 / 20f32.to_radians().tan();
    assert!((lens.aperture_radius - focal / 11.2).abs() < 1e-6, "{}", lens.aperture_radius);
    let eye = Vec3::new(0.0, 1.7, 5.5);
    assert!((lens.focus_distance - (Vec3::new(0.2, 0.6, 0.0) - eye).length()).abs() < 1e-5);
    assert_eq!(show.shutter, (0.0, 0.25));
}

#[test]
fn motion_moves_nodes_over_the_shutter_on_top_of_their_placement() {
    let s = load("motion.toml").scene;
    assert_eq!(s.shutter, (0.0, 0.5));
    let index = |name: &str| s.instances.iter().position(|i| i.name == name).unwrap();
    let (slide, fall, still) = (index("sliding box"), index("falling sphere"), index("still box"));
    let at_open = s.instance_transforms_at(0.0);
    let at_close = s.instance_transforms_at(0.5);
    let moved = |i: usize| at_close[i].w_axis.truncate() - at_open[i].w_axis.truncate();
    assert!((moved(slide) - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6, "2 m/s for 0.5 s");
    assert!((moved(fall) - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
    assert_eq!(moved(still), Vec3::ZERO);
    assert_eq!(at_open[slide], s.instances[slide].world_from_object, "t = 0 is the placement");
    // The slab spins π rad/s about Z: a quarter turn by the shutter closing at 0.5 s, so +X turns to +Y.
    let slab = index("spinning slab");
    let x_axis = at_close[slab].x_axis.truncate().normalize();
    assert!((x_axis - Vec3::Y).length() < 1e-4, "{x_axis}");
}

#[test]
fn soft_shadow_lights_convert_power_to_radiance() {
    let s = load("soft-shadows.toml").scene;
    assert_eq!(s.lights.len(), 4);
    let quad = &s.lights[0];
    assert_eq!(quad.shape, LightShape::Quad { size: glam::Vec2::new(0.1, 0.1) });
    // Φ = π L A for a one-sided Lambertian emitter: 60 W over 0.01 m² is L = 60 / (0.01 π).
    let expected = 60.0 / (0.01 * std::f32::consts::PI);
    assert!((quad.emission.x / expected - 1.0).abs() < 1e-5, "{} vs {expected}", quad.emission.x);
    // It faces down (−Z of its frame along −Y) and sits where the file says.
    let frame = quad.world_from_light;
    assert!((frame.transform_vector3(Vec3::NEG_Z) - Vec3::NEG_Y).length() < 1e-6);
    assert!((frame.w_axis.truncate() - Vec3::new(-2.5, 3.0, 0.0)).length() < 1e-6);
    let point = &s.lights[3];
    assert_eq!(point.shape, LightShape::Point { radius: 0.0 });
    assert_eq!(point.emission, Vec3::splat(2.0));
    assert_eq!(point.range, 0.0, "no range given: unbounded");
}

#[test]
fn a_point_light_takes_a_range() {
    let dir = crate::common::cli::temp_dir("range");
    let path = dir.join("ranged.toml");
    let gltf = crate::common::cli::repo_file("scenes/cornell.gltf");
    let light = "[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = 3\nrange = 4.5\n";
    std::fs::write(&path, format!("gltf = {:?}\n{light}", gltf.display().to_string())).unwrap();
    let scene = strata::load(&path, &Default::default()).unwrap_or_else(|e| panic!("{e:#}")).scene;
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(scene.lights[0].range, 4.5);
}

#[test]
fn settings_layer_defaults_then_file_then_command_line() {
    let loaded = load("showcase.toml");
    let file = RenderSettings::default().with(&loaded.settings);
    assert_eq!((file.width, file.height, file.spp), (960, 540, 64));
    assert_eq!((file.sampler, file.tone_map), (SamplerKind::MultiJittered, ToneMap::Filmic));
    let cli = SettingsOverrides { spp: Some(4), width: Some(100), ..Default::default() };
    let both = file.clone().with(&cli);
    assert_eq!((both.width, both.height, both.spp), (100, 540, 4));
    assert_eq!(RenderSettings::default().with(&SettingsOverrides::default()), RenderSettings::default());
    assert_eq!(file.primary, Primary::Raster, "the G-buffer pass is the default");
    assert_eq!(
        file.with(&SettingsOverrides { primary: Some(Primary::Rays), ..Default::default() }).primary,
        Primary::Rays
    );
}

#[test]
fn the_render_table_chooses_traced_primary_rays_and_interreflection() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = crate::common::cli::temp_dir("primary");
    let path = dir.join("traced.toml");
    let gltf = root.join("scenes/cornell.gltf");
    let render = "[render]\nprimary = \"rays\"\nindirect = true\nbounces = 6\nshading_samples = 4\n";
    std::fs::write(&path, format!("gltf = {:?}\n{render}", gltf.to_str().unwrap())).unwrap();
    let loaded = strata::load(&path, &Default::default()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(loaded.settings.primary, Some(Primary::Rays));
    assert_eq!((loaded.settings.indirect, loaded.settings.bounces), (Some(true), Some(6)));
    assert_eq!(loaded.settings.shading_samples, Some(4));
    assert_eq!(RenderSettings::default().shading_samples, 1, "one path per camera sample unless asked");
    assert!(RenderSettings::default().with(&loaded.settings).indirect);
    assert!(!RenderSettings::default().indirect, "Cook's effects alone unless asked");
}

#[test]
fn every_example_in_the_format_document_loads() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/scene-format.md")).unwrap();
    let blocks: Vec<&str> = doc.split("```toml\n").skip(1).map(|b| b.split("```").next().unwrap()).collect();
    assert!(blocks.len() >= 8, "found {} toml examples", blocks.len());
    let dir = crate::common::cli::temp_dir("doc-examples");
    for (i, block) in blocks.iter().enumerate() {
        // Examples name materials of the cornell scene or nodes of the showcase; point them at the right glTF.
        let scene = if block.contains("white wall") { "cornell" } else { "showcase" };
        let gltf = root.join(format!("scenes/{scene}.gltf"));
        let body: String = block.lines().filter(|l| !l.starts_with("gltf =")).collect::<Vec<_>>().join("\n");
        let text = format!("gltf = {:?}\n{body}\n", gltf.to_str().unwrap());
        let path = dir.join(format!("example-{i}.toml"));
        std::fs::write(&path, text).unwrap();
        strata::load(&path, &Default::default())
            .unwrap_or_else(|e| panic!("example {i} does not load: {e:#}\n{block}"));
    }
}

#[test]
fn the_environment_table_and_background_words_land_where_the_renderer_reads_them() {
    use strata::scene::settings::Backdrop;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = crate::common::cli::temp_dir("environment-table");
    let gltf = root.join("scenes/showcase.gltf");
    let write = |name: &str, body: &str| {
        let path = dir.join(name);
        std::fs::write(&path, format!("gltf = {:?}\n{body}", gltf.to_str().unwrap())).unwrap();
        path
    };
    let path = write(
        "env.toml",
        "[environment]\nbuiltin = \"studio\"\nrotation_degrees = -45.0\nintensity = 2.0\n[render]\nbackground = \"transparent\"\n",
    );
    let loaded = strata::load(&path, &Default::default()).unwrap();
    let e = loaded.scene.environment.as_ref().expect("an environment");
    assert_eq!((e.rotation_degrees, e.intensity), (-45.0, 2.0));
    assert_eq!(loaded.settings.backdrop, Some(Backdrop::Transparent));
    let path = write("colour.toml", "[render]\nbackground = [0.1, 0.2, 0.3]\n");
    let loaded = strata::load(&path, &Default::default()).unwrap();
    assert_eq!(loaded.settings.background, Some(glam::Vec3::new(0.1, 0.2, 0.3)));
    assert!(loaded.scene.environment.is_none());
    for (body, says) in [
        ("[environment]\nbuiltin = \"forest\"\n", ":3:11: unknown builtin environment \"forest\""),
        ("[environment]\nfile = \"missing.hdr\"\n", ":3:8: "),
        ("[environment]\nintensity = 2.0\n", "[environment] needs one of file"),
        ("[environment]\nbuiltin = \"studio\"\nintensity = -1.0\n", ":4:13: intensity = -1 is out of range"),
        ("[render]\nbackground = \"sky\"\n", ":3:14: background must be [r, g, b]"),
        ("[render]\nshading_samples = 0\n", ":3:19: shading_samples = 0 is out of range"),
        ("[render]\nbackground = [1.0, -1.0, 0.0]\n", ":3:14: background must be"),
    ] {
        let path = write("bad.toml", body);
        let err = format!("{:#}", strata::load(&path, &Default::default()).unwrap_err());
        assert!(err.contains(says) && err.contains("bad.toml"), "{body:?}: {err}");
    }
}
