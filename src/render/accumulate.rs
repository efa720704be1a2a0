//! The accumulation pass (`shaders/accumulate.comp`): one compute invocation per pixel reads the G-buffer (or,
//! in the reference mode, traces the pixel's own primary ray), casts shadow, gloss and translucency rays with ray queries against the TLAS, and adds the sample's radiance into
//! the RGBA32F accumulation image.
use super::accumulate_layout::{AccumulatePush, COUNTERS_PER_SLOT};
use super::gbuffer::{GBuffer, GBufferMaterials};
use super::gbuffer_layout::{ATTACHMENTS, IDS};
use super::textures::GpuTextures;
use crate::shaders;
use crate::vk::accel::AccelerationStructure;
use crate::vk::commands::labelled;
use crate::vk::descriptors::DescriptorSet;
use crate::vk::pipeline::{Binding, Pipeline};
use crate::vk::sampler::{Sampler, SamplerDesc};
use crate::vk::{Buffer, Device, Image};
use anyhow::Result;
use ash::vk;
use std::sync::Arc;

const LOCAL_SIZE: u32 = 8;

pub struct AccumulatePass {
    pipeline: Pipeline,
    /// Nearest, clamped: the G-buffer is read texel by texel.
    gbuffer_sampler: Sampler,
    device: Arc<Device>,
}

/// What one frame's accumulation reads and writes.
pub struct AccumulateInputs<'a> {
    pub tlas: &'a AccelerationStructure,
    pub gbuffer: &'a GBuffer,
    pub accumulation: &'a Image,
    pub materials: &'a GBufferMaterials,
    pub lights: &'a Buffer,
    pub primitives: &'a Buffer,
    pub textures: &'a GpuTextures,
    pub counters: &'a Buffer,
    /// One `GpuCamera` per sample slot (read in the reference mode).
    pub cameras: &'a Buffer,
}

impl AccumulatePass {
    /// `primary_rays`: trace each pixel's primary ray (the reference mode) instead of reading the G-buffer.
    /// `alpha_tested`: some geometry is not opaque to rays (RayScene::alpha_tested); without it every ray is
    /// forced opaque and the pipeline carries no alpha test.
    pub fn new(device: &Arc<Device>, texture_count: u32, primary_rays: bool, alpha_tested: bool) -> Result<Self> {
        device.require_ray_queries("the accumulation pass")?;
        let bindings = [
            Binding::new(0, vk::DescriptorType::ACCELERATION_STRUCTURE_KHR),
            // Every G-buffer attachment but the ids, which binding 2 reads as unsigned integers.
            Binding {
                binding: 1,
                kind: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                count: ATTACHMENTS.len() as u32 - 1,
            },
            Binding::new(2, vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            Binding::new(3, vk::DescriptorType::STORAGE_IMAGE),
            Binding::new(4, vk::DescriptorType::STORAGE_BUFFER),
            Binding::new(5, vk::DescriptorType::STORAGE_BUFFER),
            Binding::new(6, vk::DescriptorType::STORAGE_BUFFER),
            Binding { binding: 7, kind: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, count: texture_count.max(1) },
            Binding::new(8, vk::DescriptorType::STORAGE_BUFFER),
            Binding::new(9, vk::DescriptorType::STORAGE_BUFFER),
        ];
        let pipeline = Pipeline::compute_specialized(
            device,
            if primary_rays { "accumulate pipeline (primary rays)" } else { "accumulate pipeline" },
            ("accumulate.comp", shaders::ACCUMULATE_COMP),
            &bindings,
            std::mem::size_of::<AccumulatePush>() as u32,
            &[u32::from(primary_rays), u32::from(alpha_tested)],
        )?;
        let gbuffer_sampler = Sampler::new(
            device,
            "gbuffer texel sampler",
            &SamplerDesc {
                mag_linear: false,
                min_linear: false,
                address_u: vk::SamplerAddressMode::CLAMP_TO_EDGE,
                address_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
                mipmaps: None,
            },
        )?;
        Ok(Self { pipeline, gbuffer_sampler, device: device.clone() })
    }

    /// The descriptor set for one frame: every binding stays the same across its samples.
    pub fn descriptor_set(&self, inputs: &AccumulateInputs<'_>) -> Result<DescriptorSet> {
        let set = self.pipeline.new_descriptor_set("accumulate set")?;
        let gbuffer: Vec<(vk::ImageView, vk::Sampler)> = inputs
            .gbuffer
            .color
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != IDS)
            .map(|(_, image)| (image.view, self.gbuffer_sampler.raw))
            .collect();
        set.acceleration_structure(0, inputs.tlas.raw)
            .combined_image_samplers(1, &gbuffer)
            .combined_image_samplers(2, &[(inputs.gbuffer.color[IDS].view, self.gbuffer_sampler.raw)])
            .storage_image(3, inputs.accumulation)
            .storage_buffer(4, &inputs.materials.buffer)
            .storage_buffer(5, inputs.lights)
            .storage_buffer(6, inputs.primitives)
            .combined_image_samplers(7, &inputs.textures.bindings())
            .storage_buffer(8, inputs.counters)
            .storage_buffer(9, inputs.cameras);
        Ok(set)
    }

    /// Records one sample's dispatch; the caller has made the G-buffer readable and the TLAS built.
    pub fn record(&self, cmd: vk::CommandBuffer, set: &DescriptorSet, push: &AccumulatePush) {
        labelled(&self.device, cmd, "accumulate pass", || {
            self.pipeline.bind(cmd, Some(set), bytemuck::bytes_of(push));
            unsafe {
                self.device.raw.cmd_dispatch(cmd, push.width.div_ceil(LOCAL_SIZE), push.height.div_ceil(LOCAL_SIZE), 1)
            };
        });
    }
}

/// Bytes of ray counters for `slots` samples.
pub fn counter_bytes(slots: u32) -> u64 {
    u64::from(slots.max(1)) * (COUNTERS_PER_SLOT * 4) as u64
}
