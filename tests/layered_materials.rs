//! The layered glTF materials, KHR_materials_clearcoat and KHR_materials_sheen, and KHR_materials_diffuse_transmission
//! against what they must equal in a white furnace (a sphere in a uniform environment of radiance 1): over a black base each layer reflects its own
//! directional albedo at each pixel's view cosine (the CPU twins' integrals, math::ggx and math::sheen), and over a
//! white base the layers and the base together reflect exactly what arrives (albedo scaling); the G-buffer's visible
//! surface, met again by a short ray, shades as the reference mode's primary rays do (tests/estimators.rs, with the
//! agreement of light sampling, BSDF sampling and MIS on layered floors); a diffusely transmitting sphere returns 1
//! and a sheet lit from below shows its transmitted share; and the glTF extensions load, with their textures, or fail
//! naming the material, the extension and the property. Every GPU test runs under the validation layer.
use crate::common;

use common::scenes::*;
use common::GpuTest;
use glam::{Vec3, Vec4};
use strata::render::frame::{render_frame, DirectLight, FrameOptions, RenderedFrame};
use strata::scene::environment::Environment;
use strata::scene::settings::{RenderSettings, SamplerKind, Trace};
use strata::scene::{Anisotropy, Clearcoat, DiffuseTransmission, Iridescence, Material, Scene, Sheen};

/// A unit sphere at the origin, seen from this far with a 30° vertical field of view (the grazing silhouette in view).
const DISTANCE: f32 = 5.0;
const FOV_DEGREES: f32 = 30.0;

/// A base that reflects nothing (no diffuse, no specular), or everything diffusely (white Lambert, no specular).
fn base(white: bool) -> Material {
    let albedo = if white { 1.0 } else { 0.0 };
    Material {
        name: format!("{} base", if white { "white" } else { "black" }),
        base_color: Vec4::new(albedo, albedo, albedo, 1.0),
        metallic: 0.0,
        roughness: 0.5,
        specular: 0.0,
        ..Default::default()
    }
}

fn furnace(material: Material) -> Scene {
    let mut scene = Scene::default();
    scene.materials.push(material);
    strata::scene::library::add_sphere_in_view(&mut scene, 0, DISTANCE, FOV_DEGREES);
    scene.environment = Some(Environment::uniform(Vec3::ONE));
    scene
}

/// The view cosine n·v on the sphere along the ray through image point (x, y), in pixels (the camera at
/// (0, 0, DISTANCE) looking down −z, as add_sphere_in_view places it); None off the sphere.
fn view_cosine(x: f32, y: f32, size: u32) -> Option<f32> {
    let t = (FOV_DEGREES.to_radians() / 2.0).tan();
    let px = (2.0 * x / size as f32 - 1.0) * t;
    let py = (1.0 - 2.0 * y / size as f32) * t;
    let d = Vec3::new(px, py, -1.0).normalize();
    let o = Vec3::new(0.0, 0.0, DISTANCE);
    let b = o.dot(d);
    let disc = b * b - (o.length_squared() - 1.0);
    if disc <= 0.0 {
        return None;
    }
    let hit = o + d * (-b - disc.sqrt());
    Some(-hit.dot(d))
}

/// What a pixel wholly on the sphere shows of `f(μ)`: its mean over the pixel's box (the camera's jitter), on an
/// 8 × 8 grid; None where part of the pixel misses the sphere. Near the silhouette one pixel spans view cosines 0.2
/// apart, over which an albedo curves.
fn pixel_mean(x: u32, y: u32, size: u32, f: &impl Fn(f32) -> f32) -> Option<(f32, f32)> {
    let (mut sum, mut mu_sum) = (0.0, 0.0);
    for k in 0..64 {
        let (sx, sy) = (x as f32 + ((k % 8) as f32 + 0.5) / 8.0, y as f32 + ((k / 8) as f32 + 0.5) / 8.0);
        let mu = view_cosine(sx, sy, size)?;
        sum += f(mu);
        mu_sum += mu;
    }
    Some((sum / 64.0, mu_sum / 64.0))
}

/// Over the fully covered pixels whose mean view cosine lies in [lo, hi): the mean of (pixel's largest channel −
/// its mean of `expected(μ)`), its standard error, and the largest pixel.
fn band_error(frame: &RenderedFrame, (lo, hi): (f32, f32), expected: impl Fn(f32) -> f32) -> (f64, f64, f64) {
    let size = frame.linear.width;
    let mut diffs = Vec::new();
    let mut max = 0.0f64;
    for (i, p) in frame.linear.pixels.iter().enumerate() {
        let (x, y) = (i as u32 % size, i as u32 / size);
        let Some((want, mu)) = pixel_mean(x, y, size, &expected) else { continue };
        if p[3] < 1.0 || mu < lo || mu >= hi {
            continue;
        }
        let value = p[0].max(p[1]).max(p[2]);
        diffs.push(f64::from(value - want));
        max = max.max(f64::from(value));
    }
    let n = diffs.len() as f64;
    assert!(n > 30.0, "only {n} pixels with view cosines in [{lo}, {hi})");
    let mean = diffs.iter().sum::<f64>() / n;
    let sd = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    (mean, sd / n.sqrt(), max)
}

const BANDS: [(f32, f32); 3] = [(0.75, 1.0), (0.35, 0.75), (0.12, 0.35)];

/// The furnace frames: paths with diffuse interreflection, traced one way (ray queries), so that every layered test
/// shares one pipeline to compile; the anisotropic highlight's test traces both ways and holds them to the same bits
/// (`both_ways`), on the smallest layered pipeline.
fn furnace_settings(size: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        indirect: true,
        bounces: 8,
        trace: Trace::Query,
        ..settings(size, size, spp, SamplerKind::MultiJittered)
    }
}

/// `s` traced every way the device can (common::scenes::render then requires the same bits from each).
fn both_ways(s: RenderSettings) -> RenderSettings {
    RenderSettings { trace: Trace::Auto, ..s }
}

/// Checks every band of `frame` against `expected(μ)`: within four standard errors of its mean plus `slack` (the
/// tables' bilinear interpolation and the sphere's facets), and no pixel above `max_pixel`.
fn assert_bands(frame: &RenderedFrame, what: &str, slack: f64, max_pixel: f64, expected: impl Fn(f32) -> f32) {
    for band in BANDS {
        let (mean, se, max) = band_error(frame, band, &expected);
        eprintln!("{what}, view cosines {band:?}: error {mean:+.4} ± {se:.4}, largest pixel {max:.3}");
        assert!(mean.abs() <= 4.0 * se + slack, "{what}, view cosines {band:?}: off by {mean} ± {se}");
        assert!(max <= max_pixel, "{what}, view cosines {band:?}: a pixel of {max}");
    }
}

/// A clear coat over a black base reflects the coat's directional albedo F0·E₁ + (1 − F0)·E₅ (F0 0.04) at each
/// view cosine, through gloss rays and light samples; over a white base the coat and the base under it reflect 1.
#[test]
fn a_clear_coat_reflects_its_albedo_over_black_and_with_a_white_base_exactly_what_arrives() {
    let gpu = GpuTest::new();
    let size = 64u32;
    for roughness in [0.1f32, 0.5] {
        let coat = Clearcoat { factor: 1.0, roughness, ..Default::default() };
        let black = furnace(Material { clearcoat: Some(coat), ..base(false) });
        let frame = render(gpu.device(), &black, &furnace_settings(size, 64));
        let coat_albedo = |mu: f32| {
            let [e1, e5] = strata::math::brdf::lookup(mu, roughness);
            0.04 * e1 + 0.96 * e5
        };
        assert_bands(&frame, &format!("coat {roughness} over black"), 0.004, 1.0, coat_albedo);
        let white = furnace(Material { clearcoat: Some(coat), ..base(true) });
        let frame = render(gpu.device(), &white, &furnace_settings(size, 64));
        assert_bands(&frame, &format!("coat {roughness} over white"), 0.004, 1.2, |_| 1.0);
    }
    gpu.finish().unwrap();
}

/// A white sheen over a black base reflects the Charlie lobe's directional albedo at each view cosine (math::sheen's
/// quadrature, baked into the table that math::brdf::sheen_lookup reads; the GPU's picture of a black base does not
/// read it, as E < 1 at these roughnesses); over a white base the sheen and the base reflect 1.
#[test]
fn a_sheen_reflects_its_albedo_over_black_and_with_a_white_base_exactly_what_arrives() {
    let gpu = GpuTest::new();
    let size = 64u32;
    for roughness in [0.3f32, 0.8] {
        let sheen = Sheen { color: Vec3::ONE, roughness, ..Default::default() };
        let black = furnace(Material { sheen: Some(sheen), ..base(false) });
        let frame = render(gpu.device(), &black, &furnace_settings(size, 64));
        let sheen_albedo = |mu: f32| strata::math::brdf::sheen_lookup(mu, roughness).min(1.0);
        assert_bands(&frame, &format!("sheen {roughness} over black"), 0.004, 1.0, sheen_albedo);
        let white = furnace(Material { sheen: Some(sheen), ..base(true) });
        let frame = render(gpu.device(), &white, &furnace_settings(size, 64));
        assert_bands(&frame, &format!("sheen {roughness} over white"), 0.004, 1.2, |_| 1.0);
    }
    gpu.finish().unwrap();
}

/// KHR_materials_diffuse_transmission in a white furnace: a white sphere whose diffuse lobe passes all or half of
/// itself through the surface still returns exactly what arrives (the light crosses the sphere and leaves by its
/// far side), and a sheet seen from above in a uniform environment shows (1 − t)·albedo + t·colour, the transmitted
/// share lit from below, by light sampling alone and by BSDF sampling alone (rays through the sheet).
#[test]
fn diffuse_transmission_passes_its_share_through_and_makes_no_energy() {
    use strata::scene::library::place;
    let gpu = GpuTest::new();
    for factor in [1.0f32, 0.5] {
        let transmits = DiffuseTransmission { factor, ..Default::default() };
        let sphere = furnace(Material { diffuse_transmission: Some(transmits), ..base(true) });
        let frame = render(gpu.device(), &sphere, &furnace_settings(64, 64));
        // Light reaches the far side's inside only through the near side's sampled directions: noisy pixels (up to
        // 1.8 at 64 spp), so only the bands' means are held to 1.
        assert_bands(&frame, &format!("white sphere transmitting {factor}"), 0.004, f64::INFINITY, |_| 1.0);
    }
    let (albedo, factor, color) = (0.5f32, 0.6f32, Vec3::new(1.0, 0.5, 0.25));
    let mut sheet = Scene::default();
    sheet.materials.push(Material {
        base_color: Vec4::new(albedo, albedo, albedo, 1.0),
        diffuse_transmission: Some(DiffuseTransmission { factor, color, ..Default::default() }),
        ..base(true)
    });
    let (plane, at) = plane_at(glam::Vec2::splat(4.0), Vec3::ZERO, false, 0);
    place(&mut sheet, "sheet", plane, at);
    sheet.camera = Some(ortho_down(Vec3::ZERO, 2.0, 0.5));
    sheet.environment = Some(Environment::uniform(Vec3::ONE));
    let want = Vec3::splat((1.0 - factor) * albedo) + factor * color;
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &sheet).expect("upload");
    for direct_light in [DirectLight::LightSampling, DirectLight::BsdfSampling] {
        let s = settings(16, 16, 256, SamplerKind::MultiJittered);
        let options = FrameOptions { direct_light, ..Default::default() };
        let frame = render_frame(gpu.device(), &sheet, &on_gpu, &s, &options, &mut |_, _| true).expect("render");
        let n = frame.linear.pixels.len() as f32;
        let mean = frame.linear.pixels.iter().map(|p| Vec3::from_slice(&p[..3])).sum::<Vec3>() / n;
        let sd = (frame.linear.pixels.iter().map(|p| (Vec3::from_slice(&p[..3]) - mean).powf(2.0)).sum::<Vec3>()
            / (n - 1.0))
            .powf(0.5);
        let tolerance = sd / n.sqrt() * 4.0 + Vec3::splat(0.002);
        eprintln!("sheet, {direct_light:?}: {mean} ± {}, (1 − t)·albedo + t·colour = {want}", sd / n.sqrt());
        assert!(((mean - want).abs() - tolerance).max_element() <= 0.0, "sheet, {direct_light:?}: {mean}, want {want}");
    }
    drop(on_gpu);
    gpu.finish().unwrap();
}

/// KHR_materials_iridescence: a film of no thickness is no film (a glossy dielectric over black seen straight down
/// under a wide light, traced as primary rays), a 300 nm film recolours that reflection by the CPU twin's ratio at
/// normal view (math::iridescence::film_ratio), and a white dielectric under a
/// 400 nm film still reflects exactly what arrives in a white furnace (its diffuse base takes what the film leaves).
#[test]
fn a_thin_film_of_no_thickness_is_no_film_and_a_thicker_one_recolours_as_its_twin_says() {
    use strata::scene::library::place;
    use strata::scene::settings::Primary;
    let gpu = GpuTest::new();
    let mirror = |film: Option<Iridescence>| {
        let mut scene = Scene::default();
        scene.materials.push(Material { roughness: 0.5, specular: 1.0, iridescence: film, ..base(false) });
        let (plane, at) = plane_at(glam::Vec2::splat(4.0), Vec3::ZERO, false, 0);
        place(&mut scene, "mirror", plane, at);
        scene.camera = Some(ortho_down(Vec3::ZERO, 2.0, 0.5));
        // A wide quad light overhead (primary rays do not see it), without an environment: the pipeline is the
        // estimators' layered one (tests/estimators.rs), compiled once for both.
        scene.lights.push(strata::scene::Light {
            name: "sky panel".into(),
            shape: strata::scene::LightShape::Quad { size: glam::Vec2::splat(20.0) },
            emission: Vec3::ONE,
            world_from_light: strata::check::optics::light_down(Vec3::new(0.0, 1.0, 0.0)),
            node: None,
            range: 0.0,
        });
        // Light samples alone (no chain, so no Russian roulette whose survival would follow the film's colour):
        // every sample of the three renders is the same but for the film's factor, so their ratio is the film's.
        // One way to trace (the anisotropic highlight's test holds both to the same bits with layers).
        let s = RenderSettings {
            primary: Primary::Rays,
            bounces: 0,
            trace: Trace::Query,
            ..settings(8, 8, 16, SamplerKind::MultiJittered)
        };
        let frame = render(gpu.device(), &scene, &s);
        frame.linear.pixels.iter().map(|p| Vec3::from_slice(&p[..3])).sum::<Vec3>() / frame.linear.pixels.len() as f32
    };
    let film = |thickness: f32| Some(Iridescence { factor: 1.0, thickness_max: thickness, ..Default::default() });
    let (bare, none, thick) = (mirror(None), mirror(film(0.0)), mirror(film(300.0)));
    eprintln!("bare {bare}, film of 0 nm {none}, of 300 nm {thick}");
    assert!(((none - bare) / bare).abs().max_element() < 1e-5, "a film of no thickness: {none}, none at all: {bare}");
    let want = strata::math::iridescence::film_ratio(1.0, 1.3, 300.0, [0.04; 3]);
    let got = thick / bare;
    for c in 0..3 {
        assert!((f64::from(got[c]) - want[c]).abs() < 0.01 * want[c], "300 nm film: ratio {got}, twin {want:?}");
    }
    let white = Material {
        iridescence: Some(Iridescence { factor: 1.0, ..Default::default() }),
        roughness: 0.3,
        specular: 1.0,
        ..base(true)
    };
    let frame = render(gpu.device(), &furnace(white), &furnace_settings(64, 64));
    assert_bands(&frame, "white dielectric under a 400 nm film", 0.004, 1.3, |_| 1.0);
    gpu.finish().unwrap();
}

/// KHR_materials_anisotropy: a point light's highlight on a glossy metal floor seen straight down is round for an
/// isotropic lobe and stretched along the anisotropy direction for a strong one (the floor's u direction, image x;
/// turned a quarter by the rotation, image y): the highlight's spread along each image axis (the square root of its
/// second moment), light samples alone from a point light, so the only noise is the pixel jitter. A white
/// anisotropic dielectric in a white furnace makes no energy: its diffuse base takes what the isotropic lobe of the
/// same roughness leaves, which reflects at least as much as the stretched one, so it loses at most what separates
/// that lobe from an isotropic one as rough as the stretched axis.
#[test]
fn an_anisotropic_lobe_stretches_its_highlight_along_its_direction_and_makes_no_energy() {
    use strata::scene::library::place;
    use strata::scene::{Light, LightShape};
    let gpu = GpuTest::new();
    let size = 48u32;
    let spread = |anisotropy: Option<Anisotropy>| {
        let mut scene = Scene::default();
        scene.materials.push(Material {
            base_color: Vec4::ONE,
            metallic: 1.0,
            roughness: 0.25,
            anisotropy,
            ..Default::default()
        });
        let (plane, at) = plane_at(glam::Vec2::splat(4.0), Vec3::ZERO, false, 0);
        place(&mut scene, "floor", plane, at);
        scene.camera = Some(ortho_down(Vec3::ZERO, 2.0, 0.8));
        scene.lights.push(Light {
            name: "point".into(),
            shape: LightShape::Point { radius: 0.0 },
            emission: Vec3::splat(1.0),
            world_from_light: glam::Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            node: None,
            range: 0.0,
        });
        // Both ways to trace, which must give the same bits (common::scenes::render): the layers' code is the
        // shading body's, whichever way its rays are traced.
        let s = both_ways(RenderSettings { bounces: 0, ..settings(size, size, 16, SamplerKind::MultiJittered) });
        let frame = render(gpu.device(), &scene, &s);
        let (mut sum, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
        for y in 0..size {
            for x in 0..size {
                let w = f64::from(frame.linear.pixel(x, y)[1]);
                let (dx, dy) = (f64::from(x) + 0.5 - f64::from(size) / 2.0, f64::from(y) + 0.5 - f64::from(size) / 2.0);
                sum += w;
                sx += w * dx * dx;
                sy += w * dy * dy;
            }
        }
        ((sx / sum).sqrt(), (sy / sum).sqrt())
    };
    let (round_x, round_y) = spread(None);
    let along_u = spread(Some(Anisotropy { strength: 0.9, ..Default::default() }));
    let turned =
        spread(Some(Anisotropy { strength: 0.9, rotation: std::f32::consts::FRAC_PI_2, ..Default::default() }));
    eprintln!("highlight spread (x, y) in pixels: isotropic ({round_x:.2}, {round_y:.2}), along u {along_u:.2?}, turned {turned:.2?}");
    assert!((round_x / round_y - 1.0).abs() < 0.05, "an isotropic highlight is round: {round_x} × {round_y}");
    assert!(along_u.0 > 1.5 * along_u.1, "stretched along image x: {along_u:?}");
    assert!(turned.1 > 1.5 * turned.0, "turned a quarter, stretched along image y: {turned:?}");
    assert!((along_u.0 / turned.1 - 1.0).abs() < 0.05, "the same stretch either way: {along_u:?} {turned:?}");

    let white = Material {
        anisotropy: Some(Anisotropy { strength: 0.8, rotation: 0.5, ..Default::default() }),
        roughness: 0.3,
        specular: 1.0,
        ..base(true)
    };
    let frame = render(gpu.device(), &furnace(white), &furnace_settings(64, 64));
    // The loss is at most what separates the isotropic lobe at α from the isotropic lobe as rough as the stretched
    // axis, mix(α, 1, strength²): the stretched lobe reflects between the two.
    let albedo = |mu: f32, roughness: f32| {
        let [e1, e5] = strata::math::brdf::lookup(mu, roughness);
        0.04 * e1 + 0.96 * e5
    };
    let rough_axis = (0.09f32 + 0.91 * 0.64).sqrt();
    let least = |mu: f32| 1.0 - (albedo(mu, 0.3) - albedo(mu, rough_axis));
    for band in BANDS {
        let (above_one, se, _) = band_error(&frame, band, |_| 1.0);
        let (above_least, _, _) = band_error(&frame, band, least);
        eprintln!("white anisotropic dielectric, view cosines {band:?}: {above_one:+.4} ± {se:.4} from 1, {above_least:+.4} from the least");
        assert!(above_one <= 4.0 * se + 0.004, "view cosines {band:?}: {above_one} ± {se} above 1");
        assert!(above_least >= -(4.0 * se + 0.004), "view cosines {band:?}: {above_least} ± {se} below the least");
    }
    gpu.finish().unwrap();
}

/// A 2×1 texture, nearest and clamped: `left` and `right` texels (RGBA8; sRGB where a material reads it as colour).
fn two_texel_texture(scene: &mut Scene, name: &str, left: [u8; 4], right: [u8; 4]) -> strata::scene::TextureRef {
    use strata::scene::{Texture, TextureImage, Wrap};
    scene.images.push(TextureImage { name: name.into(), width: 2, height: 1, rgba8: [left, right].concat() });
    let image = scene.images.len() - 1;
    scene.textures.push(Texture { name: name.into(), image, sampler: nearest_sampler(Wrap::ClampToEdge), srgb: false });
    strata::scene::TextureRef { texture: scene.textures.len() - 1, tex_coord: 0, transform: None }
}

/// Per image column, the mean of each colour channel.
fn column_means(frame: &RenderedFrame) -> Vec<Vec3> {
    let (w, h) = (frame.linear.width, frame.linear.height);
    (0..w).map(|x| (0..h).map(|y| Vec3::from_slice(&frame.linear.pixel(x, y)[..3])).sum::<Vec3>() / h as f32).collect()
}

/// The layers' textures scale their factors: a floor seen straight down in a white furnace, its left half's texels
/// full and its right half's empty. A clear coat over black whose factor texture is 1 | 0 reflects the coat's albedo
/// at normal view on one half and nothing on the other; a white sheen over black whose colour texture is red | blue
/// (sRGB) reflects the sheen's albedo in red on one half and in blue on the other.
#[test]
fn layer_textures_scale_their_factors() {
    use strata::scene::library::place;
    let gpu = GpuTest::new();
    let size = 32u32;
    for layer in ["clearcoat", "sheen"] {
        let mut scene = Scene::default();
        let mut material = base(false);
        let (expected_left, expected_right) = if layer == "clearcoat" {
            let texture = two_texel_texture(&mut scene, "coat", [255, 0, 0, 255], [0, 0, 0, 255]);
            material.clearcoat =
                Some(Clearcoat { factor: 1.0, roughness: 0.2, texture: Some(texture), ..Default::default() });
            let [e1, e5] = strata::math::brdf::lookup(1.0, 0.2);
            (Vec3::splat(0.04 * e1 + 0.96 * e5), Vec3::ZERO)
        } else {
            let texture = two_texel_texture(&mut scene, "sheen colour", [255, 0, 0, 255], [0, 0, 255, 255]);
            scene.textures[texture.texture].srgb = true;
            material.sheen =
                Some(Sheen { color: Vec3::ONE, roughness: 1.0, color_texture: Some(texture), ..Default::default() });
            let e = strata::math::brdf::sheen_lookup(1.0, 1.0);
            (Vec3::new(e, 0.0, 0.0), Vec3::new(0.0, 0.0, e))
        };
        scene.materials.push(material);
        let (floor, at) = plane_at(glam::Vec2::splat(2.0), Vec3::ZERO, false, 0);
        place(&mut scene, "floor", floor, at);
        scene.camera = Some(ortho_down(Vec3::ZERO, 2.0, 0.8));
        scene.environment = Some(Environment::uniform(Vec3::ONE));
        let frame = render(gpu.device(), &scene, &furnace_settings(size, 32));
        let columns = column_means(&frame);
        // The floor's u runs along image x one way or the other: the half nearer u = 0 reads the left texel.
        let (first, second) = (columns[..size as usize / 2 - 1].to_vec(), columns[size as usize / 2 + 1..].to_vec());
        let near = |half: &[Vec3], want: Vec3| {
            half.iter().all(|c| (*c - want).abs().max_element() <= 0.01 + 0.05 * want.max_element())
        };
        let ok = (near(&first, expected_left) && near(&second, expected_right))
            || (near(&first, expected_right) && near(&second, expected_left));
        eprintln!(
            "{layer}: columns {:?} .. {:?}, expected {expected_left} | {expected_right}",
            columns[0],
            columns[size as usize - 1]
        );
        assert!(
            ok,
            "{layer}: columns {columns:?}, expected {expected_left} on one half and {expected_right} on the other"
        );
    }
    gpu.finish().unwrap();
}

/// A 1×1 white PNG as a data URI.
fn png_data_uri() -> String {
    use base64::Engine as _;
    let mut png = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut png);
    image::ImageEncoder::write_image(encoder, &[255u8; 4], 1, 1, image::ExtendedColorType::Rgba8).unwrap();
    format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(png))
}

/// The extensions load from glTF with their factors, textures (UV set, transform, the coat normal's scale) and the
/// sheen colour texture marked sRGB; a scene's factors survive export and import; a factor out of range, a colour
/// that is not three numbers in [0, 1], or a texture the file lacks fails naming the material, the extension and
/// the property.
#[test]
fn layered_materials_load_from_gltf_and_bad_ones_name_what_is_wrong() {
    use serde_json::{json, Value};
    let dir = common::cli::temp_dir("layered-gltf");
    let coat = Clearcoat { factor: 0.7, roughness: 0.2, ..Default::default() };
    let sheen = Sheen { color: Vec3::new(0.5, 0.25, 1.0), roughness: 0.6, ..Default::default() };
    let transmits = DiffuseTransmission { factor: 0.3, color: Vec3::new(0.9, 0.5, 0.2), ..Default::default() };
    let film = Iridescence { factor: 0.9, ior: 1.8, thickness_min: 50.0, thickness_max: 700.0, ..Default::default() };
    let layered = Material {
        clearcoat: Some(coat),
        sheen: Some(sheen),
        diffuse_transmission: Some(transmits),
        iridescence: Some(film),
        anisotropy: Some(Anisotropy { strength: 0.6, rotation: 1.25, ..Default::default() }),
        ..base(true)
    };
    let mut scene = furnace(layered);
    scene.environment = None;
    let path = dir.join("layered.gltf");
    strata::scene::gltf_export::write_gltf(&scene, &path).unwrap();
    let loaded = strata::load_scene(&path).unwrap();
    assert_eq!(loaded.materials[0].clearcoat, Some(coat));
    assert_eq!(loaded.materials[0].sheen, Some(sheen));
    assert_eq!(loaded.materials[0].diffuse_transmission, Some(transmits));
    assert_eq!(loaded.materials[0].iridescence, Some(film));
    assert_eq!(
        loaded.materials[0].anisotropy,
        Some(Anisotropy { strength: 0.6, rotation: 1.25, ..Default::default() })
    );
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);

    let original: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let with = |edit: &dyn Fn(&mut Value)| -> anyhow::Result<Scene> {
        let mut doc = original.clone();
        doc["images"] = json!([{"uri": png_data_uri()}]);
        doc["textures"] = json!([{"source": 0}, {"source": 0}]);
        edit(&mut doc);
        let file = dir.join("edited.gltf");
        std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
        strata::load_scene(&file)
    };
    let textured = with(&|doc| {
        let ext = &mut doc["materials"][0]["extensions"];
        ext["KHR_materials_clearcoat"]["clearcoatTexture"] = json!({"index": 1, "texCoord": 1});
        ext["KHR_materials_clearcoat"]["clearcoatRoughnessTexture"] = json!({"index": 0,
            "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}});
        ext["KHR_materials_clearcoat"]["clearcoatNormalTexture"] = json!({"index": 1, "scale": 0.5});
        ext["KHR_materials_sheen"]["sheenColorTexture"] = json!({"index": 1});
        ext["KHR_materials_sheen"]["sheenRoughnessTexture"] = json!({"index": 0});
        ext["KHR_materials_diffuse_transmission"]["diffuseTransmissionTexture"] = json!({"index": 0});
        ext["KHR_materials_iridescence"]["iridescenceThicknessTexture"] = json!({"index": 1, "texCoord": 1});
        ext["KHR_materials_diffuse_transmission"]["diffuseTransmissionColorTexture"] = json!({"index": 1});
    })
    .unwrap();
    let m = &textured.materials[0];
    let c = m.clearcoat.unwrap();
    assert_eq!((c.texture.unwrap().texture, c.texture.unwrap().tex_coord), (1, 1));
    assert_eq!(c.roughness_texture.unwrap().transform.unwrap().scale, glam::Vec2::splat(2.0));
    assert_eq!((c.normal_texture.unwrap().texture, c.normal_scale), (1, 0.5));
    let s = m.sheen.unwrap();
    assert_eq!((s.color_texture.unwrap().texture, s.roughness_texture.unwrap().texture), (1, 0));
    assert!(textured.textures[1].srgb, "the sheen colour texture holds sRGB colour");
    let d = m.diffuse_transmission.unwrap();
    assert_eq!((d.texture.unwrap().texture, d.color_texture.unwrap().texture), (0, 1));
    let thickness = m.iridescence.unwrap().thickness_texture.unwrap();
    assert_eq!((thickness.texture, thickness.tex_coord), (1, 1));

    type Edit<'a> = &'a dyn Fn(&mut Value);
    let failures: [(&str, Edit); 7] = [
        ("\"clearcoatFactor\" is 1.5", &|doc| {
            doc["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatFactor"] = json!(1.5)
        }),
        ("\"clearcoatRoughnessFactor\" is \"smooth\"", &|doc| {
            doc["materials"][0]["extensions"]["KHR_materials_clearcoat"]["clearcoatRoughnessFactor"] = json!("smooth")
        }),
        ("\"sheenColorFactor\" is [1,2]", &|doc| {
            doc["materials"][0]["extensions"]["KHR_materials_sheen"]["sheenColorFactor"] = json!([1, 2])
        }),
        ("\"diffuseTransmissionColorFactor\" is \"white\"", &|doc| {
            doc["materials"][0]["extensions"]["KHR_materials_diffuse_transmission"]["diffuseTransmissionColorFactor"] =
                json!("white")
        }),
        ("\"iridescenceIor\" is 0.5: it is at least 1", &|doc| {
            doc["materials"][0]["extensions"]["KHR_materials_iridescence"]["iridescenceIor"] = json!(0.5)
        }),
        ("\"anisotropyStrength\" is 2: it lies in [0, 1]", &|doc| {
            doc["materials"][0]["extensions"]["KHR_materials_anisotropy"]["anisotropyStrength"] = json!(2)
        }),
        ("\"sheenColorTexture\" names texture 5; the file has 2", &|doc| {
            doc["materials"][0]["extensions"]["KHR_materials_sheen"]["sheenColorTexture"] = json!({"index": 5})
        }),
    ];
    for (says, edit) in failures {
        let error = format!("{:#}", with(edit).unwrap_err());
        let extension = if says.contains("sheen") {
            "KHR_materials_sheen"
        } else if says.contains("anisotropy") {
            "KHR_materials_anisotropy"
        } else if says.contains("iridescence") {
            "KHR_materials_iridescence"
        } else if says.contains("diffuseTransmission") {
            "KHR_materials_diffuse_transmission"
        } else {
            "KHR_materials_clearcoat"
        };
        assert!(error.contains("white base") && error.contains(extension) && error.contains(says), "{error}");
    }
}
