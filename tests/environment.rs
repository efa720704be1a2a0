//! Environment lighting and transparent backgrounds against what they must equal: the furnace (a diffuse sphere
//! in a uniform environment reflects albedo × radiance; a white glTF dielectric reflects 1 at every angle, and
//! bumps make no energy), a mirror that shows the environment as it is, one
//! bright texel that lights like a directional light of the same irradiance, importance sampling that beats
//! uniform sampling, a rotation of the environment that equals the opposite rotation of the scene, and alpha
//! that composites back into the opaque render. Every GPU test runs under the validation layer.
use crate::common;

use common::scenes::*;
use common::GpuTest;
use glam::{Mat4, Vec3};
use std::f32::consts::PI;
use strata::check::optics::ground_scene;
use strata::output::{linear_to_srgb, srgb_to_linear};
use strata::render::frame::RenderedFrame;
use strata::scene::camera::{look_at, Lens};
use strata::scene::environment::{uv_to_direction, Environment};
use strata::scene::settings::{Backdrop, Primary, RenderSettings, SamplerKind};
use strata::scene::{Camera, Light, LightShape, Projection, Scene};

/// A unit sphere of `material` at the origin, seen from 3.2 m away with a 30° field of view.
fn sphere_scene(material: impl FnOnce(&mut Scene) -> usize) -> Scene {
    sphere_scene_from(3.2, material)
}

/// The same sphere seen from `distance`.
fn sphere_scene_from(distance: f32, material: impl FnOnce(&mut Scene) -> usize) -> Scene {
    let mut scene = Scene::default();
    let m = material(&mut scene);
    strata::scene::library::add_sphere_in_view(&mut scene, m, distance, 30.0);
    scene
}

/// Mean red radiance over the pixels the sphere covers fully (alpha 1), and how many there are.
fn covered_mean(frame: &RenderedFrame) -> (f32, usize) {
    let inside: Vec<f32> = frame.linear.pixels.iter().filter(|p| p[3] >= 1.0).map(|p| p[0]).collect();
    (inside.iter().sum::<f32>() / inside.len().max(1) as f32, inside.len())
}

/// An albedo a quarter of a step above the 8-bit sRGB level `k` (so that the G-buffer's sRGB attachment stores
/// `k` whether the driver rounds or truncates; lavapipe stores 0.5, 187.53 steps, as 187), and the albedo the
/// raster mode reads back from it.
fn albedo_and_stored(k: u8) -> (f32, f32) {
    (srgb_to_linear((f32::from(k) + 0.25) / 255.0), srgb_to_linear(f32::from(k) / 255.0))
}

#[test]
fn a_furnace_sphere_reflects_albedo_times_radiance_and_a_mirror_shows_the_environment() {
    let gpu = GpuTest::new();
    let ((albedo, stored), radiance) = (albedo_and_stored(188), 0.8f32);
    let mut diffuse = sphere_scene(|s| lambertian(s, albedo));
    diffuse.environment = Some(Environment::uniform(Vec3::splat(radiance)));
    for primary in [Primary::Raster, Primary::Rays] {
        for indirect in [false, true] {
            let s = RenderSettings { primary, indirect, ..settings(48, 48, 32, SamplerKind::Jittered) };
            let frame = render(gpu.device(), &diffuse, &s);
            let (mean, n) = covered_mean(&frame);
            let rho = if primary == Primary::Raster { stored } else { albedo };
            let expected = rho * radiance;
            eprintln!("{primary:?}, indirect {indirect}: {mean} over {n} pixels, ρ·L = {expected}");
            assert!(n > 400, "the sphere covers {n} pixels");
            assert!(
                (mean - expected).abs() <= 0.01 * expected,
                "{primary:?}, indirect {indirect}: {mean}, but ρ·L = {expected}"
            );
            // Where no surface is, the camera sees the environment.
            let corner = frame.linear.pixel(0, 0);
            assert!((corner[0] - radiance).abs() < 1e-5 && corner[3] == 0.0, "{corner:?}");
        }
    }
    let mut mirror = sphere_scene(|s| metal(s, 0.0));
    mirror.environment = Some(Environment::uniform(Vec3::new(0.2, 0.4, 0.8)));
    for primary in [Primary::Raster, Primary::Rays] {
        let frame =
            render(gpu.device(), &mirror, &RenderSettings { primary, ..settings(48, 48, 8, SamplerKind::Jittered) });
        // The mean over the sphere is the environment's radiance; most pixels show it exactly (a few near the
        // silhouette lose a reflection below the facet, and light samples add MIS-weighted noise).
        let covered: Vec<[f32; 4]> = frame.linear.pixels.iter().copied().filter(|p| p[3] >= 1.0).collect();
        for (c, want) in [0.2f32, 0.4, 0.8].into_iter().enumerate() {
            let mean = covered.iter().map(|p| p[c]).sum::<f32>() / covered.len() as f32;
            assert!(
                (mean - want).abs() <= 0.01 * want,
                "{primary:?}: the mirror's mean {mean}, the environment {want}"
            );
        }
        let exact = covered.iter().filter(|p| (p[2] - 0.8).abs() <= 0.01 * 0.8).count();
        assert!(
            exact * 10 >= covered.len() * 9,
            "{primary:?}: only {exact} of {} pixels show it within 1%",
            covered.len()
        );
    }
    gpu.finish().unwrap();
}

/// Ground (albedo 0.8) under an occluder over x < 0 whose edge runs along z, 1 m up, seen straight down: a
/// 128 × 32 image spans x from −1.5 to 2.5 m (32 px per metre).
fn ground_with_edge() -> Scene {
    let mut scene = ground_scene();
    let occluder = lambertian(&mut scene, 0.5);
    let slab = strata::scene::shapes::cuboid(Vec3::new(5.0, 0.01, 5.0), Some(occluder));
    place(&mut scene, "occluder", slab, Mat4::from_translation(Vec3::new(-5.0, 1.0, 0.0)));
    scene.camera = Some(ortho_down(Vec3::new(0.5, 0.0, 0.0), 0.5, 0.5));
    scene
}

#[test]
fn one_bright_texel_lights_like_a_directional_light_of_its_irradiance() {
    let gpu = GpuTest::new();
    // A texel 30.9° from the zenith, towards +X: its light falls towards −X, so the occluder's shadow edge lies
    // at x = −tan θ · 1 m (d_x / d_y).
    let (w, h, column, row) = (64u32, 32u32, 48u32, 5u32);
    let le = 40.0f32;
    let direction = uv_to_direction((column as f32 + 0.5) / w as f32, (row as f32 + 0.5) / h as f32);
    let (theta0, theta1) = (PI * row as f32 / h as f32, PI * (row + 1) as f32 / h as f32);
    let solid_angle = 2.0 * PI / w as f32 * (theta0.cos() - theta1.cos());
    let mut lit_by_texel = ground_with_edge();
    lit_by_texel.environment = Some(Environment::one_texel(w, h, column, row, Vec3::splat(le)));
    let mut lit_by_sun = ground_with_edge();
    lit_by_sun.lights.push(Light {
        name: "sun".into(),
        shape: LightShape::Directional,
        emission: Vec3::splat(le * solid_angle),
        world_from_light: look_at(Vec3::ZERO, -direction, Vec3::Z),
        node: None,
        range: 0.0,
    });
    let s = RenderSettings { backdrop: Some(Backdrop::Colour), ..settings(128, 32, 64, SamplerKind::MultiJittered) };
    let texel = column_profile(&render(gpu.device(), &lit_by_texel, &s), 0..32);
    let sun = column_profile(&render(gpu.device(), &lit_by_sun, &s), 0..32);
    // The lit part is right of the shadow's edge.
    let lit = |p: &[f32]| p[110..].iter().sum::<f32>() / p[110..].len() as f32;
    let (a, b) = (lit(&texel), lit(&sun));
    let analytic = 0.8 / PI * le * solid_angle * direction.y;
    eprintln!("lit ground: texel {a}, directional {b}, analytic {analytic}");
    assert!((a - b).abs() <= 0.01 * b, "lit ground: one texel {a}, its directional light {b}");
    assert!((b - analytic).abs() <= 0.01 * analytic, "directional light {b}, ρ/π·E·cos θ = {analytic}");
    let edge = |p: &[f32], level: f32| crossing(p, level).expect("the profile crosses the level");
    let (x_texel, x_sun) = (edge(&texel, 0.5 * a), edge(&sun, 0.5 * b));
    let predicted = (-direction.x / direction.y + 1.5) * 32.0;
    assert!((x_texel - x_sun).abs() <= 1.5, "shadow edges at {x_texel} px and {x_sun} px");
    assert!((x_sun - predicted).abs() <= 1.5, "the shadow edge at {x_sun} px, tan θ predicts {predicted} px");
    gpu.finish().unwrap();
}

#[test]
fn importance_sampling_the_environment_beats_uniform_sampling_at_equal_samples() {
    use strata::render::environment::{upload_sampled, EnvironmentSampling};
    use strata::render::frame::{render_frame, FrameOptions};
    let gpu = GpuTest::new();
    let mut scene = ground_scene();
    scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.5));
    scene.environment = Some(Environment::studio(256, 128));
    let mut on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    let mut frame = |spp: u32, sampling: EnvironmentSampling| {
        on_gpu.environment = upload_sampled(gpu.device(), scene.environment.as_ref(), sampling).unwrap();
        let s = settings(24, 24, spp, SamplerKind::Random);
        render_frame(gpu.device(), &scene, &on_gpu, &s, &FrameOptions::default(), &mut |_, _| true).unwrap()
    };
    let reference = frame(1024, EnvironmentSampling::Importance);
    let rmse = |f: &RenderedFrame| {
        let sum: f64 =
            f.linear.pixels.iter().zip(&reference.linear.pixels).map(|(a, b)| f64::from(a[0] - b[0]).powi(2)).sum();
        (sum / f.linear.pixels.len() as f64).sqrt()
    };
    let importance = rmse(&frame(16, EnvironmentSampling::Importance));
    let uniform = rmse(&frame(16, EnvironmentSampling::UniformSphere));
    // Uniform sampling at 16× the samples converges to the same picture.
    let uniform_many = frame(1024, EnvironmentSampling::UniformSphere);
    let mean =
        |f: &RenderedFrame| f.linear.pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / f.linear.pixels.len() as f64;
    let (m_ref, m_uni) = (mean(&reference), mean(&uniform_many));
    eprintln!(
        "RMSE at 16 spp: importance {importance:.5}, uniform {uniform:.5}, ratio {:.2}; means {m_ref:.4} {m_uni:.4}",
        uniform / importance
    );
    assert!((m_ref - m_uni).abs() <= 0.01 * m_ref, "both strategies converge to one picture: {m_ref} and {m_uni}");
    assert!(uniform > 2.0 * importance, "importance {importance}, uniform {uniform}");
    drop((reference, uniform_many, on_gpu));
    gpu.finish().unwrap();
}

/// A sphere and two boxes on a ground plane, every placement turned by `turn` about +Y, and a camera turned
/// with them.
fn turned_scene(turn: Mat4) -> Scene {
    let mut scene = ground_scene();
    scene.instances[0].world_from_object = turn * scene.instances[0].world_from_object;
    scene.nodes[0].transform = strata::scene::NodeTransform::Matrix(scene.instances[0].world_from_object);
    let white = lambertian(&mut scene, 0.7);
    let red = {
        let m = lambertian(&mut scene, 0.7);
        scene.materials[m].base_color = glam::Vec4::new(0.8, 0.2, 0.1, 1.0);
        m
    };
    place(
        &mut scene,
        "sphere",
        strata::scene::shapes::uv_sphere(0.5, 64, 32, Some(white)),
        turn * Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)),
    );
    let cube = strata::scene::shapes::cuboid(Vec3::splat(0.3), Some(red));
    place(&mut scene, "box", cube, turn * Mat4::from_translation(Vec3::new(1.0, 0.3, -0.5)));
    scene.camera = Some(Camera {
        name: "view".into(),
        world_from_camera: turn * look_at(Vec3::new(1.5, 1.5, 3.0), Vec3::new(0.2, 0.3, 0.0), Vec3::Y),
        projection: Projection::Perspective { yfov: 40f32.to_radians(), znear: 0.1, zfar: Some(100.0) },
        lens: Lens::PINHOLE,
    });
    scene
}

#[test]
fn rotating_the_environment_equals_rotating_the_scene_the_other_way() {
    let gpu = GpuTest::new();
    let mut studio = Environment::studio(256, 128);
    let mut a = turned_scene(Mat4::IDENTITY);
    studio.rotation_degrees = 90.0;
    a.environment = Some(studio.clone());
    let mut b = turned_scene(Mat4::from_rotation_y(-90f32.to_radians()));
    studio.rotation_degrees = 0.0;
    b.environment = Some(studio);
    let s = settings(64, 48, 16, SamplerKind::MultiJittered);
    let (fa, fb) = (render(gpu.device(), &a, &s), render(gpu.device(), &b, &s));
    let other_seed = render(gpu.device(), &a, &RenderSettings { seed: 99, ..s.clone() });
    let mean_abs = |x: &RenderedFrame, y: &RenderedFrame| {
        let sum: f64 = x
            .linear
            .pixels
            .iter()
            .zip(&y.linear.pixels)
            .map(|(p, q)| (0..3).map(|c| f64::from((p[c] - q[c]).abs())).sum::<f64>())
            .sum();
        sum / (3 * x.linear.pixels.len()) as f64
    };
    let (turned, noise) = (mean_abs(&fa, &fb), mean_abs(&fa, &other_seed));
    eprintln!("mean |Δ| rotated environment vs rotated scene {turned:.6}; vs another seed {noise:.6}");
    assert!(turned < 0.1 * noise, "the two rotations differ by {turned}, the noise between seeds is {noise}");
    gpu.finish().unwrap();
}

#[test]
fn a_transparent_background_keeps_coverage_and_composites_back_into_the_opaque_render() {
    let gpu = GpuTest::new();
    let mut scene = sphere_scene(|s| lambertian(s, 0.6));
    scene.environment = Some(Environment::studio(128, 64));
    // A little depth of field, so edges are fractional over more pixels.
    scene.camera.as_mut().unwrap().lens = Lens { aperture_radius: 0.05, focus_distance: 2.2 };
    let background = Vec3::new(0.3, 0.5, 0.2);
    let base = RenderSettings { background, ..settings(48, 48, 32, SamplerKind::MultiJittered) };
    let transparent =
        render(gpu.device(), &scene, &RenderSettings { backdrop: Some(Backdrop::Transparent), ..base.clone() });
    let opaque = render(gpu.device(), &scene, &RenderSettings { backdrop: Some(Backdrop::Colour), ..base });
    let alpha: Vec<f32> = transparent.linear.pixels.iter().map(|p| p[3]).collect();
    assert_eq!(transparent.linear.pixel(24, 24)[3], 1.0, "the object is covered");
    assert_eq!(transparent.linear.pixel(0, 0)[3], 0.0, "the corner is not");
    let fractional = alpha.iter().filter(|&&a| a > 0.0 && a < 1.0).count();
    assert!(fractional > 40, "only {fractional} pixels on the edge have fractional coverage");
    assert_eq!(transparent.linear.pixel(0, 0)[..3], [0.0; 3], "nothing is added where nothing is covered");
    for (i, (t, o)) in transparent.linear.pixels.iter().zip(&opaque.linear.pixels).enumerate() {
        // EXR: premultiplied radiance; over the background it is the opaque render (the same samples).
        for c in 0..3 {
            let over = t[c] + (1.0 - t[3]) * background[c];
            assert!((over - o[c]).abs() <= 1e-5 * (1.0 + o[c]), "pixel {i}: {t:?} over the background is not {o:?}");
        }
        // PNG: straight alpha; composited in linear light over the background, it encodes to the opaque PNG.
        let png = &transparent.display[4 * i..4 * i + 4];
        let a = f32::from(png[3]) / 255.0;
        assert!((a - t[3]).abs() <= 0.5 / 255.0 + 1e-6, "pixel {i}: PNG alpha {} for coverage {}", png[3], t[3]);
        for c in 0..3 {
            let straight = srgb_to_linear(f32::from(png[c]) / 255.0);
            let over = linear_to_srgb(straight * a + (1.0 - a) * background[c]) * 255.0;
            let want = f32::from(opaque.display[4 * i + c]);
            assert!((over - want).abs() <= 2.0, "pixel {i}: the PNG composites to {over}, the opaque PNG has {want}");
        }
    }
    gpu.finish().unwrap();
}

#[test]
fn environment_files_load_from_hdr_and_exr_and_bad_ones_name_the_file() {
    let dir = std::env::temp_dir().join(format!("strata-environment-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (8u32, 4u32);
    let texels: Vec<[f32; 3]> = (0..w * h).map(|i| [i as f32 * 0.25, 1.0, 2.0]).collect();
    // Radiance .hdr keeps 8-bit mantissas with a shared exponent: values with few bits survive exactly.
    let hdr = dir.join("sky.hdr");
    let pixels: Vec<image::Rgb<f32>> = texels.iter().map(|t| image::Rgb(*t)).collect();
    image::codecs::hdr::HdrEncoder::new(std::fs::File::create(&hdr).unwrap())
        .encode(&pixels, w as usize, h as usize)
        .unwrap();
    let from_hdr = Environment::load(&hdr).unwrap();
    assert_eq!((from_hdr.width, from_hdr.height), (w, h));
    assert_eq!(from_hdr.texels[5], Vec3::new(1.25, 1.0, 2.0));
    let exr = dir.join("sky.exr");
    let frame = strata::output::Frame::new(w, h, texels.iter().map(|t| [t[0], t[1], t[2], 1.0]).collect()).unwrap();
    strata::output::write_frame(&exr, &frame).unwrap();
    let from_exr = Environment::load(&exr).unwrap();
    assert_eq!(from_exr.texels, texels.iter().map(|t| Vec3::from_array(*t)).collect::<Vec<_>>());
    let broken = dir.join("broken.hdr");
    std::fs::write(&broken, b"#?RADIANCE\nnot really\n").unwrap();
    let err = format!("{:#}", Environment::load(&broken).unwrap_err());
    assert!(err.starts_with(&broken.display().to_string()) && err.contains("not a Radiance HDR image"), "{err}");
    let err = Environment::load(&dir.join("sky.png")).unwrap_err().to_string();
    assert!(err.contains("no such file"), "{err}");
    std::fs::write(dir.join("sky.jpg"), b"x").unwrap();
    let err = Environment::load(&dir.join("sky.jpg")).unwrap_err().to_string();
    assert!(err.contains("unknown environment extension \".jpg\""), "{err}");
}

/// Mean and standard error of the brightest channel over the fully covered pixels of a sphere's image whose
/// distance from the centre, in sphere radii (`radius` pixels), lies in [lo, hi); and the largest pixel there.
fn ring_stats(frame: &RenderedFrame, radius: f32, (lo, hi): (f32, f32)) -> (f64, f64, f64) {
    let (w, h) = (frame.linear.width, frame.linear.height);
    let values: Vec<f64> = (0..w * h)
        .filter_map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5 - w as f32 / 2.0, (i / w) as f32 + 0.5 - h as f32 / 2.0);
            let r = (x * x + y * y).sqrt() / radius;
            let p = frame.linear.pixels[i as usize];
            (p[3] >= 1.0 && r >= lo && r < hi).then(|| f64::from(p[0].max(p[1]).max(p[2])))
        })
        .collect();
    let n = values.len() as f64;
    assert!(n > 30.0, "only {n} pixels in ring {lo}–{hi}");
    let mean = values.iter().sum::<f64>() / n;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    (mean, sd / n.sqrt(), values.iter().copied().fold(0.0, f64::max))
}

/// The white furnace for the glTF dielectric: a white sphere (base colour 1, F0 0.04) in a uniform environment of
/// radiance 1 reflects exactly 1 everywhere, grazing silhouette included, since its diffuse base gets what the
/// specular layer leaves over all directions (albedo scaling); glTF 2.0 Appendix B's per-direction 1 − F(v·h)
/// made 1.04–1.11 there. With a strong bump (shading normals tilted up to grazing) it may lose energy where rays
/// leave below the surface, but never make any. Tolerances: four standard errors of each ring's mean, plus 0.003
/// for the albedo table's interpolation (math::brdf).
#[test]
fn a_white_dielectric_in_a_white_furnace_reflects_one_at_every_angle_and_bumps_make_no_energy() {
    use strata::scene::{BumpMap, Material, NoiseKind};
    let gpu = GpuTest::new();
    let size = 64u32;
    // 5 m away, so the grazing silhouette is in the 30° view: tan(asin(1/5)) / tan(15°) half images.
    let distance = 5.0f32;
    for (roughness, bump) in [(0.2, 0.0), (0.5, 0.0), (0.2, 0.08)] {
        let mut scene = sphere_scene_from(distance, |s| {
            s.materials.push(Material {
                name: "white dielectric".into(),
                base_color: glam::Vec4::ONE,
                metallic: 0.0,
                roughness,
                bump: (bump > 0.0).then(|| BumpMap {
                    kind: NoiseKind::Fbm,
                    amplitude: bump,
                    frequency: 16.0,
                    ..Default::default()
                }),
                ..Default::default()
            });
            s.materials.len() - 1
        });
        scene.environment = Some(Environment::uniform(Vec3::ONE));
        let s = RenderSettings { indirect: true, bounces: 16, ..settings(size, size, 64, SamplerKind::MultiJittered) };
        let frame = render(gpu.device(), &scene, &s);
        let radius = (1.0 / distance).asin().tan() / 15f32.to_radians().tan() * size as f32 / 2.0;
        for ring in [(0.0, 0.7), (0.7, 0.9), (0.9, 0.97)] {
            let (mean, se, max) = ring_stats(&frame, radius, ring);
            eprintln!("roughness {roughness}, bump {bump}, ring {ring:?}: {mean:.4} ± {se:.4}, max {max:.3}");
            let tolerance = 4.0 * se + 0.003;
            assert!(mean <= 1.0 + tolerance, "roughness {roughness}, bump {bump}, ring {ring:?}: {mean} ± {se} > 1");
            if bump == 0.0 {
                assert!(mean >= 1.0 - tolerance, "roughness {roughness}, ring {ring:?}: {mean} ± {se} < 1");
            }
        }
    }
    gpu.finish().unwrap();
}

/// KHR_materials_volume: light crossing a clear slab of thickness d (transmission 1, IOR 1, no Fresnel reflection)
/// whose material turns white into colour c after distance D keeps c^(d / D) = exp(−σ·d) of itself, σ = −ln(c)/D
/// (Beer–Lambert), seen straight through against a uniform environment of radiance 1: within 1% per channel, for
/// two thicknesses; without attenuation the slab passes everything.
#[test]
fn a_slab_with_volume_attenuation_passes_exp_minus_sigma_d() {
    use strata::scene::Material;
    let gpu = GpuTest::new();
    let color = Vec3::new(0.5, 0.25, 0.8);
    let distance = 1.0f32;
    for (thickness, attenuated) in [(0.5f32, true), (1.5, true), (0.5, false)] {
        let mut scene = Scene::default();
        scene.materials.push(Material {
            name: "clear".into(),
            base_color: glam::Vec4::ONE,
            metallic: 0.0,
            roughness: 0.0,
            transmission: 1.0,
            ior: 1.0,
            specular: 0.0,
            attenuation_color: if attenuated { color } else { Vec3::ONE },
            attenuation_distance: if attenuated { distance } else { f32::INFINITY },
            ..Default::default()
        });
        // Half extents: 8 m wide, `thickness` thick.
        let slab = strata::scene::shapes::cuboid(Vec3::new(4.0, 0.5 * thickness, 4.0), Some(0));
        place(&mut scene, "slab", slab, Mat4::IDENTITY);
        scene.camera = Some(ortho_down(Vec3::ZERO, 3.0, 0.5));
        scene.environment = Some(Environment::uniform(Vec3::ONE));
        let s = RenderSettings { bounces: 4, ..settings(16, 16, 4, SamplerKind::Jittered) };
        let frame = render(gpu.device(), &scene, &s);
        let want = if attenuated { color.powf(thickness / distance) } else { Vec3::ONE };
        for (i, p) in frame.linear.pixels.iter().enumerate() {
            let got = Vec3::new(p[0], p[1], p[2]);
            let error = ((got - want) / want).abs().max_element();
            assert!(error <= 0.01, "thickness {thickness}, pixel {i}: {got}, exp(−σd) = {want}");
        }
    }
    gpu.finish().unwrap();
}
