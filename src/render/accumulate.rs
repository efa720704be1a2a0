//! The accumulation pass (`shaders/accumulate.comp`): per pixel, a compute invocation reads the G-buffer (or,
//! in the reference mode, traces the pixel's own primary ray), casts shadow, gloss and translucency rays with ray
//! queries against the TLAS, and adds the sample's radiance into the RGBA32F accumulation image. Workgroups take
//! the image's 8×8 tiles from a queue (a counter per sample), so threads that finish early take more tiles
//! ([`workgroups_for`]).
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

    /// Records one sample's dispatch; the caller has made the G-buffer readable and the TLAS built, and zeroed
    /// the sample's counters (its tile queue starts at the first tile). `workgroups` overrides how many
    /// workgroups share the tiles ([`workgroups_for`]).
    pub fn record(&self, cmd: vk::CommandBuffer, set: &DescriptorSet, push: &AccumulatePush, workgroups: Option<u32>) {
        let tiles = push.width.div_ceil(LOCAL_SIZE) * push.height.div_ceil(LOCAL_SIZE);
        let groups = match workgroups {
            Some(n) => n.clamp(1, MAX_WORKGROUPS),
            None => workgroups_for(tiles, self.device.report.device_type),
        };
        labelled(&self.device, cmd, "accumulate pass", || {
            self.pipeline.bind(cmd, Some(set), bytemuck::bytes_of(push));
            unsafe { self.device.raw.cmd_dispatch(cmd, groups, 1, 1) };
        });
    }
}

/// The most workgroups one dispatch of the pass launches: the least `maxComputeWorkGroupCount[0]` the Vulkan
/// spec lets a device report. Each workgroup loops over tiles, so fewer workgroups than tiles still cover the image.
const MAX_WORKGROUPS: u32 = 65_535;

/// Workgroups a CPU device gets: more than a CPU driver runs threads (llvmpipe caps them at its LP_MAX_THREADS),
/// so every thread has one, and few enough that the rest, which find the queue empty, cost next to nothing.
const CPU_WORKGROUPS: u32 = 256;

/// How many workgroups share a sample's `tiles` (8×8 pixels each). The shader takes tiles from a queue, so any
/// number gives the same picture; what it changes is speed. A GPU gets one per tile (up to `MAX_WORKGROUPS`), as
/// many as it can keep resident. A CPU device runs one workgroup per thread at a time and pays for every one it
/// starts (lavapipe zeroes each 8-lane coroutine's frame, about 18 KiB for this shader), so it gets only
/// `CPU_WORKGROUPS`.
pub fn workgroups_for(tiles: u32, device_type: vk::PhysicalDeviceType) -> u32 {
    let wanted = if device_type == vk::PhysicalDeviceType::CPU { tiles.min(CPU_WORKGROUPS) } else { tiles };
    wanted.clamp(1, MAX_WORKGROUPS)
}

/// Bytes of counters (rays cast, the tile queue) for `slots` samples.
pub fn counter_bytes(slots: u32) -> u64 {
    u64::from(slots.max(1)) * (COUNTERS_PER_SLOT * 4) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cpu_device_gets_a_few_workgroups_and_a_gpu_one_per_tile() {
        let (cpu, gpu) = (vk::PhysicalDeviceType::CPU, vk::PhysicalDeviceType::DISCRETE_GPU);
        // 960x540: 120 x 68 tiles.
        assert_eq!(workgroups_for(8160, cpu), CPU_WORKGROUPS);
        assert_eq!(workgroups_for(8160, gpu), 8160);
        assert_eq!(workgroups_for(6, cpu), 6);
        assert_eq!(workgroups_for(0, gpu), 1);
        // 16384 x 16384: more tiles than one dispatch may launch; the queue covers the rest.
        assert_eq!(workgroups_for(2048 * 2048, gpu), MAX_WORKGROUPS);
    }
}
