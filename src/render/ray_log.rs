//! The rays one sample of the accumulation pass casts, recorded as cast (`log_ray` in accumulate.comp), so the
//! benchmark can replay exactly them through the bare ray-query probe: the driver's ceiling for the pass's own
//! mix of shadow rays (the first hit ends them) and gloss and translucency rays (closest hit), in its order.
use super::ray_probe::ProbeRay;
use crate::vk::{Buffer, Device, MemoryLocation};
use anyhow::{bail, Result};
use ash::vk;
use std::sync::Arc;

/// `RayLog` in accumulate.comp: count, capacity, two pad words, then the rays (ProbeRay's layout).
const HEADER_BYTES: u64 = 16;

pub struct RayLog {
    buffer: Buffer,
    capacity: u32,
}

impl RayLog {
    /// Room for `capacity` rays; a pass that casts more reports them in the count and [`RayLog::rays`] fails.
    pub fn new(device: &Arc<Device>, capacity: u64) -> Result<Self> {
        let Ok(capacity) = u32::try_from(capacity) else {
            bail!("a ray log of {capacity} rays is too large (at most {})", u32::MAX)
        };
        let bytes = HEADER_BYTES + u64::from(capacity) * std::mem::size_of::<ProbeRay>() as u64;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let mut buffer = Buffer::new(device, "ray log", bytes, usage, MemoryLocation::GpuToCpu, 16)?;
        buffer.write(0, bytemuck::cast_slice(&[0u32, capacity, 0, 0]))?;
        Ok(Self { buffer, capacity })
    }

    /// The address the accumulation pass's push constants carry.
    /// The buffer the pass writes the rays into (for the frame graph's uses).
    pub fn buffer(&self) -> &crate::vk::Buffer {
        &self.buffer
    }

    pub fn address(&self) -> vk::DeviceAddress {
        self.buffer.address
    }

    /// The rays logged, in the order the pass cast them (once the GPU is done and its writes are host-visible).
    pub fn rays(&self) -> Result<Vec<ProbeRay>> {
        // Only the logged rays are copied out of the mapping, not the whole (up to tens of MB) buffer.
        let bytes = self.buffer.mapped()?;
        let header: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[..HEADER_BYTES as usize]);
        let count = header[0];
        if count > self.capacity {
            bail!("the pass cast {count} rays, more than the log's room for {}", self.capacity);
        }
        let end = HEADER_BYTES as usize + count as usize * std::mem::size_of::<ProbeRay>();
        Ok(bytemuck::pod_collect_to_vec(&bytes[HEADER_BYTES as usize..end]))
    }
}
