//! GPU timestamps: a query pool with host reset, written around passes, read back in nanoseconds.
use super::device::Device;
use anyhow::{bail, Context as _, Result};
use ash::vk;
use std::sync::Arc;

pub struct TimestampPool {
    raw: vk::QueryPool,
    count: u32,
    device: Arc<Device>,
}

impl TimestampPool {
    pub fn new(device: &Arc<Device>, name: &str, count: u32) -> Result<Self> {
        if device.limits.timestamp_period_ns <= 0.0 {
            bail!("{}: the device does not support timestamps", device.report.name);
        }
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(count);
        let raw = unsafe { device.raw.create_query_pool(&info, None) }.context("vkCreateQueryPool")?;
        device.set_name(raw, name);
        let pool = Self { raw, count, device: device.clone() };
        pool.reset();
        Ok(pool)
    }

    /// Resets every query from the host (Vulkan 1.2 hostQueryReset).
    pub fn reset(&self) {
        unsafe { self.device.raw.reset_query_pool(self.raw, 0, self.count) };
    }

    /// Writes timestamp `index` once all earlier work has finished `stage`.
    pub fn write(&self, cmd: vk::CommandBuffer, stage: vk::PipelineStageFlags2, index: u32) {
        unsafe { self.device.raw.cmd_write_timestamp2(cmd, stage, self.raw, index) };
    }

    /// All timestamps in nanoseconds (after the work that wrote them has completed).
    pub fn read_ns(&self) -> Result<Vec<f64>> {
        self.read_range_ns(0, self.count)
    }

    /// Timestamps `first..first + count` in nanoseconds; each must have been written.
    pub fn read_range_ns(&self, first: u32, count: u32) -> Result<Vec<f64>> {
        if first + count > self.count {
            bail!("timestamps {first}..{} of a pool of {}", first + count, self.count);
        }
        let mut ticks = vec![0u64; count as usize];
        unsafe {
            self.device.raw.get_query_pool_results(
                self.raw,
                first,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .context("vkGetQueryPoolResults")?;
        let period = f64::from(self.device.limits.timestamp_period_ns);
        Ok(ticks.iter().map(|&t| t as f64 * period).collect())
    }
}

impl Drop for TimestampPool {
    fn drop(&mut self) {
        unsafe { self.device.raw.destroy_query_pool(self.raw, None) };
    }
}
