//! The sample loop (docs/architecture.md, "One frame"): for each of N samples a camera sample (pixel jitter, shutter time,
//! lens point from the sampler), the instances and lights at that time, a TLAS rebuild, the G-buffer pass and
//! the accumulation pass; then the resolve pass. Samples go to the GPU in batches that share one submission;
//! the host waits once per batch (to report progress and reuse the per-sample buffers), never per sample.
use super::accumulate::{AccumulateInputs, AccumulateLaunch, AccumulatePass, AccumulateVariant, TracePath};
use super::accumulate_layout::AccumulatePush;
use super::deformed::DEFORMED_STREAMS;
use super::gbuffer::{GBuffer, GBufferPass};
use super::resolve::ResolvePass;
pub use super::sample_slots::{camera_sample_at, gpu_camera, seed32};
use super::sample_slots::{SampleRecord, SampleSlots, ACCELERATION_STRUCTURES};
use super::SceneOnGpu;
use crate::output::Frame;
use crate::scene::settings::{Backdrop, Primary, RenderSettings, SamplerKind};
use crate::scene::Scene;
use crate::vk::commands::{submit_and_wait, Access};
use crate::vk::frame_graph::{FrameGraph, Use};
use crate::vk::timer::TimestampPool;
use crate::vk::{Buffer, Device, Image, MemoryLocation};
use anyhow::{bail, Result};
use ash::vk;
use std::sync::Arc;

/// How the accumulation pass estimates the light that reaches a path vertex straight from the lights and
/// emitters. All three converge to the same picture (the tests hold them to it); they differ in noise.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum DirectLight {
    /// Light sampling and BSDF sampling combined by multiple importance sampling (Veach and Guibas 1995, the
    /// power heuristic): the renderer's estimator.
    #[default]
    Mis,
    /// Light sampling alone: every lobe takes the light sample whole; rays add only light that light sampling
    /// cannot choose (seen through refraction).
    LightSampling,
    /// BSDF sampling alone: rays find the lights and emitters (one more ray past a path's last vertex, and a
    /// diffuse one even without diffuse interreflection); light sampling is left only for point and directional
    /// lights, which no ray can hit.
    BsdfSampling,
}

impl DirectLight {
    /// The value the shader reads (`pc.direct_light`).
    fn shader_value(self) -> u32 {
        use super::accumulate_layout::{DIRECT_BSDF_SAMPLING, DIRECT_LIGHT_SAMPLING, DIRECT_MIS};
        match self {
            DirectLight::Mis => DIRECT_MIS,
            DirectLight::LightSampling => DIRECT_LIGHT_SAMPLING,
            DirectLight::BsdfSampling => DIRECT_BSDF_SAMPLING,
        }
    }
}

/// Options that are not picture settings.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameOptions {
    /// Time every pass with GPU timestamps (for benchmarks).
    pub timestamps: bool,
    /// Record every ray the first sample's accumulation pass casts, into [`RenderedFrame::ray_log`] (for the
    /// benchmark to replay through the bare ray-query probe).
    pub log_rays: bool,
    /// How the accumulation pass spreads pixels over its invocations (the device's default unless a test asks
    /// for another). The picture does not depend on it.
    pub accumulate_launch: AccumulateLaunch,
    /// The direct-light estimator (MIS unless a test asks for one strategy alone).
    pub direct_light: DirectLight,
    /// Make [`RenderedFrame::linear`]'s alpha the mean of each sample's squared luminance instead of coverage,
    /// so that a test can estimate each pixel's variance: Var = (E[L²] − E[L]²), over N − 1 for the mean's.
    pub luminance_moments: bool,
    /// Break the render on purpose: only for `strata check`'s canaries, which must fail their comparisons.
    pub sabotage: Sabotage,
    /// Render only the samples `start..end` of the frame's `spp` (a part of a render split over machines).
    pub samples: Option<(u32, u32)>,
    /// Read the samples' sums back into [`RenderedFrame::sums`].
    pub keep_sums: bool,
    /// Bytes to move the ray-tracing pipeline's shader binding table off its alignment: only for the test that
    /// shows the validation layer catches a misaligned table. 0 in every render.
    #[doc(hidden)]
    pub misalign_shader_binding_table: u64,
    /// Build the accumulation pipeline with its chain code even where no path can go on: only for the test that
    /// shows leaving it out changes no bit (`accumulate::paths_go_on`).
    pub keep_chain_code: bool,
}

/// Deliberate breakage of the accumulation pass, for `strata check`'s canaries: proof that its comparisons can
/// fail. Nothing else sets it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Sabotage {
    /// Shadow rays report every light unoccluded.
    pub no_shadow_rays: bool,
    /// The visible surface's shading normal points into it.
    pub flipped_normals: bool,
}

impl Sabotage {
    /// The push constant's `SABOTAGE_*` bits.
    pub fn bits(self) -> u32 {
        use crate::shaders::constants::{SABOTAGE_FLIPPED_NORMALS, SABOTAGE_NO_SHADOW_RAYS};
        (if self.no_shadow_rays { SABOTAGE_NO_SHADOW_RAYS } else { 0 })
            | (if self.flipped_normals { SABOTAGE_FLIPPED_NORMALS } else { 0 })
    }
}

/// GPU time per pass summed over the frame, in milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PassTimes {
    pub tlas_ms: f64,
    pub gbuffer_ms: f64,
    pub accumulate_ms: f64,
    pub resolve_ms: f64,
}

impl PassTimes {
    pub fn total_ms(&self) -> f64 {
        self.tlas_ms + self.gbuffer_ms + self.accumulate_ms + self.resolve_ms
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct FrameStats {
    /// How the accumulation pass traced its rays.
    pub trace: TracePath,
    /// The samples this render made (all of the frame's, or a part's).
    pub samples: u32,
    pub width: u32,
    pub height: u32,
    /// Primary rays traced from the camera (the reference mode; 0 when the G-buffer pass rasterised them).
    pub camera_rays: u64,
    pub shadow_rays: u64,
    pub secondary_rays: u64,
    /// Wall-clock seconds of the sample loop and resolve (not loading or uploading).
    pub seconds: f64,
    pub pass_times: Option<PassTimes>,
    /// Device memory allocated while the frame rendered (scene included), in bytes.
    pub device_bytes: u64,
    /// Of which the per-pixel images (G-buffer, accumulation, display).
    pub image_bytes: u64,
}

/// The finished picture.
pub struct RenderedFrame {
    /// Linear radiance per pixel (the mean over samples); alpha is coverage.
    pub linear: Frame,
    /// Exposed, tone-mapped, sRGB-encoded 8-bit RGBA, ready for PNG.
    pub display: Vec<u8>,
    pub stats: FrameStats,
    /// With [`FrameOptions::log_rays`]: the rays of sample 0's accumulation pass, in the order it cast them.
    pub ray_log: Vec<super::ray_probe::ProbeRay>,
    /// The exposure (stops) the display image was made with: the setting, or what auto exposure chose.
    pub exposure: f32,
    /// With [`FrameOptions::keep_sums`]: the samples' fixed-point sums, for a partial result or a checkpoint.
    pub sums: Option<crate::partial::PartialSums>,
}

/// The error a render returns when its progress callback asked it to stop (Ctrl-C).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interrupted;

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("interrupted")
    }
}

impl std::error::Error for Interrupted {}

/// Samples per submission: enough to keep the host out of the way, few enough for a lively progress bar.
fn batch_size(pixels: u64, spp: u32) -> u32 {
    ((1u64 << 20) / pixels.max(1)).clamp(1, 8).min(u64::from(spp)) as u32
}

/// The code `pc.sampler_kind` and the sampling probe read for `kind` (`SAMPLER_*`, shared_constants.glsl).
pub fn sampler_code(kind: SamplerKind) -> u32 {
    use crate::shaders::constants::*;
    match kind {
        SamplerKind::Regular => SAMPLER_REGULAR,
        SamplerKind::Random => SAMPLER_RANDOM,
        SamplerKind::Jittered => SAMPLER_JITTERED,
        SamplerKind::MultiJittered => SAMPLER_MULTI_JITTERED,
        SamplerKind::Sobol => SAMPLER_SOBOL,
    }
}

const TIMESTAMPS_PER_SAMPLE: u32 = 4;

/// Renders `settings.spp` samples of `scene` and resolves them. `progress(done, total)` is called once with
/// `done = 0` when the passes are built and sampling starts, then after each batch (on lavapipe the first batch
/// also compiles the shaders, half a minute or more on a machine whose Mesa shader cache lacks them); returning
/// `false` stops the render with [`Interrupted`] (everything is freed on the way out).
pub fn render_frame(
    device: &Arc<Device>,
    scene: &Scene,
    on_gpu: &SceneOnGpu,
    settings: &RenderSettings,
    options: &FrameOptions,
    progress: &mut dyn FnMut(u32, u32) -> bool,
) -> Result<RenderedFrame> {
    render_samples(device, scene, on_gpu, settings, options, Continuation::default(), progress)
}

/// Where a render's sums start from and where they are saved as it goes (`--resume`, `--checkpoint`).
#[derive(Default)]
pub struct Continuation<'a> {
    /// Sums to start from (a checkpoint of this render): its samples are not rendered again. None: zero.
    pub resume: Option<&'a crate::partial::PartialSums>,
    /// Called with the sums so far once `every` has passed since the last call (between sample batches), and
    /// once more when the render is interrupted.
    pub checkpoint: Option<Checkpoint<'a>>,
}

pub struct Checkpoint<'a> {
    pub every: std::time::Duration,
    pub save: &'a mut dyn FnMut(&crate::partial::PartialSums) -> Result<()>,
}

/// [`render_frame`] for the samples `options.samples` (of `settings.spp`; all of them when None) on top of the
/// sums `continuation.resume` already holds. The resolve makes the mean of every sample the sums then hold;
/// `options.keep_sums` reads the sums back for a part.
pub fn render_samples(
    device: &Arc<Device>,
    scene: &Scene,
    on_gpu: &SceneOnGpu,
    settings: &RenderSettings,
    options: &FrameOptions,
    continuation: Continuation<'_>,
    progress: &mut dyn FnMut(u32, u32) -> bool,
) -> Result<RenderedFrame> {
    let Continuation { resume, mut checkpoint } = continuation;
    let (width, height, spp) = (settings.width, settings.height, settings.spp);
    let (range_start, range_end) = sample_range(settings, options, resume)?;
    // The samples the sums hold when this run ends, and what the resolve divides them by.
    let held = resume.map_or(0, |r| r.samples.len()) + (range_end - range_start);
    let started = std::time::Instant::now();
    let traced = settings.primary == Primary::Rays;
    let backdrop = settings.backdrop_for(scene.environment.is_some());
    let look = super::resolve::DisplayLook {
        exposure: settings.exposure,
        tone_map: settings.tone_map,
        transparent: backdrop == Backdrop::Transparent,
    };
    if range_start == range_end {
        return resolve_only(device, settings, resume.expect("checked above"), look, options.keep_sums);
    }
    let gbuffer_pass = GBufferPass::new(device)?;
    let materials = gbuffer_pass.materials(scene, &on_gpu.textures)?;
    let targets = FrameTargets::new(device, width, height, traced)?;
    let ray_scene = on_gpu.ray_scene(device, scene)?;
    let batch = batch_size(u64::from(width) * u64::from(height), spp);
    let draws = gbuffer_pass.inputs_for_slots(scene, &on_gpu.geometry, &on_gpu.textures, &materials, batch)?;
    let mut slots = SampleSlots::new(device, scene, settings, &ray_scene, draws, batch)?;
    // Path vertices: the visible surface and its bounces.
    let max_depth = settings.bounces.min(crate::scene::settings::MAX_BOUNCES) + 1;
    let accumulate = AccumulatePass::new(
        device,
        &accumulate_variant(device, scene, settings, options, ray_scene.alpha_tested, max_depth)?,
    )?;
    let accumulate_set = accumulate.descriptor_set(&AccumulateInputs {
        tlas: &slots.tlas.structure,
        gbuffer: &targets.gbuffer,
        sums: &targets.sums,
        materials: &materials,
        lights: &slots.lights,
        primitives: slots.primitive_records(),
        textures: &on_gpu.textures,
        counters: &slots.counters,
        cameras: &slots.cameras,
        environment: &on_gpu.environment,
    })?;
    let ray_log = if options.log_rays { Some(ray_log_for(device, settings, max_depth)?) } else { None };
    let resolve = ResolvePass::new(device)?;
    let resolve_set = resolve.descriptor_set(&targets.sums, targets.accumulation(), &targets.display)?;
    let resolved_images = super::resolve::ResolvedImages {
        set: &resolve_set,
        sums: &targets.sums,
        accumulation: targets.accumulation(),
        display: &targets.display,
        samples: held,
    };
    let timer = if options.timestamps {
        Some(TimestampPool::new(device, "frame timestamps", batch * TIMESTAMPS_PER_SAMPLE + 2)?)
    } else {
        None
    };
    let device_bytes = device.allocator().generate_report().total_allocated_bytes;
    let frame_push = AccumulatePush {
        max_depth,
        ray_log: ray_log.as_ref().map_or(0, |log| log.address()),
        ..frame_push_constants(settings, options, backdrop)
    };
    let initial = match resume {
        Some(r) => Some(Buffer::with_data(device, "resumed sums", &r.counts, vk::BufferUsageFlags::TRANSFER_SRC, 16)?),
        None => None,
    };
    let held_sums = |done: u32| targets.held_sums(spp, resume, range_start..done);
    if !progress(0, range_end - range_start) {
        return Err(Interrupted.into());
    }
    let passes = SamplePasses {
        gbuffer: &gbuffer_pass,
        accumulate: &accumulate,
        set: &accumulate_set,
        resolve: &resolve,
        look,
        timer: timer.as_ref(),
        batch,
        traced,
        ray_log: ray_log.as_ref().map(|log| log.buffer()),
    };
    let run = SampleRun { range: range_start..range_end, initial: initial.as_ref(), push: &frame_push };
    let (shadow_rays, secondary_rays, times) =
        passes.run(&targets, &mut slots, &run, &resolved_images, progress, &mut checkpoint, &held_sums)?;
    let super::resolve::ResolvedSums { linear, display, exposure } =
        resolve.read_out(&resolved_images, look, settings.auto_exposure)?;
    let samples = range_end - range_start;
    let stats = FrameStats {
        trace: accumulate.path(),
        samples,
        width,
        height,
        camera_rays: if traced { camera_rays(settings, samples) } else { 0 },
        shadow_rays,
        secondary_rays,
        seconds: started.elapsed().as_secs_f64(),
        pass_times: options.timestamps.then_some(times),
        device_bytes,
        image_bytes: targets.image_bytes(),
    };
    let ray_log = match &ray_log {
        Some(log) => log.rays()?,
        None => Vec::new(),
    };
    let sums = if options.keep_sums { Some(held_sums(range_end)?) } else { None };
    Ok(RenderedFrame { linear, display, stats, ray_log, exposure, sums })
}

/// The camera rays the reference mode traces for `samples` camera samples: one per path (the same ray for a camera
/// sample's paths).
fn camera_rays(settings: &RenderSettings, samples: u32) -> u64 {
    u64::from(settings.width) * u64::from(settings.height) * u64::from(samples) * u64::from(settings.shading_samples)
}

/// Room for every ray one sample's accumulation pass casts (`FrameOptions::log_rays`): per pixel and path at most
/// one camera ray and, per path vertex, one shadow ray and one ray on; BSDF sampling alone casts one more ray past
/// the last vertex.
fn ray_log_for(device: &Arc<Device>, settings: &RenderSettings, max_depth: u32) -> Result<super::ray_log::RayLog> {
    let rays_per_pixel = (2 * u64::from(max_depth) + 1) * u64::from(settings.shading_samples);
    super::ray_log::RayLog::new(device, u64::from(settings.width) * u64::from(settings.height) * rays_per_pixel)
}

/// Which accumulation pipeline the frame needs (`max_depth` path vertices; ray-traced primaries or the G-buffer).
fn accumulate_variant(
    device: &Arc<Device>,
    scene: &Scene,
    settings: &RenderSettings,
    options: &FrameOptions,
    alpha_tested: bool,
    max_depth: u32,
) -> Result<AccumulateVariant> {
    let bsdf_sampling_alone = options.direct_light == DirectLight::BsdfSampling;
    Ok(AccumulateVariant {
        path: TracePath::choose(settings.trace, device)?,
        primary_rays: settings.primary == Primary::Rays,
        alpha_tested,
        environment: scene.environment.is_some(),
        chains: options.keep_chain_code || super::accumulate::paths_go_on(max_depth, bsdf_sampling_alone),
        dispersion: scene.disperses(),
        layers: scene.layered(),
        launch: options.accumulate_launch,
        table_shift: options.misalign_shader_binding_table,
    })
}

/// The accumulation pass's push constants every sample of the frame shares (`SampleSlots::fill` adds each
/// sample's own; the path depth and ray log come from the caller).
fn frame_push_constants(settings: &RenderSettings, options: &FrameOptions, backdrop: Backdrop) -> AccumulatePush {
    AccumulatePush {
        background: settings.background.extend(backdrop.code() as f32),
        width: settings.width,
        height: settings.height,
        sample_count: settings.spp,
        sampler_kind: sampler_code(settings.sampler),
        seed: seed32(settings.seed),
        indirect: u32::from(settings.indirect),
        direct_light: options.direct_light.shader_value(),
        alpha_moment: u32::from(options.luminance_moments),
        sabotage: options.sabotage.bits(),
        shading_samples: settings.shading_samples,
        ..bytemuck::Zeroable::zeroed()
    }
}

/// The samples `options.samples` asks for (all of the frame's when None), checked against the frame and the sums
/// a render goes on from.
fn sample_range(
    settings: &RenderSettings,
    options: &FrameOptions,
    resume: Option<&crate::partial::PartialSums>,
) -> Result<(u32, u32)> {
    let (width, height, spp) = (settings.width, settings.height, settings.spp);
    if width == 0 || height == 0 || spp == 0 {
        bail!("nothing to render: {width}x{height} pixels, {spp} samples per pixel");
    }
    let paths = settings.shading_samples;
    if !(1..=crate::scene::settings::MAX_SHADING_SAMPLES).contains(&paths) {
        bail!(
            "{paths} shading samples per camera sample: it takes 1 to {}",
            crate::scene::settings::MAX_SHADING_SAMPLES
        );
    }
    let (range_start, range_end) = options.samples.unwrap_or((0, spp));
    // An empty range is what a render resumed from a checkpoint that holds all of its samples has left.
    if range_start > range_end || range_end > spp || (range_start == range_end && resume.is_none()) {
        bail!("samples {range_start}..{range_end} are not a range within the frame's {spp}");
    }
    if let Some(r) = resume {
        r.check_fits(width, height, spp)?;
        if let Some((a, b)) = r.samples.overlap(&crate::partial::SampleSet::range(range_start, range_end)) {
            bail!("the sums to go on from hold samples {a}..{b} already");
        }
    }
    Ok((range_start, range_end))
}

/// The images and buffers a frame's passes write, per pixel: the G-buffer (what the accumulation pass reads),
/// the fixed-point sums (fixed_point.glsl: what makes the total independent of the samples' order and
/// grouping), and the resolve's float and 8-bit images. The float image is the G-buffer's position attachment
/// where there is a G-buffer: the resolve runs once the last sample has read it (a frame graph's aliasing of a
/// transient target), which keeps the frame within 100 bytes per pixel with the sums.
struct FrameTargets {
    gbuffer: GBuffer,
    sums: Buffer,
    /// The reference mode's float image (it has no G-buffer to borrow one from).
    own_accumulation: Option<Image>,
    display: Image,
    extent: vk::Extent2D,
}

impl FrameTargets {
    fn new(device: &Arc<Device>, width: u32, height: u32, traced: bool) -> Result<Self> {
        let extent = vk::Extent2D { width, height };
        let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        // Primary rays need no G-buffer; a one-texel stand-in keeps the accumulation's descriptor set whole.
        let gbuffer = if traced { GBuffer::new(device, 1, 1)? } else { GBuffer::new(device, width, height)? };
        let sums = Buffer::new(
            device,
            "sample sums",
            u64::from(width) * u64::from(height) * crate::partial::BYTES_PER_PIXEL,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
            16,
        )?;
        let own_accumulation = if traced {
            Some(Image::new_2d(device, "accumulation", vk::Format::R32G32B32A32_SFLOAT, extent, storage)?)
        } else {
            None
        };
        Ok(Self {
            gbuffer,
            sums,
            own_accumulation,
            display: Image::new_2d(device, "display", vk::Format::R8G8B8A8_UNORM, extent, storage)?,
            extent,
        })
    }

    /// The resolve's float image (the linear mean).
    fn accumulation(&self) -> &Image {
        match &self.own_accumulation {
            Some(image) => image,
            None => &self.gbuffer.color[super::gbuffer_layout::attachment::POSITION],
        }
    }

    /// What the sums hold once the samples `rendered` are in, on top of `resume`'s: read back for a checkpoint or
    /// a part.
    fn held_sums(
        &self,
        spp: u32,
        resume: Option<&crate::partial::PartialSums>,
        rendered: std::ops::Range<u32>,
    ) -> Result<crate::partial::PartialSums> {
        let device = self.sums.device();
        let counts = crate::vk::readback::read_buffer::<u64>(device, &self.sums, Access::COMPUTE_READ_WRITE)?;
        let mut samples = crate::partial::SampleSet::range(rendered.start, rendered.end);
        if let Some(r) = resume {
            samples = r.samples.union(&samples)?;
        }
        let vk::Extent2D { width, height } = self.extent;
        Ok(crate::partial::PartialSums { width, height, spp, samples, counts })
    }

    /// Bytes of the per-pixel images: G-buffer (none in the reference mode) or the float image, display, sums.
    fn image_bytes(&self) -> u64 {
        let gbuffer_or_float = match self.own_accumulation {
            Some(_) => 16,
            None => super::gbuffer_layout::bytes_per_pixel() as u64,
        };
        u64::from(self.extent.width)
            * u64::from(self.extent.height)
            * (gbuffer_or_float + 4 + crate::partial::BYTES_PER_PIXEL)
    }
}

/// How a sample finds the fixed-point sums: as the previous sample left them, or (the frame's first sample)
/// started from zero or from a buffer of sums (a checkpoint or another part).
#[derive(Clone, Copy)]
enum SumsStart<'a> {
    Continue,
    Zero,
    From(&'a Buffer),
}

/// A sample's passes in the order they run. Each declares what it reads and writes to the frame graph
/// (`vk::frame_graph`), which places the barriers and layout transitions between them.
struct SamplePasses<'a> {
    gbuffer: &'a GBufferPass,
    accumulate: &'a AccumulatePass,
    set: &'a crate::vk::descriptors::DescriptorSet,
    resolve: &'a ResolvePass,
    look: super::resolve::DisplayLook,
    /// Timestamps: TIMESTAMPS_PER_SAMPLE per slot of the `batch`, then two around the resolve.
    timer: Option<&'a TimestampPool>,
    batch: u32,
    traced: bool,
    /// The buffer the first sample's accumulation pass logs its rays into (`FrameOptions::log_rays`).
    ray_log: Option<&'a Buffer>,
}

/// The samples one run renders, the sums its first starts from (None: zero) and the push constants they share.
struct SampleRun<'a> {
    range: std::ops::Range<u32>,
    initial: Option<&'a Buffer>,
    push: &'a AccumulatePush,
}

impl SamplePasses<'_> {
    /// Renders `run`'s samples in batches of `self.batch`, one submission each: the host fills each sample's slot
    /// first, then records the batch; the last batch ends with the resolve into `resolved`. After each batch:
    /// `progress` (false: stop) and, when due or stopping, a checkpoint of `held_sums`. Returns the shadow and
    /// secondary rays counted and the pass times.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        targets: &FrameTargets,
        slots: &mut SampleSlots<'_>,
        run: &SampleRun<'_>,
        resolved: &super::resolve::ResolvedImages<'_>,
        progress: &mut dyn FnMut(u32, u32) -> bool,
        checkpoint: &mut Option<Checkpoint<'_>>,
        held_sums: &dyn Fn(u32) -> Result<crate::partial::PartialSums>,
    ) -> Result<(u64, u64, PassTimes)> {
        let device = targets.sums.device();
        let (start, end) = (run.range.start, run.range.end);
        let mut times = PassTimes::default();
        let (mut shadow_rays, mut secondary_rays) = (0u64, 0u64);
        let mut last_checkpoint = std::time::Instant::now();
        // One graph for every batch: what the last batch left (layouts, last writes and reads) carries over.
        let mut graph = FrameGraph::new(device);
        let mut done = start;
        while done < end {
            let count = self.batch.min(end - done);
            // Everything per sample on the host first: transforms, TLAS instances, lights, draws, camera.
            let samples = (0..count).map(|slot| slots.fill(slot, done + slot, run.push)).collect::<Result<Vec<_>>>()?;
            slots.reset_counters(self.batch)?;
            if let Some(timer) = self.timer {
                timer.reset();
            }
            let last = done + count == end;
            let batch_start = match (done == start, run.initial) {
                (false, _) => SumsStart::Continue,
                (true, Some(from)) => SumsStart::From(from),
                (true, None) => SumsStart::Zero,
            };
            submit_and_wait(device, "sample batch", |cmd| {
                self.record_batch(&mut graph, cmd, targets, slots, &samples, batch_start, last.then_some(resolved));
                Ok(())
            })?;
            let (shadow, secondary) = slots.rays_counted(count)?;
            (shadow_rays, secondary_rays) = (shadow_rays + shadow, secondary_rays + secondary);
            if let Some(timer) = self.timer {
                times.add_batch(timer, count, last.then_some(self.batch))?;
            }
            done += count;
            let stop = !progress(done - start, end - start) && done < end;
            if let Some(Checkpoint { every, save }) = checkpoint {
                if done < end && (stop || last_checkpoint.elapsed() >= *every) {
                    save(&held_sums(done)?)?;
                    last_checkpoint = std::time::Instant::now();
                }
            }
            if stop {
                return Err(Interrupted.into());
            }
        }
        Ok((shadow_rays, secondary_rays, times))
    }

    /// Records a batch's samples, then hands their sums and ray counters to the host (ray counts, checkpoints)
    /// and, for the frame's last batch, resolves them (`resolve_into`). `sums` says how the batch's first sample
    /// finds the sums.
    #[allow(clippy::too_many_arguments)]
    fn record_batch(
        &self,
        graph: &mut FrameGraph,
        cmd: vk::CommandBuffer,
        targets: &FrameTargets,
        slots: &SampleSlots<'_>,
        samples: &[SampleRecord],
        sums: SumsStart<'_>,
        resolve_into: Option<&super::resolve::ResolvedImages<'_>>,
    ) {
        for (slot, sample) in samples.iter().enumerate() {
            let stamp = |i: u32, stage: vk::PipelineStageFlags2| {
                if let Some(timer) = self.timer {
                    timer.write(cmd, stage, slot as u32 * TIMESTAMPS_PER_SAMPLE + i);
                }
            };
            let sums = if slot == 0 { sums } else { SumsStart::Continue };
            self.record(graph, cmd, targets, slots, slot as u32, sample, sums, &stamp);
        }
        let mut to_host = vec![
            Use::read_buffer(&targets.sums, Access::HOST_READ),
            Use::read_buffer(&slots.counters, Access::HOST_READ),
        ];
        to_host.extend(self.ray_log.map(|log| Use::read_buffer(log, Access::HOST_READ)));
        graph.pass(cmd, "sums and ray counts to the host", &to_host, || {});
        if let Some(images) = resolve_into {
            let stamp = |i: u32, stage: vk::PipelineStageFlags2| {
                if let Some(timer) = self.timer {
                    timer.write(cmd, stage, self.batch * TIMESTAMPS_PER_SAMPLE + i);
                }
            };
            stamp(0, vk::PipelineStageFlags2::TOP_OF_PIPE);
            self.resolve.record_into(graph, cmd, images, &self.look);
            stamp(1, vk::PipelineStageFlags2::COMPUTE_SHADER);
        }
    }

    /// Records sample `slot`'s passes: its acceleration-structure builds, its G-buffer pass (the reference mode
    /// rasterises its one-texel stand-in once, so the set reads defined texels), where the sums start (`sums`: as
    /// the previous sample left them, from zero, or from a checkpoint's or another part's buffer), and its
    /// accumulation into the sums.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        graph: &mut FrameGraph,
        cmd: vk::CommandBuffer,
        targets: &FrameTargets,
        slots: &SampleSlots<'_>,
        slot: u32,
        sample: &SampleRecord,
        sums: SumsStart<'_>,
        stamp: &dyn Fn(u32, vk::PipelineStageFlags2),
    ) {
        let device = targets.sums.device();
        let first = !matches!(sums, SumsStart::Continue);
        stamp(0, vk::PipelineStageFlags2::TOP_OF_PIPE);
        slots.draws.deformed.record_skinning(graph, cmd, slot);
        slots.record_builds(graph, cmd, slot);
        stamp(1, vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR);
        if !self.traced || first {
            self.gbuffer.record(graph, cmd, &targets.gbuffer, &slots.draws, slot, &sample.camera);
        }
        stamp(2, vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT);
        let sums_written = Use::write_buffer(&targets.sums, Access::TRANSFER_WRITE);
        match sums {
            SumsStart::Continue => {}
            SumsStart::Zero => graph.pass(cmd, "sums start at zero", &[sums_written], || unsafe {
                device.raw.cmd_fill_buffer(cmd, targets.sums.raw, 0, vk::WHOLE_SIZE, 0)
            }),
            SumsStart::From(from) => {
                let uses = [Use::read_buffer(from, Access::TRANSFER_READ), sums_written];
                graph.pass(cmd, "sums start from earlier samples", &uses, || {
                    let region = [vk::BufferCopy::default().size(from.size)];
                    unsafe { device.raw.cmd_copy_buffer(cmd, from.raw, targets.sums.raw, &region) }
                })
            }
        }
        let sampled = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
        let mut uses: Vec<Use> = targets
            .gbuffer
            .color
            .iter()
            .map(|image| Use::read_image(image, sampled, Access::SHADER_SAMPLED_READ))
            .collect();
        uses.extend([
            Use::read_memory(ACCELERATION_STRUCTURES, Access::AS_COMPUTE_READ),
            Use::write_buffer(&targets.sums, Access::COMPUTE_READ_WRITE),
            Use::write_buffer(&slots.counters, Access::COMPUTE_READ_WRITE),
            Use::read_memory(DEFORMED_STREAMS, Access::COMPUTE_READ),
        ]);
        uses.extend(self.ray_log.map(|log| Use::write_buffer(log, Access::COMPUTE_READ_WRITE)));
        graph.pass(cmd, self.accumulate.label(), &uses, || self.accumulate.record(cmd, self.set, &sample.push));
        stamp(3, self.accumulate.stage());
    }
}

impl PassTimes {
    /// Adds a batch's `count` samples from their timestamps, and the resolve's when the batch (of `slots`) ran it.
    fn add_batch(&mut self, timer: &TimestampPool, count: u32, resolve_of: Option<u32>) -> Result<()> {
        let ns = timer.read_range_ns(0, count * TIMESTAMPS_PER_SAMPLE)?;
        for slot in 0..count {
            let t = &ns[(slot * TIMESTAMPS_PER_SAMPLE) as usize..];
            self.tlas_ms += (t[1] - t[0]) / 1e6;
            self.gbuffer_ms += (t[2] - t[1]) / 1e6;
            self.accumulate_ms += (t[3] - t[2]) / 1e6;
        }
        if let Some(slots) = resolve_of {
            let r = timer.read_range_ns(slots * TIMESTAMPS_PER_SAMPLE, 2)?;
            self.resolve_ms += (r[1] - r[0]) / 1e6;
        }
        Ok(())
    }
}

/// A render with nothing left to sample: the frame its sums make.
fn resolve_only(
    device: &Arc<Device>,
    settings: &RenderSettings,
    sums: &crate::partial::PartialSums,
    look: super::resolve::DisplayLook,
    keep_sums: bool,
) -> Result<RenderedFrame> {
    let started = std::time::Instant::now();
    let resolved = super::resolve::resolve_sums(device, sums, look, settings.auto_exposure)?;
    let stats = FrameStats {
        trace: TracePath::choose(settings.trace, device)?,
        samples: 0,
        width: sums.width,
        height: sums.height,
        camera_rays: 0,
        shadow_rays: 0,
        secondary_rays: 0,
        seconds: started.elapsed().as_secs_f64(),
        pass_times: None,
        device_bytes: device.allocator().generate_report().total_allocated_bytes,
        image_bytes: 0,
    };
    Ok(RenderedFrame {
        linear: resolved.linear,
        display: resolved.display,
        stats,
        ray_log: Vec::new(),
        exposure: resolved.exposure,
        sums: keep_sums.then(|| sums.clone()),
    })
}
