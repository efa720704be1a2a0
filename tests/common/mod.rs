//! The validation harness every GPU test runs under. `GpuTest::new()` creates an instance with the Khronos
//! validation layer (synchronization validation + best practices) and the selected device; when the test's
//! `GpuTest` is dropped it destroys the device, then fails the test if the layer reported any error or warning
//! that is not on the allow-list (`strata::vk::validation::ALLOWED`), printing ids, text and object names.
//! A missing layer or ray-query device fails the test with a message that says to run scripts/setup.sh.
#![allow(dead_code)]

pub mod raycast;
pub mod scenes;

use std::sync::Arc;
use strata::vk::validation::ValidationLog;
use strata::vk::{Device, DeviceNeeds, Gpu, GpuOptions};

pub struct GpuTest {
    gpu: Option<Gpu>,
    log: Arc<ValidationLog>,
}

impl GpuTest {
    /// A device with ray queries, for tests that trace rays.
    pub fn new() -> Self {
        Self::with(DeviceNeeds::RayQueries)
    }

    /// A device that need not have ray queries, for tests that only rasterize or run compute shaders that trace
    /// no rays: they also run on GPUs without VK_KHR_ray_query.
    pub fn raster_only() -> Self {
        Self::with(DeviceNeeds::RasterOnly)
    }

    fn with(needs: DeviceNeeds) -> Self {
        let options = GpuOptions {
            validation: true,
            echo_messages: false,
            device: std::env::var("STRATA_TEST_DEVICE").ok(),
            needs,
        };
        match Gpu::new(&options) {
            Ok(gpu) => {
                let log = gpu.validation_log();
                Self { gpu: Some(gpu), log }
            }
            Err(e) => panic!(
                "GPU tests need the Khronos validation layer and a Vulkan device with VK_KHR_ray_query.\n\
                 Run `sudo scripts/setup.sh` to install them (Mesa's lavapipe works without a GPU).\n\
                 The error was: {e:#}"
            ),
        }
    }

    pub fn device(&self) -> &Arc<Device> {
        &self.gpu.as_ref().expect("GpuTest used after finish").device
    }

    pub fn log(&self) -> &Arc<ValidationLog> {
        &self.log
    }

    /// Destroys the device (its teardown messages included) and returns the verdict instead of panicking.
    /// Everything the test created from the device must be dropped first.
    pub fn finish(mut self) -> Result<(), String> {
        self.teardown()
    }

    fn teardown(&mut self) -> Result<(), String> {
        let Some(gpu) = self.gpu.take() else { return Ok(()) };
        let holders = Arc::strong_count(&gpu.device);
        drop(gpu);
        if holders > 1 {
            return Err(format!(
                "the test still holds {} reference(s) to the device at teardown; drop its GPU objects first",
                holders - 1
            ));
        }
        // Allowed messages are shown (with --nocapture) so the allow-list can be audited.
        for m in self.log.messages() {
            if let Some(allowed) = m.allowed_by() {
                eprintln!("validation (allowed: {}): {}", allowed.reason, m.id_name);
            }
        }
        self.log.check()
    }
}

impl Drop for GpuTest {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        if let Err(report) = self.teardown() {
            panic!("{report}");
        }
    }
}
