//! The validation harness every GPU test runs under. `GpuTest::new()` creates an instance with the Khronos
//! validation layer (synchronization validation + best practices) and the selected device; when the test's
//! `GpuTest` is dropped it destroys the device, then fails the test if the layer reported any error or warning
//! that is not on the allow-list (`strata::vk::validation::ALLOWED`), printing ids, text and object names.
//! A missing layer or ray-query device fails the test with a message that says to run scripts/setup.sh.
//! Within one test process, GPU tests take turns (see `ONE_GPU_AT_A_TIME`).
#![allow(dead_code)]

pub mod cli;
pub mod raycast;
pub mod scenes;

use std::cell::Cell;
use std::sync::{Arc, Mutex, MutexGuard, Once, PoisonError};
use strata::vk::validation::ValidationLog;
use strata::vk::{Device, DeviceNeeds, Gpu, GpuOptions};

/// Held by each `GpuTest` from before its instance is created until after it is destroyed, so that one test
/// process never has two validated instances at once. The Khronos validation layer that Debian 12 ships
/// (1.3.239) keeps state shared between instances that it reads and writes without a lock (its global map from
/// dispatch key to layer data, Vulkan-ValidationLayers issue #4391), and `cargo test` runs tests on parallel
/// threads: two GPU tests side by side crashed a test binary with SIGSEGV inside the layer
/// (`examples/validation_layer_race.rs` reproduces it). Tests still run side by side as separate processes
/// (scripts/test-runner.sh, nextest).
static ONE_GPU_AT_A_TIME: Mutex<()> = Mutex::new(());

thread_local! {
    /// Whether this thread holds `ONE_GPU_AT_A_TIME`: a test that asks for a second `GpuTest` while holding
    /// one gets a clear panic instead of waiting for itself forever.
    static HOLDS_THE_GPU: Cell<bool> = const { Cell::new(false) };
}

/// This thread's turn at the GPU; dropping it hands the turn on.
struct GpuTurn(MutexGuard<'static, ()>);

impl GpuTurn {
    fn take() -> Self {
        assert!(
            !HOLDS_THE_GPU.get(),
            "a test holds one GpuTest at a time: finish or drop the first before creating another"
        );
        // A test that panicked while holding the turn poisons the lock; the device it held is gone by then.
        let guard = ONE_GPU_AT_A_TIME.lock().unwrap_or_else(PoisonError::into_inner);
        HOLDS_THE_GPU.set(true);
        name_the_test_in_crash_messages();
        Self(guard)
    }
}

impl Drop for GpuTurn {
    fn drop(&mut self) {
        strata::fatal_signals::set_running(None);
        HOLDS_THE_GPU.set(false);
    }
}

/// A crash inside the driver or the layer ends the whole test binary, and `cargo test` then says only "signal: 11"
/// with no test name. GPU tests take turns, so the test holding the turn is the one that crashed: the message
/// names it (libtest names each test's thread after the test).
fn name_the_test_in_crash_messages() {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| {
        strata::fatal_signals::report_fatal_signals_with(
            "GPU tests take turns, so this test held the only device in the process. Run it alone with \
             `cargo test <module>::<test name> -- --exact`, or under gdb for a backtrace.",
        )
    });
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("an unnamed test thread");
    strata::fatal_signals::set_running(Some(&format!("the GPU test `{test}`")));
}

pub struct GpuTest {
    gpu: Option<Gpu>,
    log: Arc<ValidationLog>,
    /// Last, so that it is released after the device and instance are destroyed.
    _turn: GpuTurn,
}

impl GpuTest {
    /// A device that traces rays (ray queries, a ray-tracing pipeline, or both), for tests that render.
    pub fn new() -> Self {
        Self::with(DeviceNeeds::RayTracing)
    }

    /// A device with ray queries, for the tests of the ray probe (a compute shader that traces with them).
    pub fn ray_queries() -> Self {
        Self::with(DeviceNeeds::RayQueries)
    }

    /// A device that need not have ray queries, for tests that only rasterize or run compute shaders that trace
    /// no rays: they also run on GPUs without VK_KHR_ray_query.
    pub fn raster_only() -> Self {
        Self::with(DeviceNeeds::RasterOnly)
    }

    fn with(needs: DeviceNeeds) -> Self {
        let turn = GpuTurn::take();
        let options = GpuOptions {
            validation: true,
            echo_messages: false,
            device: std::env::var("STRATA_TEST_DEVICE").ok(),
            needs,
        };
        match Gpu::new(&options) {
            Ok(gpu) => {
                let log = gpu.validation_log();
                Self { gpu: Some(gpu), log, _turn: turn }
            }
            Err(e) => panic!(
                "GPU tests need the Khronos validation layer and a Vulkan device that traces rays \
                 (VK_KHR_ray_query or VK_KHR_ray_tracing_pipeline; the ray-probe tests need ray queries).\n\
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

/// A library [`strata::Renderer`] under the validation layer, for the tests of the library API: it takes the
/// GPU turn like `GpuTest`, and on drop closes the renderer and fails the test on any message the layer reported
/// (teardown included).
pub struct RendererTest {
    renderer: Option<strata::Renderer>,
    _turn: GpuTurn,
}

impl RendererTest {
    pub fn new() -> Self {
        let turn = GpuTurn::take();
        let options = strata::RendererOptions {
            validation: true,
            device: std::env::var("STRATA_TEST_DEVICE").ok(),
            ..Default::default()
        };
        match strata::Renderer::new(&options) {
            Ok(renderer) => Self { renderer: Some(renderer), _turn: turn },
            Err(e) => panic!(
                "the library tests need the Khronos validation layer and a Vulkan device that traces rays.\n\
                 Run `sudo scripts/setup.sh` to install them (Mesa's lavapipe works without a GPU).\n\
                 The error was: {e:#}"
            ),
        }
    }
}

impl std::ops::Deref for RendererTest {
    type Target = strata::Renderer;
    fn deref(&self) -> &strata::Renderer {
        self.renderer.as_ref().expect("open until dropped")
    }
}

impl std::ops::DerefMut for RendererTest {
    fn deref_mut(&mut self) -> &mut strata::Renderer {
        self.renderer.as_mut().expect("open until dropped")
    }
}

impl Drop for RendererTest {
    fn drop(&mut self) {
        let Some(renderer) = self.renderer.take() else { return };
        let verdict = renderer.close();
        if !std::thread::panicking() {
            if let Err(report) = verdict {
                panic!("{report:#}");
            }
        }
    }
}
