//! Whole renders: reproducibility, the pinhole and still-frame limits, finite output for every scene and sample
//! model, and what the samplers claim (Cook 1984: regular sampling aliases, jittered sampling converges faster
//! than random).
use crate::common;

use common::scenes::*;
use common::GpuTest;
use glam::{Vec2, Vec3};
use std::path::PathBuf;
use strata::scene::settings::RenderSettings;
use strata::scene::settings::{CameraOverrides, Primary, SamplerKind};
use strata::scene::{Scene, UvTransform, Wrap};

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn load(path: &std::path::Path) -> Scene {
    let mut scene = strata::load(path, &Default::default()).expect("scene loads").scene;
    if !scene.has_light() {
        scene.add_default_light();
    }
    scene
}

#[test]
fn the_same_seed_gives_the_same_bits_and_another_seed_does_not() {
    let gpu = GpuTest::new();
    let scene = load(&repo("scenes/showcase.toml"));
    let mut s = settings(96, 54, 6, SamplerKind::MultiJittered);
    let a = render(gpu.device(), &scene, &s);
    let b = render(gpu.device(), &scene, &s);
    assert!(a.linear == b.linear, "two renders with one seed differ in linear radiance");
    assert_eq!(a.display, b.display);
    s.seed += 1;
    let c = render(gpu.device(), &scene, &s);
    assert!(a.linear != c.linear, "another seed must give other samples");
    assert_finite(&a, "showcase");
    drop((a, b, c));
    gpu.finish().unwrap();
}

#[test]
fn aperture_zero_is_the_pinhole_whatever_the_focus() {
    let gpu = GpuTest::new();
    let mut near = load(&repo("scenes/dof.toml"));
    let mut far = near.clone();
    CameraOverrides { aperture_radius: Some(0.0), focus_distance: Some(1.5), shutter: None }.apply(&mut near).unwrap();
    CameraOverrides { aperture_radius: Some(0.0), focus_distance: Some(9.0), shutter: None }.apply(&mut far).unwrap();
    let s = settings(80, 45, 4, SamplerKind::Jittered);
    let (a, b) = (render(gpu.device(), &near, &s), render(gpu.device(), &far, &s));
    assert!(a.linear == b.linear && a.display == b.display, "aperture 0 must not depend on the focus distance");
    drop((a, b));
    gpu.finish().unwrap();
}

#[test]
fn a_closed_shutter_renders_the_still_frame_at_that_time() {
    let gpu = GpuTest::new();
    let mut moving = load(&repo("scenes/motion.toml"));
    assert!(!moving.node_motion.is_empty() || !moving.animations.is_empty(), "the motion scene moves");
    CameraOverrides { shutter: Some((0.1, 0.1)), ..Default::default() }.apply(&mut moving).unwrap();
    // The same instants baked into a scene without motion.
    let mut still = moving.clone();
    let transforms = moving.instance_transforms_at(0.1);
    for (instance, transform) in still.instances.iter_mut().zip(transforms) {
        instance.node = None;
        instance.world_from_object = transform;
    }
    still.node_motion.clear();
    still.animations.clear();
    still.camera = Some(moving.camera_at(0.1));
    still.camera_motion = Default::default();
    let s = settings(80, 45, 4, SamplerKind::Jittered);
    let (a, b) = (render(gpu.device(), &moving, &s), render(gpu.device(), &still, &s));
    assert!(a.linear == b.linear, "shutter open = close must equal the still frame, bit for bit");
    drop((a, b));
    gpu.finish().unwrap();
}

#[test]
fn every_scene_and_sample_model_renders_finite_pixels() {
    let gpu = GpuTest::new();
    let mut paths: Vec<PathBuf> = std::fs::read_dir(repo("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    let samples = repo("tests/data/gltf-samples");
    assert!(samples.is_dir(), "the glTF samples are expected at {}", samples.display());
    paths.extend(
        std::fs::read_dir(&samples)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "gltf" || e == "glb")),
    );
    paths.sort();
    assert!(paths.len() >= 10, "found only {paths:?}");
    for path in &paths {
        let scene = load(path);
        // Both primary modes with the default picture settings, then both with diffuse bounces and a better
        // sampler (the paths and sample points only those options reach).
        let configurations = [
            (Primary::Raster, SamplerKind::Jittered, false),
            (Primary::Rays, SamplerKind::Jittered, false),
            (Primary::Raster, SamplerKind::Sobol, true),
            (Primary::Rays, SamplerKind::MultiJittered, true),
        ];
        for (primary, sampler, indirect) in configurations {
            let s = RenderSettings { primary, indirect, ..settings(48, 32, 2, sampler) };
            let frame = render(gpu.device(), &scene, &s);
            let what = format!("{} ({}, {sampler:?}, indirect {indirect})", path.display(), primary.name());
            assert_finite(&frame, &what);
        }
    }
    gpu.finish().unwrap();
}

/// Emitting stripes with a period a little longer than a quarter pixel: 4x4 regular samples beat against them.
fn stripes() -> Scene {
    let mut scene = Scene::default();
    let bright = emitter(&mut scene, 1.0);
    // 64 px over 1 m; period (1/64)/4 × 1.03 m, half of it bright.
    let period = 1.0 / 64.0 / 4.0 * 1.03;
    let mut x = -0.5;
    while x < 0.5 {
        let (p, m) = plane_at(Vec2::new(period * 0.5, 0.5), Vec3::new(x + period * 0.25, 0.0, 0.0), false, bright);
        place(&mut scene, "stripe", p, m);
        x += period;
    }
    scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.125));
    scene
}

/// The error against the true 0.5 of each pixel of a stripes render: its rms, and the correlation of
/// horizontally adjacent errors (near 1 for a moiré's smooth beat, near 0 for independent noise).
fn stripe_error(frame: &strata::render::frame::RenderedFrame) -> (f32, f32) {
    let f = &frame.linear;
    let error = |x: u32, y: u32| f.pixels[(y * f.width + x) as usize][0] - 0.5;
    let (mut sum_sq, mut sum_xy, mut n) = (0.0f32, 0.0f32, 0.0f32);
    for y in 0..f.height {
        for x in 0..f.width - 1 {
            sum_sq += error(x, y) * error(x, y);
            sum_xy += error(x, y) * error(x + 1, y);
            n += 1.0;
        }
    }
    ((sum_sq / n).sqrt(), sum_xy / sum_sq.max(1e-12))
}

#[test]
fn regular_sampling_aliases_on_fine_stripes_and_raster_jitter_only_weakens_it() {
    let gpu = GpuTest::new();
    let scene = stripes();
    let error = |kind: SamplerKind| stripe_error(&render(gpu.device(), &scene, &settings(64, 16, 16, kind)));
    let ((regular, _), (jittered, correlation)) = (error(SamplerKind::Regular), error(SamplerKind::Jittered));
    // 4x4 strata centres against a period just over a quarter pixel: whole pixels come out black or white.
    assert!(regular > 0.4, "regular sampling should show a full-strength moiré here: rms deviation {regular}");
    // The raster G-buffer shares each sample's jitter between all pixels of its pass (docs/architecture.md), so jitter
    // cannot turn the beat into independent noise per pixel; it does cut its strength. The reference mode
    // (the next test) is what removes it.
    assert!(jittered < 0.65 * regular, "jittered {jittered} vs regular {regular}");
    assert!(correlation > 0.5, "raster jitter is shared per pass, so its error stays a smooth beat: {correlation}");
    gpu.finish().unwrap();
}

#[test]
fn traced_primary_rays_turn_the_moire_into_noise_with_jitter_but_not_with_regular_sampling() {
    let gpu = GpuTest::new();
    let scene = stripes();
    let error = |kind: SamplerKind| {
        let s = RenderSettings { primary: Primary::Rays, ..settings(64, 16, 16, kind) };
        stripe_error(&render(gpu.device(), &scene, &s))
    };
    let ((regular, regular_corr), (jittered, jittered_corr)) =
        (error(SamplerKind::Regular), error(SamplerKind::Jittered));
    eprintln!("rays: regular rms {regular} corr {regular_corr}; jittered rms {jittered} corr {jittered_corr}");
    // Regular puts the same 16 points in every pixel: the same moiré as the raster pass.
    assert!(regular > 0.4 && regular_corr > 0.5, "regular: rms {regular}, neighbour correlation {regular_corr}");
    // Jitter per pixel: each 1/4-pixel stratum holds about one stripe period, so every sample is bright with
    // probability ½ independently of the other pixels: rms about sqrt(¼ / 16) = 0.125 and no correlation.
    assert!(jittered < 0.18, "jittered per pixel should leave only noise of rms ~0.125: {jittered}");
    assert!(jittered_corr.abs() < 0.2, "jittered per pixel: neighbouring errors must be independent: {jittered_corr}");
    gpu.finish().unwrap();
}

/// Both ways to find the visible surface shade it with the same material, bump and light code (docs/architecture.md: "the
/// two modes must agree, which makes each the other's test"). With the regular sampler every pixel of the
/// reference mode gets the very jitter and lens points the raster pass shares, so the pictures agree pixel by
/// pixel up to the G-buffer's 8-bit albedo and material channels and pixels on silhouettes.
#[test]
fn raster_and_traced_primary_visibility_agree_on_the_showcase() {
    let gpu = GpuTest::new();
    let scene = load(&repo("scenes/showcase.toml"));
    let base = settings(96, 54, 16, SamplerKind::Regular);
    let raster = render(gpu.device(), &scene, &base).linear;
    let traced = render(gpu.device(), &scene, &RenderSettings { primary: Primary::Rays, ..base }).linear;
    let luminance = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let mean = raster.pixels.iter().map(luminance).sum::<f32>() / raster.pixels.len() as f32;
    let mut differences: Vec<f32> = raster
        .pixels
        .iter()
        .zip(&traced.pixels)
        .map(|(a, b)| (luminance(a) - luminance(b)).abs() / (0.5 * (luminance(a) + luminance(b))).max(mean * 0.1))
        .collect();
    let mean_difference = differences.iter().sum::<f32>() / differences.len() as f32;
    differences.sort_by(f32::total_cmp);
    let p90 = differences[differences.len() * 9 / 10];
    let p99 = differences[differences.len() * 99 / 100];
    let coverage_differs = raster.pixels.iter().zip(&traced.pixels).filter(|(a, b)| a[3] != b[3]).count();
    eprintln!(
        "relative difference: mean {mean_difference}, 90% {p90}, 99% {p99}; coverage differs in {coverage_differs}"
    );
    // Measured on lavapipe: mean 0.0009, 90% 0.001, 99% 0.009; leaving out the bump map in the reference mode
    // alone gives mean 0.009, 90% 0.014, 99% 0.18.
    assert!(mean_difference < 0.005, "mean relative difference {mean_difference}");
    assert!(p90 < 0.01 && p99 < 0.1, "90% of pixels within {p90}, 99% within {p99}");
    assert!(coverage_differs <= raster.pixels.len() / 100, "coverage differs in {coverage_differs} pixels");
    gpu.finish().unwrap();
}

/// glTF's metallic-roughness texture scales the factors (glTF 2.0 §3.9.2) wherever a surface is shaded: in the
/// G-buffer, at the reference mode's visible hits, and at the gloss and translucency rays' hits. A texel with
/// roughness 1 and metalness 0 on every showcase material must render exactly as the factors with metalness 0.
#[test]
fn metallic_roughness_textures_shade_like_their_factors_in_both_modes_and_at_ray_hits() {
    use strata::scene::Sampler;
    let gpu = GpuTest::new();
    let original = load(&repo("scenes/showcase.toml"));
    assert!(original.materials.iter().any(|m| m.metallic > 0.0), "the showcase needs a metal for this test");
    let mut textured = original.clone();
    let texture = with_texture(&mut textured, "metal 0, rough 1", &[[0, 255, 0, 255]], Sampler::default(), None);
    let mut factors = original.clone();
    for (t, f) in textured.materials.iter_mut().zip(&mut factors.materials) {
        t.metallic_roughness_texture = Some(texture);
        f.metallic = 0.0;
    }
    assert_renders_alike_in_both_modes(&gpu, &textured, &factors, &original, "metalness 0, roughness 1");
    gpu.finish().unwrap();
}

/// Transmission textures (R scales the factor, KHR_materials_transmission) are read, through their
/// KHR_texture_transform, in the G-buffer, at the reference mode's visible hits and at the rays' hits. A texture
/// whose left texel transmits and whose right texel does not, transformed so that every lookup lands on the right
/// one, must render the showcase exactly as transmission factor 0 does, in both modes.
#[test]
fn transformed_transmission_textures_shade_like_their_factors_in_both_modes_and_at_ray_hits() {
    let showcase = load(&repo("scenes/showcase.toml"));
    assert!(showcase.materials.iter().any(|m| m.transmission > 0.0), "the showcase needs glass for this test");
    let right_half = UvTransform { offset: Vec2::new(0.55, 0.0), rotation: 0.0, scale: Vec2::new(0.4, 1.0) };
    assert_transformed_texture_acts_as_factor(
        "transmits | does not",
        &[[255, 255, 255, 255], [0, 255, 255, 255]],
        right_half,
        |m, texture| m.transmission_texture = Some(texture),
        |m| m.transmission = 0.0,
        "transmission 0",
    );
}

/// Specular textures (A scales the factor, KHR_materials_specular) are read, through their KHR_texture_transform,
/// in the G-buffer, at the reference mode's visible hits and at the rays' hits: a texture whose left texel is
/// opaque and whose right texel clear, transformed onto the right one, renders the showcase as specular 0 does.
/// (Without the transform the showcase's UVs reach both texels.)
#[test]
fn transformed_specular_textures_shade_like_their_factors_in_both_modes_and_at_ray_hits() {
    assert_transformed_texture_acts_as_factor(
        "reflects | does not",
        &[[255, 255, 255, 255], [255, 255, 255, 0]],
        ONTO_THE_RIGHT_TEXEL,
        |m, texture| m.specular_texture = Some(texture),
        |m| m.specular = 0.0,
        "specular 0",
    );
}

/// Specular colour textures (RGB scales the colour factor, KHR_materials_specular) are read, through their
/// KHR_texture_transform, in the G-buffer (whose 8-bit attachment holds the texel, the factor applied where it is
/// read), at the reference mode's visible hits and at the rays' hits: a texture whose right texel is magenta,
/// transformed onto it, renders the showcase as the colour factor without its green does. Its left texel, green,
/// would show if the transform were lost.
#[test]
fn transformed_specular_colour_textures_shade_like_their_factors_in_both_modes_and_at_ray_hits() {
    assert_transformed_texture_acts_as_factor(
        "green | magenta",
        &[[0, 255, 0, 255], [255, 0, 255, 255]],
        ONTO_THE_RIGHT_TEXEL,
        |m, texture| m.specular_color_texture = Some(texture),
        |m| m.specular_color *= Vec3::new(1.0, 0.0, 1.0),
        "a specular colour without green",
    );
}

/// Sends every lookup of a two-texel texture to its right texel: scale 0 in u, whatever the UVs (the showcase
/// floor's run past 1).
const ONTO_THE_RIGHT_TEXEL: UvTransform =
    UvTransform { offset: Vec2::new(0.75, 0.0), rotation: 0.0, scale: Vec2::new(0.0, 1.0) };

/// Gives every showcase material the two-texel texture `texels`, read through `transform` (`use_texture`), and
/// checks that it renders in both modes exactly as the showcase with `as_factor` applied to every material.
fn assert_transformed_texture_acts_as_factor(
    name: &str,
    texels: &[[u8; 4]],
    transform: UvTransform,
    use_texture: impl Fn(&mut strata::scene::Material, strata::scene::TextureRef),
    as_factor: impl Fn(&mut strata::scene::Material),
    what: &str,
) {
    let gpu = GpuTest::new();
    let original = load(&repo("scenes/showcase.toml"));
    let mut textured = original.clone();
    let texture = with_texture(&mut textured, name, texels, nearest_sampler(Wrap::Repeat), Some(transform));
    let mut factors = original.clone();
    for (t, f) in textured.materials.iter_mut().zip(&mut factors.materials) {
        use_texture(t, texture);
        as_factor(f);
    }
    assert_renders_alike_in_both_modes(&gpu, &textured, &factors, &original, what);
    gpu.finish().unwrap();
}

/// Textures read the UV set they name: a base-colour texture, black on its left texel and white on its right,
/// read through a TEXCOORD_1 that sends every lookup to the white texel renders the showcase exactly as no
/// texture does, in both modes and at the rays' hits; read through TEXCOORD_0 (whose coordinates reach both
/// texels) it does not.
#[test]
fn textures_on_the_second_uv_set_read_it_in_both_modes_and_at_ray_hits() {
    use strata::scene::TextureRef;
    let gpu = GpuTest::new();
    let original = load(&repo("scenes/showcase.toml"));
    let mut on_uv1 = original.clone();
    for p in on_uv1.meshes.iter_mut().flat_map(|m| &mut m.primitives) {
        p.uvs1 = vec![Vec2::new(0.75, 0.5); p.positions.len()];
    }
    let black_white = [[0, 0, 0, 255], [255; 4]];
    let texture = with_texture(&mut on_uv1, "black | white", &black_white, nearest_sampler(Wrap::Repeat), None);
    let mut on_uv0 = on_uv1.clone();
    for (uv1, uv0) in on_uv1.materials.iter_mut().zip(&mut on_uv0.materials) {
        uv1.base_color_texture = Some(TextureRef { tex_coord: 1, ..texture });
        uv0.base_color_texture = Some(texture);
    }
    for primary in [Primary::Raster, Primary::Rays] {
        let s = RenderSettings { primary, ..settings(64, 36, 2, SamplerKind::Jittered) };
        let untextured = render(gpu.device(), &original, &s).linear;
        assert!(render(gpu.device(), &on_uv1, &s).linear == untextured, "{primary:?}: TEXCOORD_1 was not read");
        assert!(render(gpu.device(), &on_uv0, &s).linear != untextured, "{primary:?}: TEXCOORD_0 reads the same");
    }
    gpu.finish().unwrap();
}

/// Adds a linear (non-colour) texture of one row of `texels` to the scene; returns a use of it.
fn with_texture(
    scene: &mut Scene,
    name: &str,
    texels: &[[u8; 4]],
    sampler: strata::scene::Sampler,
    transform: Option<strata::scene::UvTransform>,
) -> strata::scene::TextureRef {
    use strata::scene::{Texture, TextureImage, TextureRef};
    let rgba8 = texels.concat();
    scene.images.push(TextureImage { name: name.into(), width: texels.len() as u32, height: 1, rgba8 });
    scene.textures.push(Texture { name: name.into(), image: scene.images.len() - 1, sampler, srgb: false });
    TextureRef { texture: scene.textures.len() - 1, tex_coord: 0, transform }
}

/// In both primary modes, `textured` renders bit-identical to `factors` (what the texture should act as), and
/// `factors` visibly differs from `original`, so the comparison means something.
fn assert_renders_alike_in_both_modes(gpu: &GpuTest, textured: &Scene, factors: &Scene, original: &Scene, what: &str) {
    for primary in [Primary::Raster, Primary::Rays] {
        let s = RenderSettings { primary, ..settings(64, 36, 2, SamplerKind::Jittered) };
        let with_texture = render(gpu.device(), textured, &s).linear;
        let with_factors = render(gpu.device(), factors, &s).linear;
        let untouched = render(gpu.device(), original, &s).linear;
        assert!(with_texture == with_factors, "{primary:?}: the texture does not act as {what}");
        assert!(with_factors != untouched, "{primary:?}: {what} does not show in this picture");
    }
}

/// A second frame on the same device builds no pipeline of its own (the device keeps them) and is the first
/// frame bit for bit.
#[test]
fn a_second_frame_on_one_device_reuses_the_pipelines_and_matches_the_first() {
    let gpu = GpuTest::new();
    let scene = load(&repo("scenes/cornell.toml"));
    let s = settings(48, 32, 2, SamplerKind::Jittered);
    let first = render(gpu.device(), &scene, &s);
    let kept = gpu.device().kept_pipelines().len();
    let second = render(gpu.device(), &scene, &s);
    assert_eq!(gpu.device().kept_pipelines().len(), kept, "the second frame built a pipeline");
    assert!(first.linear == second.linear && first.display == second.display, "the frames differ");
    let traced = render(gpu.device(), &scene, &RenderSettings { primary: Primary::Rays, ..s });
    // One more per way to trace (`render` renders with each the device has).
    let paths = strata::render::accumulate::TracePath::available(gpu.device()).len();
    assert_eq!(gpu.device().kept_pipelines().len(), kept + paths, "the reference mode is its own pipeline");
    assert!(traced.linear != first.linear, "the reference mode rendered the raster frame");
    gpu.finish().unwrap();
}

/// The ray log the benchmark replays (render::ray_log): exactly the rays the pass counts, each a unit direction
/// with a sane interval, shadow rays flagged to end at their first hit; and logging leaves the picture untouched.
/// KHR_materials_unlit: an unlit ground shows its base colour as radiance, whatever the light (the same bits
/// under a light ten times brighter), in both primary modes; a lit ground of the same colour does not.
#[test]
fn an_unlit_surface_shows_its_base_colour_whatever_the_light_in_both_modes() {
    use strata::check::optics::shadow_scene;
    use strata::scene::LightShape;
    let gpu = GpuTest::new();
    let colour = Vec3::new(0.2, 0.5, 0.8);
    let ground = |emission: f32, unlit: bool| {
        let mut scene = shadow_scene(LightShape::Point { radius: 0.1 }, emission, false);
        for m in &mut scene.materials {
            m.base_color = colour.extend(1.0);
            m.unlit = unlit;
        }
        scene
    };
    for primary in [Primary::Raster, Primary::Rays] {
        let s = RenderSettings { primary, ..settings(24, 24, 4, SamplerKind::MultiJittered) };
        let dim = render(gpu.device(), &ground(1.0, true), &s);
        let bright = render(gpu.device(), &ground(10.0, true), &s);
        assert!(dim.linear == bright.linear, "{primary:?}: the light changed an unlit surface");
        // The raster mode's G-buffer holds emission in half floats: within 2^-11 of the colour, relatively.
        let tolerance = colour * 2f32.powi(-11) + Vec3::splat(1e-6);
        for (i, p) in dim.linear.pixels.iter().enumerate() {
            let got = Vec3::new(p[0], p[1], p[2]);
            assert!((got - colour).abs().cmple(tolerance).all(), "{primary:?}: pixel {i} is {got}, not {colour}");
        }
        let lit = render(gpu.device(), &ground(1.0, false), &s);
        let got = Vec3::from_slice(&lit.linear.pixels[0][..3]);
        assert!((got - colour).abs().max_element() > 0.01, "{primary:?}: a lit ground shows {got} as well");
    }
    gpu.finish().unwrap();
}

/// A frame's device memory beyond the scene: at most 100 bytes per pixel with the 32 of the fixed-point sums
/// (issue 30), in both primary modes. (In the raster mode the resolve writes its linear mean over the G-buffer's
/// position attachment; tests/scale_out.rs holds that picture to the one a merge resolves into images of its
/// own, byte for byte.)
#[test]
fn a_frame_holds_at_most_100_bytes_per_pixel_with_its_sums() {
    use strata::render::frame::{render_frame, FrameOptions};
    let gpu = GpuTest::new();
    let device = gpu.device();
    let scene = load(&repo("scenes/cornell.toml"));
    let on_gpu = strata::render::SceneOnGpu::upload(device, &scene).unwrap();
    let scene_bytes = device.allocator().generate_report().total_allocated_bytes;
    let (width, height) = (192, 128);
    for primary in [Primary::Raster, Primary::Rays] {
        let s = RenderSettings { primary, ..settings(width, height, 2, SamplerKind::MultiJittered) };
        let frame = render_frame(device, &scene, &on_gpu, &s, &FrameOptions::default(), &mut |_, _| true).unwrap();
        let per_pixel = (frame.stats.device_bytes - scene_bytes) as f64 / f64::from(width * height);
        assert!(per_pixel <= 100.0, "{primary:?}: {per_pixel:.1} bytes per pixel");
        // Not vacuous: the images alone are most of it.
        assert!(per_pixel >= 52.0, "{primary:?}: {per_pixel:.1} bytes per pixel is less than the images hold");
    }
    drop(on_gpu);
    gpu.finish().unwrap();
}

#[test]
fn the_ray_log_holds_every_ray_the_pass_casts_and_only_observes() {
    use strata::render::frame::{render_frame, FrameOptions};
    use strata::render::ray_probe::ProbeRay;
    let gpu = GpuTest::new();
    let scene = load(&repo("scenes/showcase.toml"));
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    let paths = strata::render::accumulate::TracePath::available(gpu.device());
    for (primary, path) in [Primary::Raster, Primary::Rays].into_iter().flat_map(|p| paths.iter().map(move |t| (p, *t)))
    {
        let s = RenderSettings { primary, trace: path.as_trace(), ..settings(64, 36, 1, SamplerKind::Jittered) };
        let logged = FrameOptions { log_rays: true, ..Default::default() };
        let frame = render_frame(gpu.device(), &scene, &on_gpu, &s, &logged, &mut |_, _| true).unwrap();
        let plain = render(gpu.device(), &scene, &s);
        assert!(frame.linear == plain.linear, "{primary:?}, {path:?}: logging the rays changed the picture");
        let st = &frame.stats;
        let shadow = frame.ray_log.iter().filter(|r| r.flags == ProbeRay::FIRST_HIT).count() as u64;
        let closest = frame.ray_log.iter().filter(|r| r.flags == 0).count() as u64;
        eprintln!(
            "{primary:?}, {path:?}: {} rays logged, {shadow} shadow, {closest} closest hit; {st:?}",
            frame.ray_log.len()
        );
        assert_eq!(shadow + closest, frame.ray_log.len() as u64, "{primary:?}, {path:?}: unexpected ray flags");
        assert_eq!(shadow, st.shadow_rays, "{primary:?}, {path:?}: shadow rays logged vs counted");
        assert_eq!(
            closest,
            st.secondary_rays + st.camera_rays,
            "{primary:?}, {path:?}: closest-hit rays logged vs counted"
        );
        assert!(
            st.shadow_rays > 1000 && st.secondary_rays > 100,
            "{primary:?}, {path:?}: too few rays to mean anything"
        );
        for r in &frame.ray_log {
            assert!(
                r.origin.is_finite() && (r.direction.length() - 1.0).abs() < 1e-3,
                "{primary:?}, {path:?}: ray {r:?}"
            );
            assert!(r.t_min >= 0.0 && r.t_max > r.t_min, "{primary:?}, {path:?}: empty interval {r:?}");
        }
    }
    drop(on_gpu);
    gpu.finish().unwrap();
}

/// On a CPU device the accumulation pass's workgroups share the work (load balance on lavapipe, which splits a
/// launch into one fixed run of workgroups per thread): with ray queries they take 8×8 tiles from a queue until
/// it runs dry; through the ray-tracing pipeline, rows of 8 invocations take 8-pixel runs in turn. How the work
/// is spread must not matter: one workgroup doing everything, a few, the device's default, more than there are
/// tiles, and a GPU's launch (one workgroup per tile, one invocation per pixel) give the same bits and count the
/// same rays, both ways to trace, in both primary modes, on an image whose edge tiles are partial; with one path
/// per camera sample and with three (`--shading-samples`, whose paths pack their chains tile by tile in turn),
/// and both ways to trace agree on the bits.
#[test]
fn the_picture_does_not_depend_on_how_the_work_is_spread_over_invocations() {
    use strata::render::accumulate::AccumulateLaunch;
    use strata::render::frame::{render_frame, FrameOptions};
    let gpu = GpuTest::new();
    let scene = load(&repo("scenes/showcase.toml"));
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    // 45x29 pixels: 6x4 = 24 tiles, the last column and row partial.
    let tiles = 24;
    let paths = strata::render::accumulate::TracePath::available(gpu.device());
    let mut by_path: Vec<(Primary, u32, Vec<[f32; 4]>)> = Vec::new();
    let cases = [Primary::Raster, Primary::Rays].into_iter().flat_map(|primary| [(primary, 1), (primary, 3)]);
    for ((primary, shading_samples), path) in cases.flat_map(|c| paths.iter().map(move |p| (c, *p))) {
        // A background no surface shows, so a pixel nothing shaded (the image is never cleared) stands out.
        let background = Vec3::new(0.25, 0.5, 0.75);
        let s = RenderSettings {
            primary,
            background,
            trace: path.as_trace(),
            shading_samples,
            ..settings(45, 29, 2, SamplerKind::MultiJittered)
        };
        let frame = |launch: AccumulateLaunch| {
            let options = FrameOptions { accumulate_launch: launch, ..Default::default() };
            render_frame(gpu.device(), &scene, &on_gpu, &s, &options, &mut |_, _| true).unwrap()
        };
        let default = frame(AccumulateLaunch::DeviceDefault);
        assert!(default.stats.shadow_rays > 500 && default.stats.secondary_rays > 50, "{primary:?}: too few rays");
        let background_rgb = background.to_array();
        let unshaded = default.linear.pixels.iter().filter(|p| p[3] == 0.0 && p[..3] != background_rgb).count();
        assert_eq!(unshaded, 0, "{path:?} {primary:?}: pixels showing neither a surface nor the background");
        assert!(default.linear.pixels.iter().any(|p| p[3] == 0.0), "{primary:?}: the background is not in view");
        let launches = [1, 3, tiles, tiles + 7].map(AccumulateLaunch::Workgroups);
        for launch in launches.into_iter().chain([AccumulateLaunch::OnePerTileOrPixel]) {
            let other = frame(launch);
            assert!(
                other.linear == default.linear,
                "{path:?} {primary:?} x{shading_samples}: {launch:?} changed the picture"
            );
            let rays = |f: &strata::render::frame::RenderedFrame| (f.stats.shadow_rays, f.stats.secondary_rays);
            assert_eq!(
                rays(&other),
                rays(&default),
                "{path:?} {primary:?} x{shading_samples}: {launch:?} counted other rays"
            );
        }
        match by_path.iter().find(|(p, k, _)| (*p, *k) == (primary, shading_samples)) {
            Some((_, _, first)) => {
                assert!(first == &default.linear.pixels, "{path:?} {primary:?}: not the other path's bits")
            }
            None => by_path.push((primary, shading_samples, default.linear.pixels.clone())),
        }
    }
    // Three paths a sample are not one path thrice: they draw their own light and lobe samples.
    let pictures = |k: u32| by_path.iter().filter(move |(_, s, _)| *s == k).map(|(_, _, p)| p);
    assert!(pictures(1).zip(pictures(3)).all(|(a, b)| a != b), "three paths per sample repeated the first");
    drop(on_gpu);
    gpu.finish().unwrap();
}

/// Direct light alone (`--bounces 0`) builds the accumulation pipeline without the chain code no path reaches
/// (CHAINS, accumulate_bindings.glsl): the same bits and rays as the pipeline that holds it, both ways to trace.
#[test]
fn leaving_out_chain_code_no_path_reaches_changes_no_bit() {
    use strata::render::frame::{render_frame, FrameOptions};
    let gpu = GpuTest::new();
    let scene = load(&repo("scenes/showcase.toml"));
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    for path in strata::render::accumulate::TracePath::available(gpu.device()) {
        let s =
            RenderSettings { bounces: 0, trace: path.as_trace(), ..settings(40, 24, 2, SamplerKind::MultiJittered) };
        let frame = |keep_chain_code: bool| {
            let options = FrameOptions { keep_chain_code, ..Default::default() };
            render_frame(gpu.device(), &scene, &on_gpu, &s, &options, &mut |_, _| true).unwrap()
        };
        let (without, with) = (frame(false), frame(true));
        assert!(without.stats.shadow_rays > 300, "{path:?}: too few shadow rays to compare");
        assert_eq!(without.stats.secondary_rays, 0, "{path:?}: a path went on at --bounces 0");
        assert!(without.linear == with.linear, "{path:?}: leaving out the chain code changed the picture");
        assert_eq!(without.stats.shadow_rays, with.stats.shadow_rays, "{path:?}: other shadow rays");
    }
    drop(on_gpu);
    gpu.finish().unwrap();
}

/// Soft shadows, depth of field and motion blur without glossy paths: a Lambertian floor and boxes (one
/// sliding) under a quad light, seen through a lens focused between them.
fn effects_scene() -> Scene {
    use strata::scene::{Camera, Light, LightShape, NodeMotion, Projection, RigidMotion};
    let mut scene = Scene::default();
    let floor = lambertian(&mut scene, 0.7);
    let (p, m) = plane_at(Vec2::new(10.0, 10.0), Vec3::ZERO, false, floor);
    place(&mut scene, "floor", p, m);
    let white = lambertian(&mut scene, 0.9);
    for (i, (x, z)) in [(-0.8f32, -0.5f32), (0.6, 0.4), (0.2, -2.0)].into_iter().enumerate() {
        let cube = strata::scene::shapes::cuboid(Vec3::splat(0.3), Some(white));
        let node = place(&mut scene, "box", cube, glam::Mat4::from_translation(Vec3::new(x, 0.3, z)));
        if i == 1 {
            let motion = RigidMotion { velocity: Vec3::new(0.8, 0.0, 0.0), angular_velocity: Vec3::ZERO };
            scene.node_motion.push(NodeMotion { node, motion });
        }
    }
    scene.shutter = (0.0, 0.5);
    scene.lights.push(Light {
        name: "quad".into(),
        shape: LightShape::Quad { size: Vec2::new(1.5, 1.5) },
        emission: Vec3::splat(4.0),
        world_from_light: strata::scene::camera::look_at(Vec3::new(-1.0, 3.0, 1.0), Vec3::ZERO, Vec3::Y),
        node: None,
        range: 0.0,
    });
    scene.camera = Some(Camera {
        name: "lens".into(),
        world_from_camera: strata::scene::camera::look_at(Vec3::new(0.0, 1.5, 3.5), Vec3::new(0.0, 0.2, 0.0), Vec3::Y),
        projection: Projection::Perspective { yfov: 40f32.to_radians(), znear: 0.05, zfar: Some(50.0) },
        lens: strata::scene::camera::Lens { aperture_radius: 0.08, focus_distance: 3.6 },
    });
    scene
}

fn rmse(a: &strata::output::Frame, b: &strata::output::Frame) -> f64 {
    let sum: f64 =
        a.pixels.iter().zip(&b.pixels).map(|(p, q)| (0..3).map(|c| f64::from(p[c] - q[c]).powi(2)).sum::<f64>()).sum();
    (sum / (3 * a.pixels.len()) as f64).sqrt()
}

#[test]
fn jittered_sampling_converges_faster_than_random() {
    let gpu = GpuTest::new();
    let scene = effects_scene();
    let (w, h) = (64, 36);
    let reference = render(gpu.device(), &scene, &settings(w, h, 2048, SamplerKind::Random)).linear;
    let curve = |kind: SamplerKind| -> Vec<(u32, f64)> {
        [4u32, 16, 64]
            .into_iter()
            .map(|spp| (spp, rmse(&render(gpu.device(), &scene, &settings(w, h, spp, kind)).linear, &reference)))
            .collect()
    };
    let (jittered, random) = (curve(SamplerKind::Jittered), curve(SamplerKind::Random));
    let (sj, sr) = (log_log_slope(&jittered), log_log_slope(&random));
    eprintln!("RMSE jittered {jittered:?} slope {sj:.3}; random {random:?} slope {sr:.3}");
    assert!(sj < sr, "jittered error must fall faster: slope {sj:.3} vs random {sr:.3}");
    assert!(jittered[1].1 < random[1].1, "at 16 spp jittered {} vs random {}", jittered[1].1, random[1].1);
    gpu.finish().unwrap();
}
