//! The distributed ray tracing effects against their optics (Cook, Porter and Carpenter 1984): each test builds
//! a small scene whose answer follows from geometry, renders it through the whole sample loop (G-buffer,
//! TLAS, accumulation, resolve) under the validation layer, and measures the picture.
use crate::common;

use common::scenes::*;
use common::GpuTest;
use glam::{Mat4, Vec2, Vec3};
use strata::check::optics::{self, disk_light_scene, ground_scene, light_down, moving_square, shadow_scene, Renderer};
use strata::check::Figure;
use strata::render::frame::RenderedFrame;
use strata::scene::camera::{look_at, Lens};
use strata::scene::settings::{Primary, RenderSettings, SamplerKind};
use strata::scene::{Camera, Light, LightShape, NodeMotion, Projection, RigidMotion, Scene};

/// Runs one of the library's optics cases (strata::check::optics, what `strata check` runs too) through the
/// tests' renderer, which renders both ways to trace and holds them to the same bits, and asserts every figure.
fn assert_optics(gpu: &GpuTest, case: impl FnOnce(&mut Renderer<'_>) -> anyhow::Result<Vec<Figure>>) {
    let figures = case(&mut |scene: &Scene, settings: &RenderSettings| Ok(render(gpu.device(), scene, settings)))
        .unwrap_or_else(|e| panic!("{e:#}"));
    assert!(!figures.is_empty());
    for f in &figures {
        eprintln!("{f}");
        assert!(f.passes(), "{f}");
    }
}

#[test]
fn soft_shadow_penumbra_matches_similar_triangles_and_a_point_light_is_hard() {
    let gpu = GpuTest::new();
    assert_optics(&gpu, optics::penumbra);
    gpu.finish().unwrap();
}

#[test]
fn energy_a_lambertian_plane_under_a_disk_light_reflects_the_analytic_radiance() {
    let gpu = GpuTest::new();
    assert_optics(&gpu, optics::disk_light_radiance);
    gpu.finish().unwrap();
}

#[test]
fn better_samplers_integrate_a_disk_light_with_less_error() {
    // Every pixel estimates the same integral (the window is a millimetre across, so the analytic value
    // differs across it by about 1e-6) with its own decorrelated light samples: the RMSE over pixels is the
    // estimator's error, measured against the closed form, with no noisy reference to flatten the curve.
    let gpu = GpuTest::new();
    let (scene, expected) = disk_light_scene(0.0005);
    let curve = |kind: SamplerKind| -> Vec<(u32, f64)> {
        [4u32, 16, 64]
            .into_iter()
            .map(|spp| {
                let frame = render(gpu.device(), &scene, &settings(32, 32, spp, kind));
                let pixels = &frame.linear.pixels;
                let sum: f64 = pixels.iter().map(|p| f64::from(p[0] - expected).powi(2)).sum();
                (spp, (sum / pixels.len() as f64).sqrt() / f64::from(expected))
            })
            .collect()
    };
    let kinds = [SamplerKind::Random, SamplerKind::Jittered, SamplerKind::MultiJittered, SamplerKind::Sobol];
    let curves: Vec<Vec<(u32, f64)>> = kinds.iter().map(|&k| curve(k)).collect();
    let slopes: Vec<f64> = curves.iter().map(|c| log_log_slope(c)).collect();
    for ((kind, c), slope) in kinds.iter().zip(&curves).zip(&slopes) {
        eprintln!("relative RMSE {kind:?}: {c:?}, log-log slope {slope:.3}");
    }
    let [random, jittered, multi_jittered, sobol] = [0, 1, 2, 3];
    // Independent samples: error ∝ N^-1/2. Strata on a smooth 2D integrand: ∝ N^-1 (Mitchell 1996).
    assert!((-0.6..=-0.4).contains(&slopes[random]), "random: slope {:.3}, not -1/2", slopes[random]);
    for k in [jittered, multi_jittered, sobol] {
        assert!(slopes[k] < -0.8, "{:?}: slope {:.3}, not near -1", kinds[k], slopes[k]);
        assert!(curves[k][1].1 < curves[random][1].1, "{:?} at 16 spp is no better than random", kinds[k]);
    }
    // The better samplers also stratify each 1D projection (and, for Sobol, every elementary interval): at 16
    // and 64 spp their error is well below jittered's.
    for k in [multi_jittered, sobol] {
        for n in [1, 2] {
            assert!(
                curves[k][n].1 * 1.3 < curves[jittered][n].1,
                "{:?} at {} spp: {:.4} vs jittered {:.4}",
                kinds[k],
                curves[k][n].0,
                curves[k][n].1,
                curves[jittered][n].1
            );
        }
    }
    drop(curves);
    gpu.finish().unwrap();
}

#[test]
fn diffuse_interreflection_reflects_a_uniform_sky_as_the_albedo_and_never_counts_a_light_twice() {
    let gpu = GpuTest::new();
    // No lights: a Lambertian plane under a sky of radiance 1 reflects ρ/π · π · 1 = ρ, and cosine-weighted
    // bounces estimate it without variance. Without diffuse interreflection it is black.
    let mut sky = ground_scene();
    sky.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.25));
    for primary in [Primary::Raster, Primary::Rays] {
        let base = RenderSettings { background: Vec3::ONE, primary, ..settings(16, 16, 4, SamplerKind::Jittered) };
        let direct = render(gpu.device(), &sky, &base);
        let indirect = render(gpu.device(), &sky, &RenderSettings { indirect: true, ..base });
        let range = |f: &RenderedFrame| {
            let values = f.linear.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]);
            values.fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)))
        };
        assert_eq!(range(&direct), (0.0, 0.0), "{primary:?}: without interreflection the sky lights nothing");
        // The raster mode reads the albedo from the G-buffer's 8-bit sRGB texel (0.8 is stored as 231/255).
        let (lo, hi) = range(&indirect);
        assert!(hi - lo < 1e-5 && (lo - 0.8).abs() < 2e-3, "{primary:?}: {lo}..{hi}, not the albedo 0.8");
    }
    // Bounces that reach a light add nothing: light sampling has counted it. The disk light's closed form holds
    // with interreflection on (the plane sees nothing else).
    let (disk, expected) = disk_light_scene(0.01);
    let s = RenderSettings { indirect: true, ..settings(32, 32, 64, SamplerKind::Jittered) };
    let frame = render(gpu.device(), &disk, &s);
    let mean = mean_red(&frame);
    assert!((mean - expected).abs() <= 0.01 * expected, "mean radiance {mean}, analytic {expected}");
    // On a glossy dielectric the gloss rays now share their paths with diffuse bounces; their MIS weights against
    // light sampling must follow, or the highlight would change.
    let mut glossy = disk;
    glossy.materials[0].roughness = 0.3;
    glossy.materials[0].specular = 1.0;
    let on = mean_red(&render(gpu.device(), &glossy, &s));
    let off = mean_red(&render(gpu.device(), &glossy, &RenderSettings { indirect: false, ..s }));
    assert!((on - off).abs() <= 0.01 * off, "glossy: {on} with interreflection, {off} without");
    gpu.finish().unwrap();
}

/// The furnace: inside a closed glowing box the radiance is the geometric series of the bounces (Kajiya 1986),
/// cut where --bounces cuts the paths (optics::glowing_box).
#[test]
fn diffuse_interreflection_inside_a_glowing_box_sums_the_bounces() {
    let gpu = GpuTest::new();
    // The default 3 bounces and 1 (their series differ by 9%).
    assert_optics(&gpu, |render| optics::glowing_box_series(render, &[3, 1]));
    gpu.finish().unwrap();
}

#[test]
fn depth_of_field_blur_is_the_circle_of_confusion() {
    let gpu = GpuTest::new();
    assert_optics(&gpu, optics::circle_of_confusion);
    gpu.finish().unwrap();
}

#[test]
fn motion_blur_is_a_linear_ramp_as_long_as_the_motion() {
    let gpu = GpuTest::new();
    assert_optics(&gpu, optics::motion_blur_ramp);
    let (width, height) = (192u32, 64u32);
    // The same square with the shutter closed is the still frame, bit for bit.
    let still_shutter = render(
        gpu.device(),
        &moving_square(Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO, (0.0, 0.0)),
        &settings(width, height, 4, SamplerKind::Jittered),
    );
    let still = render(
        gpu.device(),
        &moving_square(Vec3::ZERO, Vec3::ZERO, (0.0, 0.0)),
        &settings(width, height, 4, SamplerKind::Jittered),
    );
    assert!(still_shutter.linear == still.linear && still_shutter.display == still.display);
    drop((still_shutter, still));
    gpu.finish().unwrap();
}

#[test]
fn a_spinning_bar_blurs_along_its_arc() {
    let gpu = GpuTest::new();
    let mut scene = Scene::default();
    let bright = emitter(&mut scene, 1.0);
    // A bar 1.6 m long along x, 0.04 m wide, spinning about the vertical axis by 0.2 rad during the shutter.
    let (p, m) = plane_at(Vec2::new(1.6, 0.04), Vec3::ZERO, false, bright);
    let node = place(&mut scene, "bar", p, m);
    scene.node_motion.push(NodeMotion {
        node,
        motion: RigidMotion { velocity: Vec3::ZERO, angular_velocity: Vec3::new(0.0, 0.8, 0.0) },
    });
    scene.shutter = (0.0, 0.25);
    scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.5));
    let (width, height) = (128u32, 128u32); // 128 px per metre
    let frame = render(gpu.device(), &scene, &settings(width, height, 64, SamplerKind::Jittered));
    // Across the bar (along image y) at radius r the streak is an arc of about r·θ (plus the bar's width); near
    // the axis it stays as thin as the bar.
    let spread = |r: f32| {
        let x = (width as f32 / 2.0 + r * 128.0) as u32;
        let column: Vec<f32> = (0..height).map(|y| frame.linear.pixel(x, y)[0]).collect();
        column.iter().sum::<f32>() / 128.0 // metres of coverage-weighted length: ∫ profile dy
    };
    let (inner, outer) = (spread(0.1), spread(0.45));
    // The integrated profile is the same (the bar passes each column once) only if the blur is along the arc:
    // the coverage integral ∫ profile dy equals the bar's width divided by the cosine of the angle to the column,
    // ≈ 0.04 m, at every radius.
    assert!((inner - 0.04).abs() < 0.006 && (outer - 0.04).abs() < 0.006, "coverage {inner} {outer}");
    let peak = |r: f32| {
        let x = (width as f32 / 2.0 + r * 128.0) as u32;
        (0..height).map(|y| frame.linear.pixel(x, y)[0]).fold(0.0, f32::max)
    };
    // A bar of width w swept over an arc of length a = r·θ: the profile is the box w convolved with the box a,
    // whose peak is min(1, w / a).
    for r in [0.1f32, 0.45] {
        let expected = (0.04 / (r * 0.2)).min(1.0);
        let got = peak(r);
        assert!((got - expected).abs() < 0.15 * expected + 0.03, "peak at r={r}: {got}, arc predicts {expected}");
    }
    drop(frame);
    gpu.finish().unwrap();
}

fn gloss_scene(roughness: f32) -> Scene {
    let mut scene = Scene::default();
    let mirror = metal(&mut scene, roughness);
    let (p, m) = plane_at(Vec2::new(20.0, 20.0), Vec3::ZERO, false, mirror);
    place(&mut scene, "metal floor", p, m);
    // An emitting half-plane x > 0 at height 2 facing down, behind the camera: seen only in the reflection.
    let bright = emitter(&mut scene, 1.0);
    let (p, m) = plane_at(Vec2::new(10.0, 10.0), Vec3::new(5.0, 2.0, 0.0), true, bright);
    place(&mut scene, "sky edge", p, m);
    scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.25));
    scene
}

#[test]
fn gloss_widens_the_reflected_edge_with_roughness_and_roughness_zero_is_a_mirror() {
    let gpu = GpuTest::new();
    let (width, height) = (256u32, 32u32);
    let mut widths = Vec::new();
    for roughness in [0.0f32, 0.1, 0.2, 0.3] {
        let frame = render(gpu.device(), &gloss_scene(roughness), &settings(width, height, 64, SamplerKind::Jittered));
        assert_finite(&frame, "gloss");
        let profile = column_profile(&frame, 0..height);
        let lit = profile[width as usize - 8..].iter().sum::<f32>() / 8.0;
        assert!(lit > 0.8, "a white metal reflects the emitter almost fully: {lit}");
        widths.push(rise_width(&profile, 0.0, lit));
    }
    assert!(widths[0] <= 1.5, "roughness 0 reflects like a mirror: edge over {:.2} px", widths[0]);
    assert!(widths.windows(2).all(|w| w[1] > w[0] * 1.3), "edge widths must grow with roughness: {widths:?}");
    gpu.finish().unwrap();
}

/// KHR_lights_punctual `range`: a point light's contribution follows the extension's recommended window
/// max(min(1 − (d/range)⁴, 1), 0) on top of the inverse square law, and is zero beyond the range — for a point
/// (delta) light and for one with a radius (sampled as a sphere, windowed by the distance to its centre).
#[test]
fn a_point_lights_range_windows_its_light_as_khr_lights_punctual_recommends() {
    let gpu = GpuTest::new();
    let (width, height, half_height) = (256u32, 32u32, 0.125f32); // 2 m x 0.25 m of ground
    let (light_height, range) = (1.0f32, 1.3f32);
    let lit = |radius: f32, range: f32| {
        let mut scene = ground_scene();
        scene.lights.push(Light {
            name: "point".into(),
            shape: LightShape::Point { radius },
            emission: Vec3::splat(1.0),
            world_from_light: light_down(Vec3::new(0.0, light_height, 0.0)),
            node: None,
            range,
        });
        scene.camera = Some(ortho_down(Vec3::ZERO, 2.0, half_height));
        render(gpu.device(), &scene, &settings(width, height, 1, SamplerKind::Regular)).linear
    };
    for radius in [0.0, 0.05] {
        let (windowed, open) = (lit(radius, range), lit(radius, 0.0));
        let (mut checked, mut dark) = (0, 0);
        for y in 0..height {
            for x in 0..width {
                // Pixel centres on the ground: image x is world x, image y (down) world z.
                let wx = ((x as f32 + 0.5) / width as f32 * 2.0 - 1.0) * half_height * width as f32 / height as f32;
                let wz = ((y as f32 + 0.5) / height as f32 * 2.0 - 1.0) * half_height;
                let d = Vec3::new(wx, -light_height, wz).length();
                let want = (1.0 - (d / range).powi(4)).clamp(0.0, 1.0);
                let (w, o) = (windowed.pixel(x, y)[0], open.pixel(x, y)[0]);
                assert!(o > 0.0, "radius {radius}: ({x}, {y}) is unlit without a range");
                if d > range * 1.001 {
                    assert_eq!(w, 0.0, "radius {radius}: ({x}, {y}) at {d} m lies beyond the range");
                    dark += 1;
                } else if d < range * 0.999 {
                    assert!((w / o - want).abs() < 2e-3, "radius {radius}: ({x}, {y}) at {d} m: {} vs {want}", w / o);
                    checked += 1;
                }
            }
        }
        assert!(checked > 3000 && dark > 1000, "radius {radius}: {checked} pixels in range, {dark} beyond");
    }
    gpu.finish().unwrap();
}

/// A 2×1 texture, nearest-sampled and clamped, whose left texel (u < 0.5) is opaque grey and right texel clear
/// (alpha 0); returns its texture index.
fn half_clear_texture(scene: &mut Scene) -> usize {
    use strata::scene::{Texture, TextureImage, Wrap};
    scene.images.push(TextureImage {
        name: "half clear".into(),
        width: 2,
        height: 1,
        rgba8: vec![200, 200, 200, 255, 200, 200, 200, 0],
    });
    scene.textures.push(Texture {
        name: "half clear".into(),
        image: scene.images.len() - 1,
        sampler: nearest_sampler(Wrap::ClampToEdge),
        srgb: true,
    });
    scene.textures.len() - 1
}

/// A ground-facing leaf card: a plane at height 2 over x in [-10, 10] whose base-colour texture is opaque over
/// its left half (x < 0) and clear over its right half, alpha-masked (glTF MASK, cutoff 0.5).
fn add_leaf_card(scene: &mut Scene) {
    use strata::scene::{AlphaMode, Material, TextureRef};
    let texture = half_clear_texture(scene);
    scene.materials.push(Material {
        name: "leaf card".into(),
        base_color_texture: Some(TextureRef { texture, tex_coord: 0, transform: None }),
        metallic: 0.0,
        specular: 0.0,
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        double_sided: true,
        ..Default::default()
    });
    let (p, m) = plane_at(Vec2::new(20.0, 20.0), Vec3::new(0.0, 2.0, 0.0), false, scene.materials.len() - 1);
    place(scene, "leaf card", p, m);
}

/// Alpha-masked geometry is cut out for rays as the raster pass cuts it out: the leaf card shadows the ground
/// exactly as a solid slab over its opaque half does, and the reference mode's primary rays see through its
/// clear half where the raster pass does.
#[test]
fn alpha_masked_surfaces_are_cut_out_for_shadow_and_primary_rays() {
    let gpu = GpuTest::new();
    let (width, height) = (256, 64);
    let point = LightShape::Point { radius: 0.0 };
    let slab =
        render(gpu.device(), &shadow_scene(point, 20.0, true), &settings(width, height, 1, SamplerKind::Regular));
    let mut card = shadow_scene(point, 20.0, false);
    add_leaf_card(&mut card);
    let masked = render(gpu.device(), &card, &settings(width, height, 1, SamplerKind::Regular));
    let (slab, masked) = (column_profile(&slab, 0..height), column_profile(&masked, 0..height));
    let lit = masked[width as usize - 20..].iter().sum::<f32>() / 20.0;
    assert!(masked[..100].iter().all(|&v| v == 0.0) && lit > 0.0, "no shadow under the opaque half, or no light");
    for (x, (a, b)) in slab.iter().zip(&masked).enumerate() {
        if (x as i32 - 128).abs() > 1 {
            assert!((a - b).abs() <= 1e-4 * lit, "column {x}: the slab gives {a}, the masked card {b}");
        }
    }

    // From above the card: the raster pass discards its clear half, primary rays must pass through it.
    card.camera = Some(ortho_down(Vec3::ZERO, 3.0, 0.25));
    let raster = render(gpu.device(), &card, &settings(width, height, 1, SamplerKind::Regular)).linear;
    let rays = RenderSettings { primary: Primary::Rays, ..settings(width, height, 1, SamplerKind::Regular) };
    let traced = render(gpu.device(), &card, &rays).linear;
    let (raster_profile, traced_profile) = (
        (0..width).map(|x| raster.pixel(x, 32)[0]).collect::<Vec<_>>(),
        (0..width).map(|x| traced.pixel(x, 32)[0]).collect::<Vec<_>>(),
    );
    // Left: the card's lit top; right: the ground through the clear half, lit by the same point light.
    let (card_top, ground) = (raster_profile[20], raster_profile[236]);
    assert!(card_top > 0.0 && ground > 0.0 && (card_top - ground).abs() > 0.1 * card_top, "{card_top} vs {ground}");
    for x in (0..width as usize).filter(|x| (*x as i32 - 128).abs() > 1) {
        let (a, b) = (raster_profile[x], traced_profile[x]);
        // The raster pass's albedo passes through the G-buffer's 8-bit sRGB (0.8 comes back 0.25% darker).
        assert!((a - b).abs() <= 4e-3 * a.max(b), "column {x}: raster {a}, primary rays {b}");
    }
    gpu.finish().unwrap();
}

/// An emissive texture makes its surface a light like any other: a textured quad emitter lights the ground
/// exactly as an untextured one whose factor is the texture's colour times the factor. (Light sampling picks
/// the triangles by the factor's power and the shader scales each sample by the texel it landed on, through the
/// texture's KHR_texture_transform: here one that keeps every lookup on the lit texel of a lit/black pair.)
#[test]
fn emissive_textured_surfaces_light_the_scene_like_their_colour() {
    use strata::scene::{Texture, TextureImage, TextureRef, UvTransform, Wrap};
    let gpu = GpuTest::new();
    // Stored linear here, so the comparison is about the lighting, not lavapipe's sRGB decoding (which glTF's
    // emissive textures go through and which differed from an exact decode by 0.17% in this test).
    let texel = [200u8, 150, 100, 255];
    let colour = Vec3::from_array([0, 1, 2].map(|i| f32::from(texel[i]) / 255.0));
    let lit_by = |textured: bool| {
        let mut scene = ground_scene();
        let lamp = emitter(&mut scene, 3.0);
        // The plain lamp wears a white texel: a lamp with no texture at all is sampled as one quad rather than
        // two triangles (render/lights.rs), with other sample points, and this compares bits, not noise.
        let lit = if textured {
            texel
        } else {
            scene.materials[lamp].emissive *= colour;
            [255; 4]
        };
        let rgba8 = [lit, [0, 0, 0, 255]].concat();
        scene.images.push(TextureImage { name: "lamp".into(), width: 2, height: 1, rgba8 });
        let sampler = nearest_sampler(Wrap::ClampToEdge);
        scene.textures.push(Texture { name: "lamp".into(), image: 0, sampler, srgb: false });
        // u' = 0.4 u stays on the left texel; untransformed, half the lamp would be black.
        let transform = Some(UvTransform { offset: Vec2::ZERO, rotation: 0.0, scale: Vec2::new(0.4, 1.0) });
        scene.materials[lamp].emissive_texture = Some(TextureRef { texture: 0, tex_coord: 0, transform });
        let (p, m) = plane_at(Vec2::new(0.5, 0.5), Vec3::new(0.0, 2.0, 0.0), true, lamp);
        place(&mut scene, "lamp", p, m);
        scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.5));
        render(gpu.device(), &scene, &settings(64, 64, 4, SamplerKind::Jittered)).linear
    };
    let (textured, plain) = (lit_by(true), lit_by(false));
    let brightest = plain.pixels.iter().map(|p| p[0]).fold(0.0f32, f32::max);
    assert!(brightest > 0.01, "the plain lamp lights the ground: {brightest}");
    for (i, (a, b)) in textured.pixels.iter().zip(&plain.pixels).enumerate() {
        for c in 0..3 {
            assert!(
                (a[c] - b[c]).abs() <= 1e-3 * b[c].max(1e-3),
                "pixel {i} channel {c}: textured {}, plain {}",
                a[c],
                b[c]
            );
        }
    }
    gpu.finish().unwrap();
}

/// Alpha-masking cuts an emitter out as it cuts any surface: a lamp whose base-colour texture is clear over its
/// right half lights the ground as a lamp of its left half alone does. Light samples are spread over the whole
/// triangle pair (chosen by power), so those that land on the clear half must bring nothing — rays pass there —
/// or the masked lamp would shine about twice as bright. The mask read through TEXCOORD_1 (TEXCOORD_0 then
/// sending every lookup to the clear texel) lights the ground exactly alike.
#[test]
fn alpha_masked_emitters_light_the_ground_only_from_what_they_cover() {
    use strata::scene::{AlphaMode, TextureRef};
    let gpu = GpuTest::new();
    let (size, half_height) = (48u32, 1.5);
    let lit_by = |mask_uv_set: Option<u32>| {
        let mut scene = ground_scene();
        let lamp = emitter(&mut scene, 3.0);
        let (p, m) = if let Some(tex_coord) = mask_uv_set {
            let texture = half_clear_texture(&mut scene);
            let material = &mut scene.materials[lamp];
            material.base_color_texture = Some(TextureRef { texture, tex_coord, transform: None });
            material.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
            let (mut p, m) = plane_at(Vec2::new(1.0, 0.5), Vec3::new(0.0, 2.0, 0.0), true, lamp);
            if tex_coord == 1 {
                let clear = vec![Vec2::new(0.75, 0.5); p.uvs.len()];
                p.uvs1 = std::mem::replace(&mut p.uvs, clear);
            }
            (p, m)
        } else {
            plane_at(Vec2::new(0.5, 0.5), Vec3::new(-0.25, 2.0, 0.0), true, lamp)
        };
        place(&mut scene, "lamp", p, m);
        scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, half_height));
        render(gpu.device(), &scene, &settings(size, size, 64, SamplerKind::Jittered)).linear
    };
    let (masked, masked_on_uv1, half) = (lit_by(Some(0)), lit_by(Some(1)), lit_by(None));
    assert!(masked == masked_on_uv1, "the mask on TEXCOORD_1 does not act as on TEXCOORD_0");
    // Means over 8×8-pixel blocks: 4,096 light samples each.
    let blocks = |f: &strata::output::Frame| -> Vec<f32> {
        let n = size / 8;
        (0..n * n)
            .map(|b| {
                let (bx, by) = (b % n * 8, b / n * 8);
                (0..64).map(|i| f.pixel(bx + i % 8, by + i / 8)[0]).sum::<f32>() / 64.0
            })
            .collect()
    };
    let (masked, half) = (blocks(&masked), blocks(&half));
    let (total_masked, total_half) = (masked.iter().sum::<f32>(), half.iter().sum::<f32>());
    assert!(total_half > 0.0, "the half lamp lights the ground");
    assert!(
        (total_masked / total_half - 1.0).abs() < 0.02,
        "the masked lamp brings {total_masked}, the half lamp {total_half} (ratio {})",
        total_masked / total_half
    );
    let brightest = half.iter().copied().fold(0.0f32, f32::max);
    for (i, (a, b)) in masked.iter().zip(&half).enumerate().filter(|(_, (_, b))| **b > 0.1 * brightest) {
        assert!((a / b - 1.0).abs() < 0.05, "block {i}: masked lamp {a}, half lamp {b}");
    }
    gpu.finish().unwrap();
}

/// KHR_materials_specular's colour tints a dielectric's reflectance at normal incidence, F0 = min(F0(ior) ×
/// colour, 1) × factor: a black, smooth dielectric seen straight down mirrors a white sky as F0 per channel
/// (Schlick at v·h = 1). The red channel's F0 is clamped to 1 in the second case.
#[test]
fn the_specular_colour_tints_a_dielectric_mirror_by_its_clamped_f0() {
    use strata::scene::Material;
    let gpu = GpuTest::new();
    let f0_ior = ((1.5f32 - 1.0) / (1.5 + 1.0)).powi(2);
    for (colour, factor) in [(Vec3::new(1.0, 0.5, 0.25), 1.0), (Vec3::new(30.0, 1.0, 0.5), 0.8)] {
        let mut scene = Scene::default();
        scene.materials.push(Material {
            name: "tinted glaze".into(),
            base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
            metallic: 0.0,
            roughness: 0.0,
            specular: factor,
            specular_color: colour,
            ..Default::default()
        });
        let (p, m) = plane_at(Vec2::new(20.0, 20.0), Vec3::ZERO, false, 0);
        place(&mut scene, "glaze", p, m);
        scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 1.0));
        let sky = RenderSettings { background: Vec3::ONE, ..settings(32, 32, 16, SamplerKind::Jittered) };
        let frame = render(gpu.device(), &scene, &sky).linear;
        let f0 = (Vec3::splat(f0_ior) * colour).min(Vec3::ONE) * factor;
        let mean = frame.pixels.iter().map(|p| Vec3::new(p[0], p[1], p[2])).sum::<Vec3>() / frame.pixels.len() as f32;
        // Russian roulette keeps a weak reflection's path with probability 4·F0 (weighted up): a mean over 16,384
        // samples, within 6% (3σ for the weakest, F0 = 0.04).
        assert!(
            ((mean - f0) / f0).abs().max_element() < 0.06,
            "colour {colour}, factor {factor}: mean reflection {mean}, F0 {f0}"
        );
        // Each surviving path carries F per channel, so every lit pixel shows F0's ratios exactly.
        for p in frame.pixels.iter().filter(|p| p[0] > 0.0) {
            let got = Vec3::new(p[0], p[1], p[2]) / p[0];
            assert!((got - f0 / f0.x).abs().max_element() < 2e-3, "colour {colour}: pixel ratios {got}, F0 {f0}");
        }
    }
    gpu.finish().unwrap();
}

/// glTF's BRDF mixes the dielectric and the metal by metalness (glTF 2.0 Appendix B), so a partial metal lit
/// directly is the mix of the two, sample for sample: the light points are the same, and without transmission
/// neither the MIS weights nor the lobe choice depend on metalness. (The dielectric's base layer keeps
/// 1 − F_dielectric of the light, not 1 − F of the mixed material.) Metalness 0.2 = 51/255 passes the G-buffer's
/// 8-bit channel exactly.
#[test]
fn direct_light_is_linear_in_metalness() {
    use strata::render::frame::{render_frame, FrameOptions};
    use strata::render::SceneOnGpu;
    let gpu = GpuTest::new();
    let lit = |metallic: f32| {
        let mut scene = shadow_scene(LightShape::Quad { size: Vec2::splat(1.0) }, 10.0, false);
        let ground = &mut scene.materials[0];
        ground.base_color = glam::Vec4::new(0.9, 0.6, 0.3, 1.0);
        (ground.metallic, ground.roughness, ground.specular) = (metallic, 0.4, 1.0);
        scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 3.0));
        let on_gpu = SceneOnGpu::upload(gpu.device(), &scene).unwrap();
        let direct_only = RenderSettings { bounces: 0, ..settings(48, 48, 4, SamplerKind::Jittered) };
        render_frame(gpu.device(), &scene, &on_gpu, &direct_only, &FrameOptions::default(), &mut |_, _| true)
            .unwrap()
            .linear
    };
    let t = 51.0 / 255.0;
    let (dielectric, partial, metal) = (lit(0.0), lit(t), lit(1.0));
    let brightest = metal.pixels.iter().chain(&dielectric.pixels).map(|p| p[0]).fold(0.0f32, f32::max);
    let mut differing = 0;
    for (i, ((d, p), m)) in dielectric.pixels.iter().zip(&partial.pixels).zip(&metal.pixels).enumerate() {
        for c in 0..3 {
            let mix = d[c] + (m[c] - d[c]) * t;
            assert!(
                (p[c] - mix).abs() <= 1e-4 * brightest,
                "pixel {i} channel {c}: metalness {t}: {}, mix {mix}",
                p[c]
            );
        }
        differing += usize::from((d[0] - m[0]).abs() > 0.05 * brightest);
    }
    assert!(differing > 500, "the metal and the dielectric must look different: {differing} pixels do");
    gpu.finish().unwrap();
}

/// What tilts the mirrored ceiling's normal into stripes across x.
#[derive(Clone, Copy, Debug)]
enum CeilingDetail {
    /// Sine bumps, period 0.5 m, slopes up to 0.2.
    Bump,
    /// A 16×1 normal texture of alternating texels tilted ±30° about z, linearly filtered: period 0.5 m.
    NormalTexture,
    /// A 48×48 grey base-colour texture tiled 8 times each way (KHR_texture_transform scale 8: 96 texels per
    /// metre, 3 per pixel of the 64-pixel views): stripes across x, 24 texels light and 24 dark (period 0.5 m), each
    /// texel a checker square darker or lighter than its neighbours. Seen at 3 texels per pixel only the trilinear
    /// mip levels (about 1.6) show the stripes without the checker; level 0 shows the checker as noise.
    MinifiedTexture,
    /// MinifiedTexture's tiling for an alpha-masked (cutoff 0.5) grey texture whose every 2×2 block of texels has
    /// one clear: from mip level 1 on its alpha is 0.75 everywhere, so a view at 3 texels per pixel covers every
    /// pixel; read at level 0, the clear texels are holes.
    MinifiedCutout,
}

/// A Lambertian ceiling at y = 2 facing down, 4 m square, with `detail` and a vertex colour, lit from the side by a
/// point light at z = 0; seen either in a mirror at y = 0 by a camera looking down from y = 1, or directly by a
/// camera at y = 0 looking up. Both cameras are orthographic and see the same 2 m square of ceiling, image x along
/// world x; the mirror turns image y from +z to −z, which the scene's symmetry in z makes no difference to, sample
/// for sample.
fn mirrored_ceiling(detail: CeilingDetail, through_mirror: bool) -> Scene {
    use strata::scene::{BumpDerivative, BumpMap, NoiseKind, Sampler, Texture, TextureImage, TextureRef};
    let mut scene = Scene::default();
    let ceiling = lambertian(&mut scene, 0.8);
    match detail {
        CeilingDetail::Bump => {
            scene.materials[ceiling].bump = Some(BumpMap {
                kind: NoiseKind::Sine,
                amplitude: 0.016,
                frequency: 8.0,
                derivative: BumpDerivative::Analytic,
                ..Default::default()
            })
        }
        CeilingDetail::NormalTexture => {
            // Tangent-space (±sin 30°, 0, cos 30°), encoded as (n + 1) / 2 (glTF 2.0 §3.9.3).
            let rgba8 = (0..16).flat_map(|i| if i % 2 == 0 { [191u8, 128, 238, 255] } else { [64, 128, 238, 255] });
            scene.images = vec![TextureImage { name: "tilts".into(), width: 16, height: 1, rgba8: rgba8.collect() }];
            scene.textures = vec![Texture { name: "tilts".into(), image: 0, sampler: Sampler::default(), srgb: false }];
            scene.materials[ceiling].normal_texture = Some(TextureRef { texture: 0, tex_coord: 0, transform: None });
        }
        CeilingDetail::MinifiedTexture => {
            let grey = |i: u32, j: u32| match ((i / 24) % 2 == 0, (i + j) % 2 == 0) {
                (true, true) => 250u8,
                (true, false) => 150,
                (false, true) => 110,
                (false, false) => 20,
            };
            tile_base_colour(&mut scene, ceiling, "stripes", |i, j| [grey(i, j), grey(i, j), grey(i, j), 255]);
        }
        CeilingDetail::MinifiedCutout => {
            let alpha = |i: u32, j: u32| if i % 2 == 0 && j % 2 == 0 { 0u8 } else { 255 };
            tile_base_colour(&mut scene, ceiling, "holes", |i, j| [200, 200, 200, alpha(i, j)]);
            scene.materials[ceiling].alpha_mode = strata::scene::AlphaMode::Mask { cutoff: 0.5 };
        }
    }
    let (mut p, m) = plane_at(Vec2::splat(4.0), Vec3::new(0.0, 2.0, 0.0), true, ceiling);
    p.colors = vec![glam::Vec4::new(1.0, 0.5, 0.25, 1.0); p.positions.len()];
    place(&mut scene, "ceiling", p, m);
    scene.lights.push(Light {
        name: "side light".into(),
        shape: LightShape::Point { radius: 0.0 },
        emission: Vec3::splat(20.0),
        world_from_light: Mat4::from_translation(Vec3::new(3.0, 1.0, 0.0)),
        node: None,
        range: 0.0,
    });
    if through_mirror {
        let mirror = metal(&mut scene, 0.0);
        let (p, m) = plane_at(Vec2::splat(20.0), Vec3::ZERO, false, mirror);
        place(&mut scene, "mirror", p, m);
        scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 1.0));
    } else {
        scene.camera = Some(Camera {
            name: "ortho up".into(),
            world_from_camera: look_at(Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0), Vec3::Z),
            projection: Projection::Orthographic { xmag: 1.0, ymag: 1.0, znear: 0.01, zfar: 100.0 },
            lens: Lens::PINHOLE,
        });
    }
    scene
}

/// Gives `material` a 48×48 sRGB base-colour texture of `texel(i, j)`, tiled 8 times each way (KHR_texture_transform
/// scale 8): on the 4 m ceiling, 96 texels per metre.
fn tile_base_colour(scene: &mut Scene, material: usize, name: &str, texel: impl Fn(u32, u32) -> [u8; 4]) {
    use strata::scene::{Sampler, Texture, TextureImage, TextureRef, UvTransform};
    let rgba8 = (0..48).flat_map(|j| (0..48).map(move |i| (i, j))).flat_map(|(i, j)| texel(i, j)).collect();
    scene.images.push(TextureImage { name: name.into(), width: 48, height: 48, rgba8 });
    let image = scene.images.len() - 1;
    scene.textures.push(Texture { name: name.into(), image, sampler: Sampler::default(), srgb: true });
    let tiled = UvTransform { offset: Vec2::ZERO, rotation: 0.0, scale: Vec2::splat(8.0) };
    let texture = scene.textures.len() - 1;
    scene.materials[material].base_color_texture = Some(TextureRef { texture, tex_coord: 0, transform: Some(tiled) });
}

/// Gloss rays shade what they hit as the raster pass shades what the camera sees: a white mirror (metal,
/// roughness 0: F = 1) shows a bump-mapped or normal-textured, vertex-coloured surface as a direct view of it does,
/// pixel for pixel.
#[test]
fn a_mirror_shows_bumps_normal_textures_and_vertex_colours_as_a_direct_view_does() {
    let gpu = GpuTest::new();
    for detail in [CeilingDetail::Bump, CeilingDetail::NormalTexture] {
        mirror_matches_direct_view(&gpu, detail);
    }
    gpu.finish().unwrap();
}

/// Rays read textures through the mip level of their ray cone (Ray Tracing Gems 2019, ch. 20): a mirror shows a
/// minified texture filtered as a direct view of it is, not aliased, and so do a clear pane of glass in front of it
/// (the cone goes on through refraction) and the reference mode's primary rays; for orthographic cameras (the cone
/// keeps the pixel's width) and perspective ones (it spreads by the pixel's angle). One sample per pixel, so
/// nothing but the level of detail filters the texture.
#[test]
fn mirrors_and_primary_rays_filter_a_minified_texture_as_the_raster_pass_does() {
    let gpu = GpuTest::new();
    let s = settings(64, 64, 1, SamplerKind::Jittered);
    let traced = RenderSettings { primary: Primary::Rays, ..s.clone() };
    for perspective in [false, true] {
        let scene = |through_mirror| {
            let mut scene = mirrored_ceiling(CeilingDetail::MinifiedTexture, through_mirror);
            if perspective {
                // From 1 m below the mirror's plane straight up, or 1 m above the mirror straight down: either way 3 m
                // from the ceiling, seeing the same 2 m square at its centre.
                let camera = scene.camera.as_mut().unwrap();
                camera.world_from_camera = match through_mirror {
                    false => look_at(Vec3::NEG_Y, Vec3::new(0.0, 2.0, 0.0), Vec3::Z),
                    true => look_at(Vec3::Y, Vec3::ZERO, Vec3::NEG_Z),
                };
                let yfov = 2.0 * (1.0f32 / 3.0).atan();
                camera.projection = Projection::Perspective { yfov, znear: 0.01, zfar: Some(100.0) };
            }
            scene
        };
        let direct = render(gpu.device(), &scene(false), &s);
        let mirrored = render(gpu.device(), &scene(true), &s);
        let direct_traced = render(gpu.device(), &scene(false), &traced);
        let mut glazed = scene(false);
        add_clear_pane(&mut glazed);
        let through_glass = render(gpu.device(), &glazed, &s);
        assert_filters_alike(&direct, &mirrored, true, &format!("mirror, perspective {perspective}"));
        assert_filters_alike(&direct, &through_glass, true, &format!("glass, perspective {perspective}"));
        // Each traced pixel has its own sub-pixel point where the raster pass shifts the whole image by one, so at
        // one sample per pixel their columns differ across the edges, by the pixel's width: the inside only.
        assert_filters_alike(&direct, &direct_traced, false, &format!("primary rays, perspective {perspective}"));
    }
    gpu.finish().unwrap();
}

/// Alpha tests along rays read the cut-out's texture through the ray's cone too: a minified cut-out covers a mirror's
/// pixels and primary rays' as it covers the raster pass's. Read at level 0, as before ray cones, 551 of the mirror's
/// 4,096 pixels saw through it.
#[test]
fn mirrors_and_primary_rays_see_a_minified_cutout_as_covered_as_the_raster_pass_does() {
    let gpu = GpuTest::new();
    let raster = settings(64, 64, 1, SamplerKind::Jittered);
    let traced = RenderSettings { primary: Primary::Rays, ..raster.clone() };
    for (what, through_mirror, s) in
        [("raster", false, &raster), ("mirror", true, &raster), ("primary rays", false, &traced)]
    {
        let image = render(gpu.device(), &mirrored_ceiling(CeilingDetail::MinifiedCutout, through_mirror), s).linear;
        let reds: Vec<f32> = image.pixels.iter().map(|p| p[0]).collect();
        let mean = reds.iter().sum::<f32>() / reds.len() as f32;
        // The side light leaves the far side of the ceiling at about a third of the mean; a hole shows the black sky.
        let holes = reds.iter().filter(|&&r| r < 0.1 * mean).count();
        eprintln!("{what}: {holes} of {} pixels see through the cut-out", reds.len());
        assert!(holes <= reds.len() / 200, "{what}: {holes} pixels see through a cut-out its mip levels cover");
    }
    gpu.finish().unwrap();
}

/// A smooth glass pane of IOR 1 (it refracts straight on and reflects nothing) between the direct view's camera
/// and the ceiling, at y = 1.2: wide enough for either camera's view, and clear of the shadow rays from the ceiling
/// to the side light, which cross y = 1.2 beyond x = 2.2.
fn add_clear_pane(scene: &mut Scene) {
    scene.materials.push(strata::scene::Material {
        name: "clear glass".into(),
        base_color: glam::Vec4::ONE,
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.0,
        ..Default::default()
    });
    let (p, m) = plane_at(Vec2::splat(2.2), Vec3::new(0.0, 1.2, 0.0), true, scene.materials.len() - 1);
    place(scene, "pane", p, m);
}

/// `other` shows CeilingDetail::MinifiedTexture's stripes filtered as `direct`, the raster pass's view, does. With
/// `columns`, also across the stripes' edges: `other` must sample each image row at the raster pass's sub-pixel point.
fn assert_filters_alike(direct: &RenderedFrame, other: &RenderedFrame, columns: bool, what: &str) {
    let (width, height) = (direct.linear.width, direct.linear.height);
    let profile = column_profile(direct, 0..height);
    let (lo, hi, mean) = range_and_mean(&profile);
    assert!((hi - lo) / mean > 0.5, "{what}: the direct view shows no stripes: {profile:?}");
    // Inside the stripes, where the direct view's columns change by under a twentieth of the stripes' swing over
    // two pixels either way: there a shift under a pixel (the mirror's roughness-0 GGX core, α = 10⁻³; primary
    // rays' own sub-pixel points) changes nothing, and only filtering does.
    let flat: Vec<u32> = (2..width - 2)
        .filter(|&x| {
            let x = x as usize;
            profile[x - 2..=x + 2].windows(2).all(|w| (w[1] - w[0]).abs() < 0.05 * (hi - lo))
        })
        .collect();
    assert!(flat.len() > width as usize / 3, "{what}: too few columns inside the stripes: {flat:?}");
    let (d, o) = (&direct.linear, &other.linear);
    let mut errors: Vec<f32> = flat
        .iter()
        .flat_map(|&x| (0..height).map(move |y| (x, y)))
        .map(|(x, y)| (0..3).map(|c| (o.pixel(x, y)[c] - d.pixel(x, y)[c]).abs() / mean).fold(0.0, f32::max))
        .collect();
    errors.sort_by(f32::total_cmp);
    let (median, p99) = (errors[errors.len() / 2], errors[errors.len() * 99 / 100]);
    // Across the stripes' edges, where those shifts do show, compare whole columns (64 rows average them out): a
    // level too high blurs the edges.
    let profile_error =
        profile.iter().zip(&column_profile(other, 0..height)).map(|(d, o)| (o - d).abs()).fold(0.0f32, f32::max)
            / (hi - lo);
    eprintln!(
        "{what}: against the raster view, inside the stripes in mean pixels median {median:.4} and 99th percentile \
         {p99:.4}; columns, in the stripes' swing, {profile_error:.4}"
    );
    // Measured for the orthographic mirror: median 0.0035, 99th percentile 0.045, columns 0.031 (perspective: 0.0034,
    // 0.043, 0.024); through the glass 0.0036, 0.010, 0.003 to 0.007; primary rays 0.0059 and 0.098, their sub-pixel
    // points moving the side light's gradient. Reading level 0 gives 0.058 and 1.01; one level too high gives 0.10
    // on the columns and passes inside the stripes (every level from 1 to 3 is flat there); dropping the cone's
    // width at the visible vertex gives 0.043 and 0.16 through the perspective glass (1.9 levels low there; 0.6 in
    // the mirror, which passes). Half a level either way is within the noise.
    assert!(
        median < 0.02 && p99 < 0.2,
        "{what}: the texture is less filtered than in the raster view: median {median}, 99th percentile {p99}"
    );
    assert!(
        !columns || profile_error < 0.06,
        "{what}: the stripes are blurred more than in the raster view: {profile_error}"
    );
}

/// A column profile's least and greatest values and its mean.
fn range_and_mean(profile: &[f32]) -> (f32, f32, f32) {
    let (lo, hi) = profile.iter().fold((f32::MAX, 0.0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    (lo, hi, profile.iter().sum::<f32>() / profile.len() as f32)
}

fn mirror_matches_direct_view(gpu: &GpuTest, detail: CeilingDetail) {
    let (width, height) = (64u32, 64u32);
    let s = settings(width, height, 16, SamplerKind::Jittered);
    let direct_frame = render(gpu.device(), &mirrored_ceiling(detail, false), &s);
    let mirrored = render(gpu.device(), &mirrored_ceiling(detail, true), &s).linear;
    // The detail makes stripes in the direct view (without it the ceiling would shade smoothly); `steepest` is their
    // largest change across one pixel, in mean pixels.
    let profile = column_profile(&direct_frame, 0..height);
    let (lo, hi, mean) = range_and_mean(&profile);
    let direct = direct_frame.linear;
    assert!((hi - lo) / mean > 0.3, "{detail:?}: the direct view shows no stripes: {profile:?}");
    let steepest = profile.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0f32, f32::max) / mean;
    // Each mirror pixel against the same pixel seen directly, in units of the mean pixel's red.
    let unit = mean;
    let (mut errors, mut lit) = (Vec::new(), 0);
    for y in 0..height {
        for x in 0..width {
            let (d, m) = (direct.pixel(x, y), mirrored.pixel(x, y));
            errors.push((0..3).map(|c| (m[c] - d[c]).abs() / unit).fold(0.0f32, f32::max));
            // The vertex colour tints what the mirror shows. Pixels under a tenth of the mean are left out: there the
            // mirror's own glint of the point light (its GGX tail, white, a few 10⁻⁶) shows in the ratios.
            if m[0] > 0.1 * unit {
                lit += 1;
                let tint_kept = (m[1] / m[0] - 0.5).abs() < 1e-3 && (m[2] / m[0] - 0.25).abs() < 1e-3;
                assert!(tint_kept, "{detail:?} ({x}, {y}): {m:?}");
            }
        }
    }
    assert!(lit > (width * height / 2) as usize, "{detail:?}: only {lit} lit pixels");
    errors.sort_by(f32::total_cmp);
    let (median, p99, worst) = (errors[errors.len() / 2], errors[errors.len() * 99 / 100], errors[errors.len() - 1]);
    eprintln!("{detail:?}: mirror vs direct view, in mean pixels: median {median:.4}, 99th percentile {p99:.4}, worst {worst:.4}");
    // Roughness 0 is GGX with α = 10⁻³ (ggx_alpha): its core moves a reflected hit by a fraction of a pixel and its
    // tails now and then send a sample pixels aside, so the images part where the stripes are steep. Measured, for
    // both details: the steepest step times 0.013 px at the median, 0.09 px at the 99th percentile. Without the
    // detail at the mirror's hits the stripes would be gone, errors of the order of their whole swing.
    assert!(
        median < 0.03 * steepest && p99 < 0.15 * steepest,
        "{detail:?}: the mirror's image strays from the direct view: median {median}, 99th percentile {p99}, \
         steepest step {steepest}"
    );
}

/// glTF BLEND is stochastic coverage (material.glsl's alpha_test_passes): an unlit quad of alpha 0.3 over a black
/// background shows 0.3 × its colour and covers 0.3 of each pixel on average, in both primary modes; a BLEND veil
/// of alpha 0.3 passes 0.7 of a directional light to the floor in its shadow. Tolerances: 5 standard errors of
/// the Bernoulli coverage over the pixels and samples, σ = sqrt(a(1 − a) / (P·N)) of the full value.
#[test]
fn blend_is_stochastic_coverage_that_averages_to_the_blend() {
    use strata::scene::{AlphaMode, Material};
    let gpu = GpuTest::new();
    let a = 0.3f32;
    let colour = Vec3::new(0.8, 0.4, 0.2);
    let (size, spp) = (16u32, 64u32);
    let sigma = |full: f32| full * (a * (1.0 - a) / (size * size * spp) as f32).sqrt();
    let blend = |name: &str, rgb: Vec3, unlit: bool| Material {
        name: name.into(),
        base_color: rgb.extend(a),
        alpha_mode: AlphaMode::Blend,
        unlit,
        ..Default::default()
    };
    let frame_settings =
        |primary| RenderSettings { primary, ..optics::settings(size, size, spp, SamplerKind::MultiJittered) };
    let mean = |frame: &RenderedFrame, channel: usize| {
        frame.linear.pixels.iter().map(|p| p[channel]).sum::<f32>() / frame.linear.pixels.len() as f32
    };

    let mut glaze = Scene::default();
    glaze.materials.push(blend("glaze", colour, true));
    let (p, m) = plane_at(Vec2::splat(4.0), Vec3::ZERO, false, 0);
    place(&mut glaze, "glaze", p, m);
    glaze.camera = Some(optics::ortho_down(Vec3::ZERO, 1.0, 0.5));
    for primary in [Primary::Raster, Primary::Rays] {
        let frame = render(gpu.device(), &glaze, &frame_settings(primary));
        let (red, blue, coverage) = (mean(&frame, 0), mean(&frame, 2), mean(&frame, 3));
        eprintln!(
            "{primary:?}: red {red:.4} (expected {:.4} ± {:.4}), coverage {coverage:.4}",
            a * colour.x,
            sigma(colour.x)
        );
        assert!((red - a * colour.x).abs() < 5.0 * sigma(colour.x), "{primary:?}: red {red}, not {}", a * colour.x);
        assert!((blue - a * colour.z).abs() < 5.0 * sigma(colour.z), "{primary:?}: blue {blue}, not {}", a * colour.z);
        assert!((coverage - a).abs() < 5.0 * sigma(1.0), "{primary:?}: coverage {coverage}, not {a}");
    }

    // A floor under a sun travelling down and towards +x at 45°: a 1 m veil 1 m up over the origin shadows
    // x in [0.5, 1.5]; the camera, 0.5 m up, sees x in [0.7, 1.3] and not the veil.
    let floor = |veil: bool| {
        let mut scene = Scene::default();
        let ground = lambertian(&mut scene, 0.5);
        let (p, m) = plane_at(Vec2::splat(8.0), Vec3::ZERO, false, ground);
        place(&mut scene, "floor", p, m);
        if veil {
            scene.materials.push(blend("veil", Vec3::splat(0.5), false));
            let (p, m) = plane_at(Vec2::ONE, Vec3::Y, false, scene.materials.len() - 1);
            place(&mut scene, "veil", p, m);
        }
        let travel = Vec3::new(1.0, -1.0, 0.0).normalize();
        scene.lights.push(Light {
            name: "sun".into(),
            shape: LightShape::Directional,
            emission: Vec3::splat(2.0),
            world_from_light: look_at(Vec3::Y, Vec3::Y + travel, Vec3::Y),
            node: None,
            range: 0.0,
        });
        scene.camera = Some(optics::ortho_down(Vec3::X, 0.5, 0.3));
        scene
    };
    let lit = mean(&render(gpu.device(), &floor(false), &frame_settings(Primary::Raster)), 0);
    let shadowed = mean(&render(gpu.device(), &floor(true), &frame_settings(Primary::Raster)), 0);
    let passed = shadowed / lit;
    eprintln!("the veil passes {passed:.4} of the sun (expected {:.4} ± {:.4})", 1.0 - a, sigma(1.0));
    assert!(lit > 0.05, "the floor is lit: {lit}");
    assert!((passed - (1.0 - a)).abs() < 5.0 * sigma(1.0), "the veil passes {passed} of the sun, not {}", 1.0 - a);
    gpu.finish().unwrap();
}
