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
    let pass = GBufferPass::new(device, textures.images.len() as u32)?;
    let gbuffer = GBuffer::new(device, width, height)?;
    let transforms = scene.instance_transforms_at(scene.shutter.0);
    let materials = pass.materials(&scene, textures)?;
    let inputs = pass.inputs(&scene, gpu_scene, textures, &materials, &transforms)?;
    let camera = scene.camera_at(scene.shutter.0);
    let timer = TimestampPool::new(device, "gbuffer bench timestamps", 2)?;
    let mut times = Vec::new();
    // One warm-up sample, then the measured ones with sub-pixel jitter as a render would use.
    for s in 0..=samples {
        let jitter = Vec2::new((s as f32 * 0.618_034).fract() - 0.5, (s as f32 * 0.414_214).fract() - 0.5);
        let sample = camera_sample(&camera, width, height, Vec2::splat(0.5), jitter);
        timer.reset();
        submit_and_wait(device, "gbuffer bench sample", |cmd| {
            timer.write(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, 0);
            pass.record(cmd, &gbuffer, gpu_scene, &inputs, &sample, crate::vk::commands::Access::NONE);
            timer.write(cmd, vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, 1);
            Ok(())
        })?;
        let t = timer.read_ns()?;
        if s > 0 {
            times.push((t[1] - t[0]) / 1e6);
        }
    }
    times.sort_by(f64::total_cmp);
    Ok(GBufferFigure {
        scene: name.to_owned(),
        width,
        height,
        triangles: scene.triangle_count(),
        bump: bump.label(),
        median_ms: times[times.len() / 2],
    })
}
