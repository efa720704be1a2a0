//! `strata bench`: figures, not pass/fail. Each case runs in one process so ratios compare like with like on a
//! shared, noisy machine. GPU times come from timestamp queries around the pass alone.
use crate::math::lens::camera_sample;
use crate::render::gbuffer::{GBuffer, GBufferPass};
use crate::render::SceneOnGpu;
use crate::scene::{BumpDerivative, BumpMap, Scene};
use crate::vk::commands::submit_and_wait;
use crate::vk::timer::TimestampPool;
use crate::vk::Gpu;
use anyhow::Result;
use ash::vk;
use glam::Vec2;

/// One measured configuration: median G-buffer pass time per sample.
#[derive(Debug, Clone)]
pub struct GBufferFigure {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub triangles: usize,
    pub bump: &'static str,
    pub median_ms: f64,
}

/// How the scene's bump maps are set for a case.
#[derive(Debug, Clone, Copy)]
pub enum BumpSetting {
    /// As the scene says.
    AsGiven,
    /// Every bump removed.
    Off,
    /// Every material bumped (the scene's own bump, or fBm defaults), with this derivative method.
    All(BumpDerivative),
}

impl BumpSetting {
    fn label(self) -> &'static str {
        match self {
            BumpSetting::AsGiven => "as given",
            BumpSetting::Off => "none",
            BumpSetting::All(BumpDerivative::CentralDifferences) => "central differences",
            BumpSetting::All(BumpDerivative::Analytic) => "analytic gradient",
        }
    }

    fn apply(self, scene: &Scene) -> Scene {
        let mut scene = scene.clone();
        for m in &mut scene.materials {
            match self {
                BumpSetting::AsGiven => {}
                BumpSetting::Off => m.bump = None,
                BumpSetting::All(derivative) => {
                    let mut bump = m.bump.unwrap_or(BumpMap::default());
                    bump.derivative = derivative;
                    m.bump = Some(bump);
                }
            }
        }
        scene
    }
}

/// Times the G-buffer pass over `samples` camera samples (each its own submission) and returns the median.
pub fn time_gbuffer(
    gpu: &Gpu,
    name: &str,
    scene: &Scene,
    width: u32,
    height: u32,
    bump: BumpSetting,
    samples: u32,
) -> Result<GBufferFigure> {
    let device = &gpu.device;
    let scene = bump.apply(scene);
    let on_gpu = SceneOnGpu::upload(device, &scene)?;
    let (gpu_scene, textures) = (&on_gpu.geometry, &on_gpu.textures);
    let pass = GBufferPass::new(device)?;
    let gbuffer = GBuffer::new(device, width, height)?;
    let materials = pass.materials(&scene, textures)?;
    let inputs = pass.inputs(&scene, gpu_scene, textures, &materials, scene.shutter.0)?;
    let camera = scene.camera_at(scene.shutter.0);
    let timer = TimestampPool::new(device, "gbuffer bench timestamps", 2)?;
    let mut times = Vec::new();
    let mut graph = crate::vk::frame_graph::FrameGraph::new(device);
    // One warm-up sample, then the measured ones with sub-pixel jitter as a render would use.
    for s in 0..=samples {
        let jitter = Vec2::new((s as f32 * 0.618_034).fract() - 0.5, (s as f32 * 0.414_214).fract() - 0.5);
        let sample = camera_sample(&camera, width, height, Vec2::splat(0.5), jitter);
        timer.reset();
        submit_and_wait(device, "gbuffer bench sample", |cmd| {
            timer.write(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, 0);
            pass.record(&mut graph, cmd, &gbuffer, &inputs, 0, &sample);
            timer.write(cmd, vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, 1);
            Ok(())
        })?;
        let t = timer.read_ns()?;
        if s > 0 {
            times.push((t[1] - t[0]) / 1e6);
        }
    }
    Ok(GBufferFigure {
        scene: name.to_owned(),
        width,
        height,
        triangles: scene.triangle_count(),
        bump: bump.label(),
        median_ms: median(times),
    })
}

/// The middle value (the upper one of an even count); `values` is not empty.
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// One distributed-ray-traced frame, measured.
#[derive(Debug, Clone)]
pub struct FrameFigure {
    pub stats: crate::render::frame::FrameStats,
    /// Device memory of the scene alone (geometry, textures), before the frame's own allocations.
    pub scene_bytes: u64,
    /// The bare ray-query probe on the same TLAS: rays cast and GPU ms.
    pub probe_rays: u64,
    pub probe_ms: f64,
    /// The probe replaying the very rays one sample's accumulation pass cast (logged), with no shading: how many,
    /// how many of them shadow rays (the first hit ends them), and GPU ms.
    pub replay_rays: u64,
    pub replay_shadow_rays: u64,
    pub replay_ms: f64,
}

/// Renders `scene` at `width` × `height` with `spp` samples, timing every pass; with `probe`, also casts bare rays
/// at the scene's TLAS (camera rays through the frame, closest hit, no shading: the driver's ray-query ceiling)
/// and replays the rays one sample's pass cast, as it cast them (the ceiling of that pass's own mix of rays).
pub fn time_frame(
    gpu: &Gpu,
    scene: &Scene,
    (width, height): (u32, u32),
    spp: u32,
    primary: crate::scene::settings::Primary,
    trace: crate::scene::settings::Trace,
    probe: bool,
) -> Result<FrameFigure> {
    let settings = crate::scene::settings::RenderSettings {
        width,
        height,
        spp,
        sampler: crate::scene::settings::SamplerKind::Jittered,
        primary,
        trace,
        ..Default::default()
    };
    time_frame_with(gpu, scene, &settings, probe)
}

/// The probe's two casts, readied before the timed frame and cast between its batches.
struct ProbeCasts {
    probe: crate::render::ray_probe::RayProbe,
    timer: TimestampPool,
    tlas: crate::vk::accel::AccelerationStructure,
    camera_rays: Vec<crate::render::ray_probe::ProbeRay>,
    replay_tlas: crate::vk::accel::AccelerationStructure,
    replay_rays: Vec<crate::render::ray_probe::ProbeRay>,
    camera_ms: Vec<f64>,
    replay_ms: Vec<f64>,
    /// The BLASes both TLASes point at: kept as long as they are, dropped after them.
    _ray_scene: crate::render::ray_scene::RayScene,
}

impl ProbeCasts {
    /// Logs the rays a one-sample frame's accumulation pass casts and builds as many camera rays through
    /// jittered points of the frame; TLASes at the shutter's opening (camera rays) and at that sample's time
    /// (its own rays).
    fn ready(
        device: &std::sync::Arc<crate::vk::Device>,
        scene: &Scene,
        on_gpu: &SceneOnGpu,
        settings: &crate::scene::settings::RenderSettings,
    ) -> Result<Self> {
        use crate::render::frame::{render_frame, FrameOptions};
        use crate::render::ray_probe::{ProbeRay, RayProbe};
        let ray_scene = crate::render::ray_scene::RayScene::build(device, scene, &on_gpu.geometry, 0)?;
        let tlas_at = |name: &str, t: f32| {
            let instances = ray_scene.tlas_instances(scene, &scene.instance_transforms_at(t));
            crate::vk::accel::AccelerationStructure::build_tlas(device, name, &instances)
        };
        let one_sample = crate::scene::settings::RenderSettings { spp: 1, ..settings.clone() };
        let log_options = FrameOptions { log_rays: true, ..Default::default() };
        let replay_rays = render_frame(device, scene, on_gpu, &one_sample, &log_options, &mut |_, _| true)?.ray_log;
        let (t, _, _) = crate::render::frame::camera_sample_at(scene, &one_sample, 0);
        let camera = scene.camera_at(scene.shutter.0);
        let sample = camera_sample(&camera, settings.width, settings.height, Vec2::splat(0.5), Vec2::ZERO);
        let world_from_clip = sample.clip_from_world().inverse();
        let camera_rays = (0..replay_rays.len().max(1))
            .map(|i| {
                let h = crate::math::sampling::pcg_hash(i as u32);
                let u = crate::math::sampling::unit_float(h);
                let v = crate::math::sampling::unit_float(crate::math::sampling::pcg_hash(h));
                let ndc = glam::Vec2::new(u * 2.0 - 1.0, v * 2.0 - 1.0);
                let near = world_from_clip.project_point3(ndc.extend(0.0));
                let far = world_from_clip.project_point3(ndc.extend(0.999));
                ProbeRay::closest(near, (far - near).normalize_or_zero(), 0.0, 1e30)
            })
            .collect();
        let casts = Self {
            probe: RayProbe::new(device)?,
            timer: TimestampPool::new(device, "probe timestamps", 2)?,
            tlas: tlas_at("probe TLAS", scene.shutter.0)?,
            camera_rays,
            replay_tlas: tlas_at("replay TLAS", t)?,
            replay_rays,
            camera_ms: Vec::new(),
            replay_ms: Vec::new(),
            _ray_scene: ray_scene,
        };
        // Each cast once untimed: the probe's pipeline compiles at its first dispatch.
        casts.probe.cast_timed(&casts.tlas, &casts.camera_rays, None)?;
        casts.probe.cast_timed(&casts.replay_tlas, &casts.replay_rays, None)?;
        Ok(casts)
    }

    /// Both casts once, timed.
    fn cast(&mut self) -> Result<()> {
        self.camera_ms.push(self.probe.cast_timed(&self.tlas, &self.camera_rays, Some(&self.timer))?.1);
        self.replay_ms.push(self.probe.cast_timed(&self.replay_tlas, &self.replay_rays, Some(&self.timer))?.1);
        Ok(())
    }
}

/// [`time_frame`] with any settings (the benchmark's own: jittered, still defaults otherwise).
pub fn time_frame_with(
    gpu: &Gpu,
    scene: &Scene,
    settings: &crate::scene::settings::RenderSettings,
    probe: bool,
) -> Result<FrameFigure> {
    use crate::render::frame::{render_frame, FrameOptions};
    use crate::render::ray_probe::ProbeRay;
    let (width, height) = (settings.width, settings.height);
    let device = &gpu.device;
    let on_gpu = SceneOnGpu::upload(device, scene)?;
    let scene_bytes = device.allocator().generate_report().total_allocated_bytes;
    let options = FrameOptions { timestamps: true, ..Default::default() };
    // lavapipe compiles a pipeline's shaders with LLVM at its first dispatch, between the GPU timestamps: seconds
    // that once made a cold run's first scene read 750 ms per sample against 80 warm. A one-sample frame of a few
    // pixels first readies every pipeline these settings use (the device keeps them), so the figures time the
    // rendering alone, whatever Mesa's shader cache holds.
    let warm_up = crate::scene::settings::RenderSettings {
        width: width.min(8),
        height: height.min(8),
        spp: 1,
        ..settings.clone()
    };
    render_frame(device, scene, &on_gpu, &warm_up, &options, &mut |_, _| true)?;
    let mut casts = if probe { Some(ProbeCasts::ready(device, scene, &on_gpu, settings)?) } else { None };
    // The probe's casts run between the frame's batches (before the first and after each), so the ratios compare
    // passes timed over the same minutes: this shared machine's speed swings within a run by more than the
    // figures' margins, and a probe timed after the frame once read 4.9 M rays/s in one run and 8.9 in the next.
    let mut cast_error = None;
    let frame = render_frame(device, scene, &on_gpu, settings, &options, &mut |_, _| {
        if let Some(casts) = casts.as_mut() {
            if let Err(e) = casts.cast() {
                cast_error.get_or_insert(e);
                return false;
            }
        }
        true
    });
    if let Some(e) = cast_error {
        return Err(e);
    }
    let stats = frame?.stats;
    Ok(match casts {
        Some(mut c) => {
            // The frame reports its progress before its first batch, so there is a cast; if not, one now.
            if c.camera_ms.is_empty() {
                c.cast()?;
            }
            FrameFigure {
                stats,
                scene_bytes,
                probe_rays: c.camera_rays.len() as u64,
                probe_ms: median(c.camera_ms),
                replay_rays: c.replay_rays.len() as u64,
                replay_shadow_rays: c.replay_rays.iter().filter(|r| r.flags & ProbeRay::FIRST_HIT != 0).count() as u64,
                replay_ms: median(c.replay_ms),
            }
        }
        None => FrameFigure {
            stats,
            scene_bytes,
            probe_rays: 0,
            probe_ms: 0.0,
            replay_rays: 0,
            replay_shadow_rays: 0,
            replay_ms: 0.0,
        },
    })
}

/// Wall-clock milliseconds to create the accumulation pass's pipeline for `path` (its alpha-tested variant, with
/// the any-hit shader) on a device that holds none yet: what the first frame of a render pays. Mesa's shader
/// disk cache may hold the compiled code from an earlier run; the figure is then the cached cost.
pub fn time_pipeline_creation(gpu: &Gpu, path: crate::render::accumulate::TracePath) -> Result<f64> {
    let started = std::time::Instant::now();
    use crate::render::accumulate::{AccumulateLaunch, AccumulatePass, AccumulateVariant};
    let variant = AccumulateVariant {
        path,
        primary_rays: false,
        alpha_tested: true,
        environment: false,
        chains: true,
        dispersion: false,
        layers: false,
        launch: AccumulateLaunch::DeviceDefault,
        table_shift: 0,
    };
    let pass = AccumulatePass::new(&gpu.device, &variant)?;
    let ms = started.elapsed().as_secs_f64() * 1e3;
    drop(pass);
    Ok(ms)
}

/// Least-squares exponent b of y = a·x^b.
pub fn fitted_exponent(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let cov: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let var: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    if var > 0.0 {
        cov / var
    } else {
        0.0
    }
}
