//! A ready-to-use GPU: instance (with validation when asked) and the selected device.
use super::device::{Device, DeviceNeeds};
use super::instance::{Instance, InstanceOptions};
use super::validation::ValidationLog;
use anyhow::Result;
use std::sync::Arc;

/// What to create.
#[derive(Debug, Clone, Default)]
pub struct GpuOptions {
    /// Load the Khronos validation layer. Keep validated `Gpu`s on different threads from living at the same
    /// time: the layer Debian 12 ships (1.3.239) shares unlocked state between instances and crashes when one
    /// thread creates or destroys an instance while another records commands (the test harness takes turns).
    pub validation: bool,
    /// Print validation messages to stderr as they arrive.
    pub echo_messages: bool,
    /// `--device NAME|INDEX`.
    pub device: Option<String>,
    /// Ray queries, unless the caller only rasterizes and runs compute shaders that trace no rays.
    pub needs: DeviceNeeds,
}

/// The instance and device; clone the `Arc<Device>` to create resources.
pub struct Gpu {
    pub device: Arc<Device>,
    log: Arc<ValidationLog>,
}

impl Gpu {
    pub fn new(options: &GpuOptions) -> Result<Self> {
        let instance =
            Instance::new(&InstanceOptions { validation: options.validation, echo_messages: options.echo_messages })?;
        let log = instance.validation_log();
        let device = Device::new(instance, options.device.as_deref(), options.needs)?;
        Ok(Self { device, log })
    }

    /// The validation log; keep it to check messages reported during teardown, after the `Gpu` is gone.
    pub fn validation_log(&self) -> Arc<ValidationLog> {
        self.log.clone()
    }
}
