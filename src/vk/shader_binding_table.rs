//! The shader binding table of a ray-tracing pipeline built by `Pipeline::ray_tracing`: its three groups'
//! handles (raygen, miss, hit) in a buffer, each region where the device's limits say it must be (Vulkan spec,
//! "Shader Binding Table"): every region starts at a multiple of `shaderGroupBaseAlignment`, records within a
//! region sit `shaderGroupHandleAlignment` apart, and the raygen region is exactly one record. The limits are
//! read from the device (lavapipe 32/16/32 for handle size/alignment/base alignment; NVIDIA's base alignment is
//! 64), never assumed, and the buffer's address is itself checked.
use super::device::Device;
pub use super::device::ShaderGroupLimits;
use super::memory::{Buffer, MemoryLocation};
use super::pipeline::Pipeline;
use anyhow::{bail, Context as _, Result};
use ash::vk;
use std::sync::Arc;

/// Where each region lies in the table, in bytes from its start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TableLayout {
    /// The distance between records: the handle size rounded up to the handle alignment.
    pub stride: u64,
    pub raygen_offset: u64,
    pub miss_offset: u64,
    pub hit_offset: u64,
    pub size: u64,
}

/// The groups `Pipeline::ray_tracing` creates, in order: raygen, miss, hit.
const GROUPS: u32 = 3;

impl TableLayout {
    /// One record per region, each region on the base alignment. Fails on limits the spec does not allow (zero,
    /// or alignments that are not powers of two), which would make the table impossible to lay out.
    pub fn new(limits: &ShaderGroupLimits) -> Result<Self> {
        let (size, align, base) =
            (u64::from(limits.handle_size), u64::from(limits.handle_alignment), u64::from(limits.base_alignment));
        if size == 0 || !align.is_power_of_two() || !base.is_power_of_two() {
            bail!("the device reports impossible shader-group limits: {limits:?}");
        }
        let stride = size.next_multiple_of(align);
        let region = stride.next_multiple_of(base);
        Ok(Self { stride, raygen_offset: 0, miss_offset: region, hit_offset: 2 * region, size: 2 * region + stride })
    }
}

/// The table's buffer and the four regions `vkCmdTraceRaysKHR` takes (the callable region is empty).
pub struct ShaderBindingTable {
    pub buffer: Buffer,
    pub raygen: vk::StridedDeviceAddressRegionKHR,
    pub miss: vk::StridedDeviceAddressRegionKHR,
    pub hit: vk::StridedDeviceAddressRegionKHR,
    pub callable: vk::StridedDeviceAddressRegionKHR,
}

impl ShaderBindingTable {
    /// Reads `pipeline`'s group handles and writes them where `TableLayout` says. `shift` moves the whole
    /// table that many bytes off the base alignment: 0 but in the test that shows the validation layer catches
    /// a misaligned table.
    pub fn new(device: &Arc<Device>, pipeline: &Pipeline, shift: u64) -> Result<Self> {
        let name = format!("{} shader binding table", pipeline.name);
        let rt = device.require_ray_tracing_pipelines(&pipeline.name)?;
        let layout = TableLayout::new(&rt.limits)?;
        let handle_size = rt.limits.handle_size as usize;
        let handles = unsafe {
            rt.loader.get_ray_tracing_shader_group_handles(pipeline.raw, 0, GROUPS, GROUPS as usize * handle_size)
        }
        .with_context(|| format!("vkGetRayTracingShaderGroupHandlesKHR for {}", pipeline.name))?;
        let base = u64::from(rt.limits.base_alignment);
        let mut buffer = Buffer::new(
            device,
            &name,
            layout.size + shift,
            vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::CpuToGpu,
            base,
        )?;
        if buffer.address % base != 0 {
            bail!(
                "{name}: the buffer's address {:#x} is not a multiple of shaderGroupBaseAlignment {base}",
                buffer.address
            );
        }
        let offsets = [layout.raygen_offset, layout.miss_offset, layout.hit_offset];
        for (group, offset) in offsets.iter().enumerate() {
            buffer.write(shift + offset, &handles[group * handle_size..(group + 1) * handle_size])?;
        }
        let region = |offset: u64| vk::StridedDeviceAddressRegionKHR {
            device_address: buffer.address + shift + offset,
            stride: layout.stride,
            size: layout.stride,
        };
        Ok(Self {
            raygen: region(layout.raygen_offset),
            miss: region(layout.miss_offset),
            hit: region(layout.hit_offset),
            callable: vk::StridedDeviceAddressRegionKHR::default(),
            buffer,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(handle_size: u32, handle_alignment: u32, base_alignment: u32) -> ShaderGroupLimits {
        ShaderGroupLimits { handle_size, handle_alignment, base_alignment, max_recursion_depth: 1 }
    }

    #[test]
    fn regions_start_on_the_base_alignment_and_records_on_the_handle_alignment() {
        // lavapipe (Mesa 25.0.7): handles 32 bytes, aligned to 16, regions to 32.
        let lavapipe = TableLayout::new(&limits(32, 16, 32)).unwrap();
        assert_eq!((lavapipe.stride, lavapipe.miss_offset, lavapipe.hit_offset, lavapipe.size), (32, 32, 64, 96));
        // NVIDIA: handles 32 bytes, aligned to 32, regions to 64.
        let nvidia = TableLayout::new(&limits(32, 32, 64)).unwrap();
        assert_eq!((nvidia.stride, nvidia.miss_offset, nvidia.hit_offset, nvidia.size), (32, 64, 128, 160));
        // A handle that is not a multiple of its alignment is padded.
        let odd = TableLayout::new(&limits(24, 16, 64)).unwrap();
        assert_eq!((odd.stride, odd.miss_offset, odd.hit_offset), (32, 64, 128));
        for l in [lavapipe, nvidia, odd] {
            assert!(l.size >= l.hit_offset + l.stride);
        }
        assert!(TableLayout::new(&limits(32, 24, 64)).is_err());
        assert!(TableLayout::new(&limits(0, 16, 32)).is_err());
    }
}
