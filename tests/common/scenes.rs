//! Small scenes built in code for the optics tests, and the measurements those tests make on rendered frames.
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::sync::Arc;
use strata::render::accumulate::TracePath;
use strata::render::frame::{render_frame, FrameOptions, RenderedFrame};
use strata::render::SceneOnGpu;
use strata::scene::camera::{look_at, Lens};
#[allow(unused_imports)] // Only the tests that build scenes use it.
pub use strata::scene::library::place;
use strata::scene::settings::{RenderSettings, SamplerKind, ToneMap, Trace};
use strata::scene::{Camera, Material, MipFilter, Primitive, Projection, Sampler, Scene, Wrap};
use strata::vk::Device;

/// Nearest filtering without mipmaps, wrapping as `wrap` says: every lookup returns one texel exactly.
pub fn nearest_sampler(wrap: Wrap) -> Sampler {
    Sampler { mag_linear: false, min_linear: false, mipmaps: MipFilter::None, wrap_s: wrap, wrap_t: wrap }
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

pub fn metal(scene: &mut Scene, roughness: f32) -> usize {
    scene.materials.push(Material {
        name: format!("metal {roughness}"),
        base_color: Vec4::ONE,
        metallic: 1.0,
        roughness,
        ..Default::default()
    });
    scene.materials.len() - 1
}

/// A plane of `size` (x by z) facing +Y (or −Y when `facing_down`), centred at `center`.
pub fn plane_at(size: Vec2, center: Vec3, facing_down: bool, material: usize) -> (Primitive, Mat4) {
    let rotation = if facing_down { Mat4::from_rotation_x(std::f32::consts::PI) } else { Mat4::IDENTITY };
    (strata::scene::shapes::plane(size, Vec2::ONE, Some(material)), Mat4::from_translation(center) * rotation)
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

/// Renders `scene`. With `settings.trace` left at auto it renders once for every way the device can trace (ray
/// queries, a ray-tracing pipeline) and fails unless they give the same bits (lavapipe builds both from one
/// traversal), so every test that renders through here holds both paths to what it checks.
pub fn render(device: &Arc<Device>, scene: &Scene, settings: &RenderSettings) -> RenderedFrame {
    let on_gpu = SceneOnGpu::upload(device, scene).expect("upload");
    let frame = |trace: Trace| {
        let settings = RenderSettings { trace, ..settings.clone() };
        render_frame(device, scene, &on_gpu, &settings, &FrameOptions::default(), &mut |_, _| true)
            .unwrap_or_else(|e| panic!("render ({}): {e:#}", trace.name()))
    };
    if settings.trace != Trace::Auto {
        return frame(settings.trace);
    }
    let mut frames = TracePath::available(device).into_iter().map(|path| frame(path.as_trace()));
    let first = frames.next().expect("the device traces rays one way or the other");
    for other in frames {
        assert_same_bits(&first, &other);
    }
    first
}

/// Fails unless two renders of one frame by the two ways to trace agree bit for bit, naming the first pixel that
/// differs.
pub fn assert_same_bits(a: &RenderedFrame, b: &RenderedFrame) {
    let (pa, pb) = (a.stats.trace.name(), b.stats.trace.name());
    if let Some(i) =
        a.linear.pixels.iter().zip(&b.linear.pixels).position(|(x, y)| x.map(f32::to_bits) != y.map(f32::to_bits))
    {
        let w = a.linear.width as usize;
        panic!(
            "--trace {pa} and --trace {pb} differ first at pixel ({}, {}): {:?} against {:?}",
            i % w,
            i / w,
            a.linear.pixels[i],
            b.linear.pixels[i]
        );
    }
    assert!(a.display == b.display, "--trace {pa} and --trace {pb} give the same radiance but different PNG bytes");
    let rays = |f: &RenderedFrame| (f.stats.camera_rays, f.stats.shadow_rays, f.stats.secondary_rays);
    assert_eq!(rays(a), rays(b), "--trace {pa} and --trace {pb} cast different numbers of rays");
}

/// Mean red radiance over the whole frame.
pub fn mean_red(frame: &RenderedFrame) -> f32 {
    frame.linear.pixels.iter().map(|p| p[0]).sum::<f32>() / frame.linear.pixels.len() as f32
}

/// Mean red radiance of each column over rows `rows`.
pub fn column_profile(frame: &RenderedFrame, rows: std::ops::Range<u32>) -> Vec<f32> {
    let f = &frame.linear;
    (0..f.width).map(|x| rows.clone().map(|y| f.pixel(x, y)[0]).sum::<f32>() / rows.len() as f32).collect()
}

/// Mean red radiance of each row over columns `columns`.
pub fn row_profile(frame: &RenderedFrame, columns: std::ops::Range<u32>) -> Vec<f32> {
    let f = &frame.linear;
    (0..f.height).map(|y| columns.clone().map(|x| f.pixel(x, y)[0]).sum::<f32>() / columns.len() as f32).collect()
}

/// Where a rising profile first crosses `level` (linear interpolation between pixel centres, in pixels from the
/// left edge of pixel 0).
pub fn crossing(profile: &[f32], level: f32) -> Option<f32> {
    profile
        .windows(2)
        .enumerate()
        .find_map(|(i, w)| (w[0] < level && w[1] >= level).then(|| i as f32 + 0.5 + (level - w[0]) / (w[1] - w[0])))
}

/// The 10%–90% rise width of a profile that goes from `low` to `high`, in pixels.
pub fn rise_width(profile: &[f32], low: f32, high: f32) -> f32 {
    let a = crossing(profile, low + 0.1 * (high - low)).expect("profile crosses 10%");
    let b = crossing(profile, low + 0.9 * (high - low)).expect("profile crosses 90%");
    b - a
}

pub fn assert_finite(frame: &RenderedFrame, what: &str) {
    let bad = frame.linear.pixels.iter().filter(|p| p.iter().any(|v| !v.is_finite())).count();
    assert_eq!(bad, 0, "{what}: {bad} pixels are NaN or infinite");
}

/// Least-squares slope of log(error) against log(spp).
pub fn log_log_slope(points: &[(u32, f64)]) -> f64 {
    let xs: Vec<f64> = points.iter().map(|p| f64::from(p.0).ln()).collect();
    let ys: Vec<f64> = points.iter().map(|p| p.1.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / xs.len() as f64, ys.iter().sum::<f64>() / ys.len() as f64);
    let cov: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let var: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    cov / var
}
