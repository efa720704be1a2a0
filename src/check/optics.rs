//! The distributed ray tracing effects against their optics (Cook, Porter and Carpenter 1984): small scenes whose
//! answer follows from geometry, and the measurements that hold a rendered frame to it. `strata check` runs them
//! as its optics cases and `tests/distributed.rs` asserts the same figures, so the two never drift apart.
//!
//! Each case takes a renderer (`render`: scene and settings to a frame, on whatever device and way to trace the
//! caller chose) and returns its figures: what it measured, what geometry predicts, and the tolerance.
use super::measure::{column_profile, crossing, mean_red, non_finite_pixels, rise_width};
use super::Figure;
use crate::render::frame::RenderedFrame;
use crate::scene::camera::{look_at, Lens};
use crate::scene::library::place;
use crate::scene::settings::{RenderSettings, SamplerKind, ToneMap};
use crate::scene::{Camera, Light, LightShape, Material, NodeMotion, Primitive, Projection, RigidMotion, Scene};
use anyhow::{bail, Result};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// Renders a scene with settings on the caller's device.
pub type Renderer<'a> = dyn FnMut(&Scene, &RenderSettings) -> Result<RenderedFrame> + 'a;

/// Small test frames: seed 7, a black background and the clamp tone map (linear values stay readable); every
/// other setting as `strata render` defaults it.
pub fn settings(width: u32, height: u32, spp: u32, sampler: SamplerKind) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp,
        sampler,
        seed: 7,
        background: Vec3::ZERO,
        tone_map: ToneMap::Clamp,
        ..RenderSettings::default()
    }
}

/// A white-ish Lambertian surface without a specular lobe (KHR_materials_specular factor 0), so its radiance is
/// exactly albedo / π × irradiance.
pub fn lambertian(scene: &mut Scene, albedo: f32) -> usize {
    scene.materials.push(Material {
        name: format!("lambertian {albedo}"),
        base_color: Vec4::new(albedo, albedo, albedo, 1.0),
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        ..Default::default()
    });
    scene.materials.len() - 1
}

/// A black surface that only emits (one-sided: from its front face).
pub fn emitter(scene: &mut Scene, radiance: f32) -> usize {
    scene.materials.push(Material {
        name: format!("emitter {radiance}"),
        base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
        metallic: 0.0,
        specular: 0.0,
        emissive: Vec3::splat(radiance),
        ..Default::default()
    });
    scene.materials.len() - 1
}

/// A plane of `size` (x by z) facing +Y (or −Y when `facing_down`), centred at `center`.
pub fn plane_at(size: Vec2, center: Vec3, facing_down: bool, material: usize) -> (Primitive, Mat4) {
    let rotation = if facing_down { Mat4::from_rotation_x(std::f32::consts::PI) } else { Mat4::IDENTITY };
    (crate::scene::shapes::plane(size, Vec2::ONE, Some(material)), Mat4::from_translation(center) * rotation)
}

/// An orthographic camera at height `height` above `center` looking straight down: image x is world +x, image y
/// (down) is world +z; the image spans 2·half_height metres vertically.
pub fn ortho_down(center: Vec3, height: f32, half_height: f32) -> Camera {
    let eye = center + Vec3::Y * height;
    Camera {
        name: "ortho down".into(),
        world_from_camera: look_at(eye, center, Vec3::NEG_Z),
        projection: Projection::Orthographic { xmag: half_height, ymag: half_height, znear: 0.01, zfar: 100.0 },
        lens: Lens::PINHOLE,
    }
}

/// A light frame at `position` emitting straight down (its −Z is world −Y; its x is world x, its y world −z).
pub fn light_down(position: Vec3) -> Mat4 {
    look_at(position, position - Vec3::Y, Vec3::NEG_Z)
}

/// A scene of one 20 m × 20 m grey (albedo 0.8) Lambertian ground plane at y = 0, facing up.
pub fn ground_scene() -> Scene {
    let mut scene = Scene::default();
    let ground = lambertian(&mut scene, 0.8);
    let (p, m) = plane_at(Vec2::new(20.0, 20.0), Vec3::ZERO, false, ground);
    place(&mut scene, "ground", p, m);
    scene
}

/// Ground (y = 0) under an occluder covering x < 0 at height 2 (unless `occluded` is false), lit by `light` 4 m
/// up, seen straight down from below the occluder: 2 m × 0.5 m of ground.
pub fn shadow_scene(light: LightShape, emission: f32, occluded: bool) -> Scene {
    let mut scene = ground_scene();
    let occluder = lambertian(&mut scene, 0.5);
    if occluded {
        let slab = crate::scene::shapes::cuboid(Vec3::new(5.0, 0.01, 5.0), Some(occluder));
        place(&mut scene, "occluder", slab, Mat4::from_translation(Vec3::new(-5.0, 2.0, 0.0)));
    }
    scene.lights.push(Light {
        name: "light".into(),
        shape: light,
        emission: Vec3::splat(emission),
        world_from_light: light_down(Vec3::new(0.0, 4.0, 0.0)),
        node: None,
        range: 0.0,
    });
    scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.25));
    scene
}

/// Fails unless every pixel of `frame` is finite.
fn finite(frame: &RenderedFrame, what: &str) -> Result<()> {
    let bad = non_finite_pixels(&frame.linear);
    if bad > 0 {
        bail!("{what}: {bad} pixels are NaN or infinite");
    }
    Ok(())
}

/// The 10–90% rise of `profile` from `low` to `high`, or an error naming `what`.
fn rise(profile: &[f32], low: f32, high: f32, what: &str) -> Result<f32> {
    match rise_width(profile, low, high) {
        Some(w) => Ok(w),
        None => bail!("{what}: the profile never rises from 10% to 90% of {low}..{high}"),
    }
}

/// Soft shadows: a quad light 0.5 m wide at height 4 over an occluder edge at height 2 casts a penumbra
/// w·h_o/(h_l − h_o) = 0.5 m wide by similar triangles, a (nearly) linear ramp whose 10–90% part is 0.8 of it,
/// centred under the edge; a point light of radius 0 casts a hard edge.
pub fn penumbra(render: &mut Renderer<'_>) -> Result<Vec<Figure>> {
    let (width, height) = (256, 64); // 2 m x 0.5 m: 128 px per metre
    let px_per_m = 128.0f32;
    let quad = LightShape::Quad { size: Vec2::new(0.5, 6.0) };
    let mut run = |occluded: bool| -> Result<Vec<f32>> {
        let frame = render(&shadow_scene(quad, 2.0, occluded), &settings(width, height, 64, SamplerKind::Jittered))?;
        finite(&frame, "soft shadow")?;
        Ok(column_profile(&frame.linear, 0..height))
    };
    // The fraction of the light each ground point sees: shadowed over unshadowed irradiance (which itself falls
    // off away from under the light).
    let (shadowed, open) = (run(true)?, run(false)?);
    let profile: Vec<f32> = shadowed.iter().zip(&open).map(|(s, o)| s / o).collect();
    let dark = profile[..20].iter().sum::<f32>() / 20.0;
    let lit = profile[width as usize - 20..].iter().sum::<f32>() / 20.0;
    let measured = rise(&profile, 0.0, 1.0, "penumbra")?;
    let predicted = 0.8 * 0.5 * 2.0 / (4.0 - 2.0) * px_per_m;
    let middle = crossing(&profile, 0.5).unwrap_or(f32::NAN);

    let hard = shadow_scene(LightShape::Point { radius: 0.0 }, 20.0, true);
    let frame = render(&hard, &settings(width, height, 16, SamplerKind::Jittered))?;
    let hard_profile = column_profile(&frame.linear, 0..height);
    let hard_lit = hard_profile[width as usize - 20..].iter().sum::<f32>() / 20.0;
    let edge = rise(&hard_profile, 0.0, hard_lit, "point-light shadow")?;
    Ok(vec![
        Figure::at_most("umbra (fraction of the light seen)", f64::from(dark), 0.01, ""),
        Figure::new("fully lit (fraction of the light seen)", f64::from(lit), 1.0, 0.01, ""),
        Figure::new(
            "penumbra 10-90% width",
            f64::from(measured),
            f64::from(predicted),
            0.1 * f64::from(predicted),
            "px",
        ),
        Figure::new("penumbra centre (the edge is at 128)", f64::from(middle), 128.0, 1.5, "px"),
        Figure::at_most("point light (radius 0) edge 10-90% width", f64::from(edge), 1.5, "px"),
    ])
}

/// A Lambertian plane (albedo 0.8) under a 1 m disk light 1 m above it, seen straight down through a window
/// `half_width` metres across, and the radiance it reflects on the axis: E = L·π·R² / (R² + h²) for the
/// irradiance on the axis of a disk, ρ/π·E reflected.
pub fn disk_light_scene(half_width: f32) -> (Scene, f32) {
    let mut scene = Scene::default();
    let albedo = 0.8;
    let ground = lambertian(&mut scene, albedo);
    let (p, m) = plane_at(Vec2::new(4.0, 4.0), Vec3::ZERO, false, ground);
    place(&mut scene, "ground", p, m);
    let (radius, h, radiance) = (1.0f32, 1.0f32, 2.0f32);
    scene.lights.push(Light {
        name: "disk".into(),
        shape: LightShape::Disk { radius },
        emission: Vec3::splat(radiance),
        world_from_light: light_down(Vec3::new(0.0, h, 0.0)),
        node: None,
        range: 0.0,
    });
    scene.camera = Some(ortho_down(Vec3::ZERO, 0.5, half_width));
    let expected =
        albedo / std::f32::consts::PI * radiance * std::f32::consts::PI * radius * radius / (radius * radius + h * h);
    (scene, expected)
}

/// Energy: the plane under the disk light reflects the analytic radiance within 1%.
pub fn disk_light_radiance(render: &mut Renderer<'_>) -> Result<Vec<Figure>> {
    let (scene, expected) = disk_light_scene(0.01);
    let frame = render(&scene, &settings(32, 32, 64, SamplerKind::Jittered))?;
    finite(&frame, "disk light")?;
    let mean = f64::from(mean_red(&frame.linear));
    let expected = f64::from(expected);
    Ok(vec![Figure::new("reflected radiance on the axis", mean, expected, 0.01 * expected, "W/(sr·m²)")])
}

/// The 10–90% width of the edge spread of a uniform disk of diameter 1 seen through a one-pixel box filter of
/// width `box_px / diameter_px`: the ratio that turns a measured edge width into a circle of confusion.
pub fn disk_edge_width_ratio(diameter_px: f32) -> f32 {
    let r = 0.5f64;
    let cdf = |x: f64| -> f64 {
        let x = x.clamp(-r, r);
        0.5 + (x * (r * r - x * x).sqrt() + r * r * (x / r).asin()) / (std::f64::consts::PI * r * r)
    };
    // Box-filtered: the mean of the CDF over one pixel (in units of the diameter).
    let pixel = 1.0 / f64::from(diameter_px);
    let filtered =
        |x: f64| (0..64).map(|i| cdf(x - pixel / 2.0 + pixel * (f64::from(i) + 0.5) / 64.0)).sum::<f64>() / 64.0;
    let solve = |level: f64| {
        let (mut lo, mut hi) = (-1.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if filtered(mid) < level {
                lo = mid
            } else {
                hi = mid
            }
        }
        lo
    };
    (solve(0.9) - solve(0.1)) as f32
}

/// An emitting half-plane x > 0 facing the camera at depth `depth`, through a thin lens of radius `aperture`
/// focused at `focus` (30° vertical field of view).
pub fn dof_scene(aperture: f32, focus: f32, depth: f32) -> Scene {
    let mut scene = Scene::default();
    let bright = emitter(&mut scene, 1.0);
    let primitive = crate::scene::shapes::plane(Vec2::new(10.0, 10.0), Vec2::ONE, Some(bright));
    place(
        &mut scene,
        "edge",
        primitive,
        Mat4::from_translation(Vec3::new(5.0, 0.0, -depth)) * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    scene.camera = Some(Camera {
        name: "lens".into(),
        world_from_camera: Mat4::IDENTITY,
        projection: Projection::Perspective { yfov: 30f32.to_radians(), znear: 0.1, zfar: Some(100.0) },
        lens: Lens { aperture_radius: aperture, focus_distance: focus },
    });
    scene
}

/// Depth of field: an edge at depth d through a lens of radius A focused at f spreads over the circle of
/// confusion 2A·|d − f|/d on the focus plane (docs/architecture.md, "Thin lens"), box-filtered by the pixel; in focus it
/// stays sharp.
pub fn circle_of_confusion(render: &mut Renderer<'_>) -> Result<Vec<Figure>> {
    let (width, height) = (128u32, 48u32);
    let (aperture, focus, depth) = (0.2f32, 2.0f32, 4.0f32);
    let frame = render(&dof_scene(aperture, focus, depth), &settings(width, height, 256, SamplerKind::MultiJittered))?;
    finite(&frame, "defocused edge")?;
    let measured = rise(&column_profile(&frame.linear, 8..40), 0.0, 1.0, "defocused edge")?;
    // The focus plane is 2 f tan(fov/2) tall.
    let lens = Lens { aperture_radius: aperture, focus_distance: focus };
    let px_per_m = height as f32 / (2.0 * focus * 15f32.to_radians().tan());
    let coc_px = lens.circle_of_confusion(depth) * px_per_m;
    let predicted = disk_edge_width_ratio(coc_px) * coc_px;
    let sharp = render(&dof_scene(aperture, depth, depth), &settings(width, height, 64, SamplerKind::MultiJittered))?;
    let in_focus = rise(&column_profile(&sharp.linear, 8..40), 0.0, 1.0, "edge in focus")?;
    Ok(vec![
        Figure::new(
            "defocused edge 10-90% width (circle of confusion, box-filtered)",
            f64::from(measured),
            f64::from(predicted),
            0.1 * f64::from(predicted),
            "px",
        ),
        Figure::at_most("edge in focus (d = f) 10-90% width", f64::from(in_focus), 1.5, "px"),
    ])
}

/// An emitting 0.5 m square moving with `velocity` and spinning with `angular` while the shutter is open, seen
/// straight down (1 m of image height).
pub fn moving_square(velocity: Vec3, angular: Vec3, shutter: (f32, f32)) -> Scene {
    let mut scene = Scene::default();
    let bright = emitter(&mut scene, 1.0);
    let (p, m) = plane_at(Vec2::new(0.5, 0.5), Vec3::ZERO, false, bright);
    let node = place(&mut scene, "square", p, m);
    scene.node_motion.push(NodeMotion { node, motion: RigidMotion { velocity, angular_velocity: angular } });
    scene.shutter = shutter;
    scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.5));
    scene
}

/// Motion blur: a square moving at 1 m/s for a quarter second smears into a linear ramp v·T long (16 px here)
/// that starts where the square started; its middle stays covered for the whole shutter.
pub fn motion_blur_ramp(render: &mut Renderer<'_>) -> Result<Vec<Figure>> {
    let (width, height) = (192u32, 64u32); // 64 px per metre
    let shutter = (0.0, 0.25);
    let scene = moving_square(Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO, shutter);
    let frame = render(&scene, &settings(width, height, 64, SamplerKind::Jittered))?;
    finite(&frame, "moving square")?;
    let profile = column_profile(&frame.linear, 24..40);
    let ramp_px = 1.0 * (shutter.1 - shutter.0) * 64.0;
    // The left side of the streak rises from 0 to 1 over the travel.
    let rising = &profile[..(width / 2) as usize + 20];
    let peak = rising.iter().cloned().fold(0.0, f32::max);
    let at = |level: f32| crossing(rising, level).unwrap_or(f32::NAN);
    let (from, quarter, half, three_quarters) = (at(0.02), at(0.25), at(0.5), at(0.75));
    let measured = (three_quarters - quarter) * 2.0;
    let start_px = width as f32 / 2.0 - 0.25 * 64.0;
    Ok(vec![
        Figure::new("covered for the whole shutter (peak)", f64::from(peak), 1.0, 0.02, ""),
        Figure::new("ramp length v·(close − open)", f64::from(measured), f64::from(ramp_px), 1.0, "px"),
        Figure::at_most(
            "linearity: |(50% − 25%) − (75% − 50%)|",
            f64::from(((half - quarter) - (three_quarters - half)).abs()),
            0.5,
            "px",
        ),
        Figure::new("the streak starts where the square started", f64::from(from), f64::from(start_px), 1.5, "px"),
    ])
}

/// Inside a closed box whose walls have albedo ρ and emit E, every vertex sees radiance arriving from walls
/// alone, so light sampling at vertex k adds ρ^(k+1)·E: with paths of B bounces the radiance is
/// E·(1 + ρ + … + ρ^(B+1)), the geometric series of the rendering equation (Kajiya 1986) cut at B; without
/// diffuse interreflection, E·(1 + ρ). The camera sits inside, 0.5 m from the centre.
pub fn glowing_box(albedo: f32, emission: f32) -> Scene {
    let mut scene = Scene::default();
    scene.materials.push(Material {
        name: "glowing wall".into(),
        base_color: Vec4::new(albedo, albedo, albedo, 1.0),
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        emissive: Vec3::splat(emission),
        double_sided: true,
        ..Default::default()
    });
    place(&mut scene, "box", crate::scene::shapes::cuboid(Vec3::ONE, Some(0)), Mat4::IDENTITY);
    scene.camera = Some(Camera {
        name: "inside".into(),
        world_from_camera: Mat4::from_translation(Vec3::new(0.0, 0.0, 0.5)),
        projection: Projection::Perspective { yfov: 50f32.to_radians(), znear: 0.05, zfar: Some(10.0) },
        lens: Lens::PINHOLE,
    });
    scene
}

/// The furnace: the glowing box's radiance is the geometric series to within 1%, without diffuse
/// interreflection and with it at `bounces_list` bounces.
pub fn glowing_box_series(render: &mut Renderer<'_>, bounces_list: &[u32]) -> Result<Vec<Figure>> {
    let (albedo, emission) = (0.5f32, 1.0f32);
    let scene = glowing_box(albedo, emission);
    let mut mean = |indirect: bool, bounces: u32| -> Result<f64> {
        let s = RenderSettings { indirect, bounces, ..settings(32, 32, 256, SamplerKind::Jittered) };
        let frame = render(&scene, &s)?;
        finite(&frame, "glowing box")?;
        Ok(f64::from(mean_red(&frame.linear)))
    };
    let series = |terms: u32| (0..=terms).map(|k| f64::from(albedo).powi(k as i32)).sum::<f64>() * f64::from(emission);
    let mut figures =
        vec![Figure::new("direct light only: E(1 + ρ)", mean(false, 3)?, series(1), 0.01 * series(1), "")];
    for &bounces in bounces_list {
        let expected = series(bounces + 1);
        figures.push(Figure::new(
            &format!("{bounces} diffuse bounces: E·Σρ^k to k = {}", bounces + 1),
            mean(true, bounces)?,
            expected,
            0.01 * expected,
            "",
        ));
    }
    Ok(figures)
}
