//! The resolve pass (`shaders/resolve.comp`): divides the accumulated sum by the sample count in place (linear
//! radiance for EXR), and writes exposure → tone map → sRGB into an 8-bit image for PNG.
use super::accumulate_layout::ResolvePush;
use crate::scene::settings::ToneMap;
use crate::shaders;
use crate::shaders::constants::RESOLVE_TILE_SIZE;
use crate::shaders::constants::{RESOLVE_BINDING_ACCUMULATION, RESOLVE_BINDING_DISPLAY, RESOLVE_BINDING_SUMS};
use crate::vk::commands::{labelled, Access};
use crate::vk::descriptors::DescriptorSet;
use crate::vk::frame_graph::{FrameGraph, Use};
use crate::vk::pipeline::{Binding, Pipeline};
use crate::vk::{Buffer, Device, Image};
use anyhow::Result;
use ash::vk;
use std::sync::Arc;

/// How the display image is made from the linear one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplayLook {
    /// Stops: radiance × 2^exposure before the tone map.
    pub exposure: f32,
    pub tone_map: ToneMap,
    /// Keep coverage in alpha, the colour unpremultiplied (a transparent background).
    pub transparent: bool,
}

pub struct ResolvePass {
    pipeline: Pipeline,
    device: Arc<Device>,
}

impl ResolvePass {
    /// The pass's descriptor bindings, as `resolve.comp` declares them, read from its SPIR-V.
    pub fn bindings() -> Result<Vec<Binding>> {
        crate::vk::spirv::descriptor_bindings(&[("resolve.comp", shaders::RESOLVE_COMP)], 1)
    }

    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let pipeline = Pipeline::compute(
            device,
            "resolve pipeline",
            ("resolve.comp", shaders::RESOLVE_COMP),
            &Self::bindings()?,
            std::mem::size_of::<ResolvePush>() as u32,
        )?;
        Ok(Self { pipeline, device: device.clone() })
    }

    /// `sums`: the samples' fixed-point sums (strata::partial); `accumulation` receives the mean, `display` the
    /// exposed, tone-mapped sRGB picture.
    pub fn descriptor_set(&self, sums: &Buffer, accumulation: &Image, display: &Image) -> Result<DescriptorSet> {
        let set = self.pipeline.new_descriptor_set("resolve set")?;
        set.storage_image(RESOLVE_BINDING_ACCUMULATION, accumulation)
            .storage_image(RESOLVE_BINDING_DISPLAY, display)
            .storage_buffer(RESOLVE_BINDING_SUMS, sums);
        Ok(set)
    }

    /// Records the resolve of `samples` accumulated samples, labelled; both images are in `GENERAL`.
    fn record(
        &self,
        cmd: vk::CommandBuffer,
        set: &DescriptorSet,
        extent: vk::Extent2D,
        samples: u32,
        look: &DisplayLook,
    ) {
        labelled(&self.device, cmd, "resolve pass", || self.dispatch(cmd, set, extent, samples, look));
    }

    /// The resolve's push constants and dispatch, unlabelled.
    fn dispatch(
        &self,
        cmd: vk::CommandBuffer,
        set: &DescriptorSet,
        extent: vk::Extent2D,
        samples: u32,
        look: &DisplayLook,
    ) {
        let DisplayLook { exposure, tone_map, transparent } = *look;
        let push = ResolvePush {
            width: extent.width,
            height: extent.height,
            samples: samples.max(1),
            exposure_scale: exposure.exp2(),
            tone_map: match tone_map {
                ToneMap::Clamp => 0,
                ToneMap::Filmic => 1,
            },
            transparent: u32::from(transparent),
            pad: [0; 2],
        };
        self.pipeline.bind(cmd, Some(set), bytemuck::bytes_of(&push));
        unsafe {
            self.device.raw.cmd_dispatch(
                cmd,
                extent.width.div_ceil(RESOLVE_TILE_SIZE),
                extent.height.div_ceil(RESOLVE_TILE_SIZE),
                1,
            )
        };
    }
}

/// A frame made from sums alone: the linear mean (for EXR), the display picture (for PNG) and the exposure it
/// was made with.
pub struct ResolvedSums {
    pub linear: crate::output::Frame,
    pub display: Vec<u8>,
    pub exposure: f32,
}

/// Resolves sums that are already summed (merged parts, or a checkpoint that holds every sample) with the same
/// pass and push constants a render ends with, so the bits are the ones that render makes. With
/// `auto_exposure` the exposure is chosen from the mean as a render chooses it.
pub fn resolve_sums(
    device: &Arc<Device>,
    sums: &crate::partial::PartialSums,
    look: DisplayLook,
    auto_exposure: bool,
) -> Result<ResolvedSums> {
    use crate::vk::commands::submit_and_wait;
    sums.check_fits(sums.width, sums.height, sums.spp)?;
    let extent = vk::Extent2D { width: sums.width, height: sums.height };
    let upload = Buffer::with_data(device, "merged sums", &sums.counts, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
    let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let accumulation = Image::new_2d(device, "accumulation", vk::Format::R32G32B32A32_SFLOAT, extent, storage)?;
    let display = Image::new_2d(device, "display", vk::Format::R8G8B8A8_UNORM, extent, storage)?;
    let pass = ResolvePass::new(device)?;
    let set = pass.descriptor_set(&upload, &accumulation, &display)?;
    let held = sums.samples.len();
    let images =
        ResolvedImages { set: &set, sums: &upload, accumulation: &accumulation, display: &display, samples: held };
    let mut graph = FrameGraph::new(device);
    submit_and_wait(device, "resolve sums", |cmd| {
        pass.record_into(&mut graph, cmd, &images, &look);
        Ok(())
    })?;
    pass.read_out(&images, look, auto_exposure)
}

/// What a recorded resolve wrote into, for [`ResolvePass::read_out`].
pub struct ResolvedImages<'a> {
    pub set: &'a DescriptorSet,
    /// The fixed-point sums the resolve reads.
    pub sums: &'a Buffer,
    /// The linear mean, in `GENERAL`, last written by the resolve (a frame's resolve writes over the
    /// G-buffer's position attachment, which the frame graph knows as the same image).
    pub accumulation: &'a Image,
    /// The display picture, in `GENERAL`, last written by the resolve.
    pub display: &'a Image,
    /// The sample count the resolve divided by.
    pub samples: u32,
}

impl ResolvePass {
    /// Records the resolve as a pass of `graph`: it reads the sums and writes over both images (their old
    /// contents discarded), which it leaves in `GENERAL` for [`Self::read_out`].
    pub fn record_into(
        &self,
        graph: &mut FrameGraph,
        cmd: vk::CommandBuffer,
        images: &ResolvedImages<'_>,
        look: &DisplayLook,
    ) {
        let general = vk::ImageLayout::GENERAL;
        let uses = [
            Use::read_buffer(images.sums, Access::COMPUTE_READ),
            Use::overwrite_image(images.accumulation, general, Access::COMPUTE_WRITE),
            Use::overwrite_image(images.display, general, Access::COMPUTE_WRITE),
        ];
        let extent = images.accumulation.extent;
        graph.pass(cmd, "resolve pass", &uses, || self.dispatch(cmd, images.set, extent, images.samples, look));
    }

    /// Reads a finished resolve back: the linear mean, then — with `auto_exposure` — the resolve again at the
    /// exposure that maps the mean's log-average to middle grey, then the display picture. The end of every
    /// render and of every merge, so that both make the same bytes from the same sums.
    pub fn read_out(
        &self,
        images: &ResolvedImages<'_>,
        look: DisplayLook,
        auto_exposure: bool,
    ) -> Result<ResolvedSums> {
        use crate::vk::commands::{image_barrier, submit_and_wait};
        use crate::vk::readback::read_image;
        let device = &self.device;
        let ResolvedImages { set, accumulation, display, samples, .. } = *images;
        let linear = read_image(device, accumulation, vk::ImageLayout::GENERAL, Access::COMPUTE_WRITE)?;
        let extent = accumulation.extent;
        let linear = crate::output::Frame::new(extent.width, extent.height, linear.to_rgba_f32()?)?;
        let mut exposure = look.exposure;
        if auto_exposure {
            exposure = self::auto_exposure(&linear, look.transparent);
            let look = DisplayLook { exposure, ..look };
            submit_and_wait(device, "auto-exposure resolve", |cmd| {
                // The read-back left the accumulation a transfer source; the display is as the resolve left it.
                image_barrier(
                    device,
                    cmd,
                    accumulation,
                    (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, Access::TRANSFER_READ),
                    (vk::ImageLayout::GENERAL, Access::COMPUTE_WRITE),
                );
                self.record(cmd, set, extent, samples, &look);
                Ok(())
            })?;
        }
        let display = read_image(device, display, vk::ImageLayout::GENERAL, Access::COMPUTE_WRITE)?.bytes;
        Ok(ResolvedSums { linear, display, exposure })
    }
}

/// The middle grey photographic tone reproduction maps the log-average luminance to (Reinhard et al.,
/// "Photographic Tone Reproduction for Digital Images", SIGGRAPH 2002: the key value a).
pub const MIDDLE_GREY: f32 = 0.18;

/// The exposure in stops that maps a frame's log-average luminance exp(mean ln(δ + L)) to middle grey, over the
/// pixels something covers when the background is transparent (else every pixel); within ±24 stops.
pub fn auto_exposure(frame: &crate::output::Frame, covered_only: bool) -> f32 {
    let luminance = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let (mut sum, mut n) = (0.0f64, 0u64);
    for p in frame.pixels.iter().filter(|p| !covered_only || p[3] > 0.0) {
        // Covered fractionally: the colour is premultiplied, so the luminance of the surface is L / alpha.
        let l = if covered_only { luminance(p) / p[3] } else { luminance(p) };
        if l.is_finite() {
            sum += f64::from(1e-4 + l.max(0.0)).ln();
            n += 1;
        }
    }
    if n == 0 {
        return 0.0;
    }
    let log_average = (sum / n as f64).exp() as f32;
    (MIDDLE_GREY / log_average).log2().clamp(-24.0, 24.0)
}
