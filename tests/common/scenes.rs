//! Small scenes built in code for the optics tests, and the measurements those tests make on rendered frames.
use glam::Vec4;
use std::sync::Arc;
use strata::render::accumulate::TracePath;
use strata::render::frame::{render_frame, FrameOptions, RenderedFrame};
use strata::render::SceneOnGpu;
#[allow(unused_imports)] // Only the tests that build scenes use it.
pub use strata::scene::library::place;
use strata::scene::settings::{RenderSettings, Trace};
use strata::scene::{Material, MipFilter, Sampler, Scene, Wrap};
use strata::vk::Device;

/// Nearest filtering without mipmaps, wrapping as `wrap` says: every lookup returns one texel exactly.
pub fn nearest_sampler(wrap: Wrap) -> Sampler {
    Sampler { mag_linear: false, min_linear: false, mipmaps: MipFilter::None, wrap_s: wrap, wrap_t: wrap }
}

#[allow(unused_imports)] // Each test binary uses some of them.
pub use strata::check::optics::{emitter, lambertian, ortho_down, plane_at, settings};

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
    strata::check::measure::mean_red(&frame.linear)
}

/// Mean red radiance of each column over rows `rows`.
pub fn column_profile(frame: &RenderedFrame, rows: std::ops::Range<u32>) -> Vec<f32> {
    strata::check::measure::column_profile(&frame.linear, rows)
}

/// Mean red radiance of each row over columns `columns`.
pub fn row_profile(frame: &RenderedFrame, columns: std::ops::Range<u32>) -> Vec<f32> {
    strata::check::measure::row_profile(&frame.linear, columns)
}

#[allow(unused_imports)]
pub use strata::check::measure::crossing;

/// The 10%–90% rise width of a profile that goes from `low` to `high`, in pixels.
pub fn rise_width(profile: &[f32], low: f32, high: f32) -> f32 {
    strata::check::measure::rise_width(profile, low, high).expect("the profile crosses 10% and 90%")
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
