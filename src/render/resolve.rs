//! The resolve pass (`shaders/resolve.comp`): divides the accumulated sum by the sample count in place (linear
//! radiance for EXR), and writes exposure → tone map → sRGB into an 8-bit image for PNG.
use super::accumulate_layout::ResolvePush;
use crate::scene::settings::ToneMap;
use crate::shaders;
use crate::shaders::constants::{RESOLVE_BINDING_ACCUMULATION, RESOLVE_BINDING_DISPLAY, RESOLVE_TILE_SIZE};
use crate::vk::commands::labelled;
use crate::vk::descriptors::DescriptorSet;
use crate::vk::pipeline::{Binding, Pipeline};
use crate::vk::{Device, Image};
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
    /// The pass's descriptor bindings, as `resolve.comp` declares them (tests/contracts.rs holds the SPIR-V to
    /// this list).
    pub fn bindings() -> Vec<Binding> {
        vec![
            Binding::new(RESOLVE_BINDING_ACCUMULATION, vk::DescriptorType::STORAGE_IMAGE),
            Binding::new(RESOLVE_BINDING_DISPLAY, vk::DescriptorType::STORAGE_IMAGE),
        ]
    }

    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let pipeline = Pipeline::compute(
            device,
            "resolve pipeline",
            ("resolve.comp", shaders::RESOLVE_COMP),
            &Self::bindings(),
            std::mem::size_of::<ResolvePush>() as u32,
        )?;
        Ok(Self { pipeline, device: device.clone() })
    }

    pub fn descriptor_set(&self, accumulation: &Image, display: &Image) -> Result<DescriptorSet> {
        let set = self.pipeline.new_descriptor_set("resolve set")?;
        set.storage_image(RESOLVE_BINDING_ACCUMULATION, accumulation).storage_image(RESOLVE_BINDING_DISPLAY, display);
        Ok(set)
    }

    /// Records the resolve of `samples` accumulated samples; both images are in `GENERAL`.
    pub fn record(
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
            inv_samples: 1.0 / samples.max(1) as f32,
            exposure_scale: exposure.exp2(),
            tone_map: match tone_map {
                ToneMap::Clamp => 0,
                ToneMap::Filmic => 1,
            },
            transparent: u32::from(transparent),
            pad: [0; 2],
        };
        labelled(&self.device, cmd, "resolve pass", || {
            self.pipeline.bind(cmd, Some(set), bytemuck::bytes_of(&push));
            unsafe {
                self.device.raw.cmd_dispatch(
                    cmd,
                    extent.width.div_ceil(RESOLVE_TILE_SIZE),
                    extent.height.div_ceil(RESOLVE_TILE_SIZE),
                    1,
                )
            };
        });
    }
}
