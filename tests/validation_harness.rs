//! The harness itself: it must catch a deliberately invalid call and a leaked object, and a clean run that
//! creates and destroys every kind of object strata uses must end with zero messages.
use crate::common;

use ash::vk;
use glam::Vec3;
use strata::render::ray_probe::RayProbe;
use strata::render::solid::SolidPass;
use strata::vk::accel::{AccelerationStructure, TlasInstance, TriangleGeometry, BUILD_INPUT_USAGE};
use strata::vk::{Buffer, Image, MemoryLocation};

#[test]
fn an_invalid_call_fails_the_harness() {
    let gpu = common::GpuTest::raster_only();
    let device = gpu.device().clone();
    // A buffer with no usage flags violates VUID-VkBufferCreateInfo-usage-requiredbitmask. lavapipe and NVIDIA's
    // driver (580, H100) create it anyway, so it can be destroyed again and the test process stays sound.
    let info = vk::BufferCreateInfo::default().size(64).usage(vk::BufferUsageFlags::empty());
    let buffer = unsafe { device.raw.create_buffer(&info, None) }.expect("the driver creates the buffer");
    unsafe { device.raw.destroy_buffer(buffer, None) };
    drop(device);
    let report = gpu.finish().expect_err("the harness must fail on an invalid call");
    assert!(report.contains("VUID-VkBufferCreateInfo-usage-requiredbitmask"), "report was:\n{report}");
    assert!(report.contains("[ERROR]"), "report was:\n{report}");
}

#[test]
fn a_leaked_object_is_reported_at_teardown() {
    let gpu = common::GpuTest::raster_only();
    let device = gpu.device().clone();
    let info = vk::BufferCreateInfo::default().size(64).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    let leaked = unsafe { device.raw.create_buffer(&info, None) }.unwrap();
    device.set_name(leaked, "deliberately leaked buffer");
    drop(device);
    let report = gpu.finish().expect_err("a leaked buffer must fail the harness");
    assert!(report.contains("vkDestroyDevice"), "report was:\n{report}");
    assert!(report.contains("deliberately leaked buffer"), "the report names the object:\n{report}");
}

#[test]
fn creating_and_destroying_every_kind_of_object_is_clean() {
    let gpu = common::GpuTest::ray_queries();
    let device = gpu.device();
    {
        let storage = Buffer::new(
            device,
            "teardown storage",
            1024,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
            1,
        )
        .unwrap();
        let uploaded =
            Buffer::device_local_with_data(device, "teardown upload", &[1u32, 2, 3, 4], BUILD_INPUT_USAGE, 16).unwrap();
        let image = Image::new_2d(
            device,
            "teardown image",
            vk::Format::R32G32B32A32_SFLOAT,
            vk::Extent2D { width: 4, height: 4 },
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        )
        .unwrap();
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let vertices = Buffer::with_data(device, "teardown vertices", &positions, BUILD_INPUT_USAGE, 16).unwrap();
        let indices = Buffer::with_data(device, "teardown indices", &[0u32, 1, 2], BUILD_INPUT_USAGE, 16).unwrap();
        let blas = AccelerationStructure::build_blas(
            device,
            "teardown BLAS",
            &[TriangleGeometry {
                vertex_address: vertices.address,
                vertex_stride: 12,
                vertex_count: 3,
                index_address: indices.address,
                triangle_count: 1,
                opaque: true,
            }],
        )
        .unwrap();
        let tlas = AccelerationStructure::build_tlas(
            device,
            "teardown TLAS",
            &[TlasInstance { blas: &blas, transform: glam::Mat4::IDENTITY, custom_index: 0, mask: 0xff }],
        )
        .unwrap();
        let empty_tlas = AccelerationStructure::build_tlas(device, "empty TLAS", &[]).unwrap();
        let probe = RayProbe::new(device).unwrap();
        let solid = SolidPass::new(device, vk::Format::R8G8B8A8_UNORM, false).unwrap();
        drop((storage, uploaded, image, vertices, indices, blas, tlas, empty_tlas, probe, solid));
    }
    let log = gpu.log().clone();
    gpu.finish().unwrap();
    let unexpected: Vec<String> =
        log.messages().iter().filter(|m| m.allowed_by().is_none()).map(|m| m.to_string()).collect();
    assert!(unexpected.is_empty(), "messages at teardown:\n{}", unexpected.join("\n"));
}

#[test]
fn an_empty_tlas_is_a_valid_miss_everywhere() {
    let gpu = common::GpuTest::ray_queries();
    let device = gpu.device();
    let tlas = AccelerationStructure::build_tlas(device, "empty TLAS", &[]).unwrap();
    let probe = RayProbe::new(device).unwrap();
    let ray = strata::render::ray_probe::ProbeRay::closest(Vec3::ZERO, Vec3::Z, 0.0, 1e9);
    let hits = probe.cast(&tlas, &[ray; 3]).unwrap();
    assert!(hits.iter().all(|h| !h.is_hit()), "{hits:?}");
}

/// Pipelines (compute and graphics) are built once per device and request, shared by every pass that asks again, outlive the
/// passes that asked, and go with the device: a later pass uses the kept pipeline cleanly and nothing leaks.
#[test]
fn a_device_builds_each_pipeline_once_and_destroys_it_with_itself() {
    use strata::vk::pipeline::{Binding, Pipeline};
    let gpu = common::GpuTest::ray_queries();
    let device = gpu.device();
    let kept = || device.kept_pipelines().len();
    let bindings = [
        Binding::new(0, vk::DescriptorType::ACCELERATION_STRUCTURE_KHR),
        Binding::new(1, vk::DescriptorType::STORAGE_BUFFER),
        Binding::new(2, vk::DescriptorType::STORAGE_BUFFER),
    ];
    let shader = ("ray_probe.comp", strata::shaders::RAY_PROBE_COMP);
    let before = kept();
    let first = Pipeline::compute(device, "kept probe", shader, &bindings, 4).unwrap();
    assert_eq!(kept(), before + 1, "the first request builds a pipeline");
    let again = Pipeline::compute(device, "kept probe", shader, &bindings, 4).unwrap();
    assert_eq!(kept(), before + 1, "the same request builds nothing new");
    assert_eq!((again.raw, again.layout, again.set_layout), (first.raw, first.layout, first.set_layout));
    let wider = Pipeline::compute(device, "kept probe", shader, &bindings, 8).unwrap();
    assert_eq!(kept(), before + 2, "a different push-constant range is a different pipeline");
    assert_ne!(wider.raw, first.raw);
    drop((first, again, wider));
    assert_eq!(kept(), before + 2, "dropping the passes' handles leaves the device's pipelines");
    // The G-buffer's graphics pipeline too: every render builds its pass, the device builds the pipeline once.
    let gbuffer = strata::render::gbuffer::GBufferPass::new(device).unwrap();
    assert_eq!(kept(), before + 3, "the first G-buffer pass builds its pipeline");
    drop(gbuffer);
    drop(strata::render::gbuffer::GBufferPass::new(device).unwrap());
    assert_eq!(kept(), before + 3, "a second G-buffer pass builds nothing new");

    // A pass whose pipeline an earlier, dropped pass asked for first still casts rays.
    let tlas = AccelerationStructure::build_tlas(device, "empty TLAS", &[]).unwrap();
    drop(RayProbe::new(device).unwrap());
    let probe = RayProbe::new(device).unwrap();
    let ray = strata::render::ray_probe::ProbeRay::closest(Vec3::ZERO, Vec3::Z, 0.0, 1e9);
    assert!(probe.cast(&tlas, &[ray; 3]).unwrap().iter().all(|h| !h.is_hit()));
    drop((probe, tlas));
    // The harness fails the test on any message at teardown, a kept pipeline that leaked included.
    gpu.finish().unwrap();
}

/// Two validated instances alive on two threads crash the validation layer (see `ONE_GPU_AT_A_TIME` in
/// tests/common/mod.rs), so the harness must never let GPU tests in one process overlap, and a test that asks for a
/// second `GpuTest` while holding one must be told so rather than wait for itself.
#[test]
fn gpu_tests_in_one_process_take_turns() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static ALIVE: AtomicUsize = AtomicUsize::new(0);
    static MOST_ALIVE: AtomicUsize = AtomicUsize::new(0);
    let threads: Vec<_> = (0..3)
        .map(|_| {
            std::thread::spawn(|| {
                for _ in 0..3 {
                    let gpu = common::GpuTest::raster_only();
                    let now = ALIVE.fetch_add(1, Ordering::SeqCst) + 1;
                    MOST_ALIVE.fetch_max(now, Ordering::SeqCst);
                    std::thread::sleep(std::time::Duration::from_millis(50));
                    ALIVE.fetch_sub(1, Ordering::SeqCst);
                    gpu.finish().unwrap();
                }
            })
        })
        .collect();
    for thread in threads {
        thread.join().expect("a GPU test thread panicked");
    }
    assert_eq!(MOST_ALIVE.load(Ordering::SeqCst), 1, "GPU tests overlapped in one process");

    let first = common::GpuTest::raster_only();
    let second = std::panic::catch_unwind(common::GpuTest::raster_only);
    let payload = second.err().expect("a second GpuTest on the same thread must panic");
    let message =
        payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned());
    let message = message.unwrap_or_default();
    assert!(
        message.contains("one GpuTest at a time"),
        "a second GpuTest on the same thread must panic clearly: {message:?}"
    );
    first.finish().unwrap();
}

/// A crash inside the driver or the layer ends the whole test binary; the message on stderr names the test that
/// held the GPU, the thread, the faulting address and the call stack. The test runs itself as a child process that
/// takes the GPU and reads an unmapped address, as a crashing driver would.
#[test]
fn a_crash_names_the_gpu_test_that_held_the_device() {
    use std::os::unix::process::ExitStatusExt as _;
    // The test's path in the one test binary (tests/suite.rs): its module, then its name.
    const NAME: &str = "validation_harness::a_crash_names_the_gpu_test_that_held_the_device";
    const CHILD: &str = "STRATA_TEST_CRASH_ON_PURPOSE";
    const UNMAPPED: usize = 0x10;
    if std::env::var_os(CHILD).is_some() {
        let _gpu = common::GpuTest::raster_only();
        // SAFETY: not sound, on purpose: the first page is never mapped on Linux, so the read faults, and the
        // harness's handler reports the fault and lets it end the process.
        unsafe { std::ptr::read_volatile(UNMAPPED as *const u8) };
        unreachable!("the read faults");
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([NAME, "--exact", "--nocapture"])
        .env(CHILD, "1")
        .output()
        .expect("run this test binary again");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.signal(), Some(libc::SIGSEGV), "the signal must still end the child: {stderr}");
    let named = format!("strata: crashed with SIGSEGV while running the GPU test `{NAME}`");
    assert!(stderr.contains(&named), "stderr must say {named:?}:\n{stderr}");
    // libtest names a test's thread after the test; the kernel keeps its first 15 bytes.
    let thread = format!("in the thread \"{}\", at the address {UNMAPPED:#x}", &NAME[..15]);
    assert!(stderr.contains(&thread), "stderr must say {thread:?}:\n{stderr}");
    // The stack names the binary the fault happened in, by file and offset.
    let binary = std::env::current_exe().unwrap();
    let binary = binary.file_name().unwrap().to_string_lossy();
    let frames = stderr.lines().skip_while(|l| !l.contains("the call stack")).filter(|l| l.contains("(+0x")).count();
    assert!(frames >= 3 && stderr.contains(&format!("{binary}(")), "stderr must list the frames:\n{stderr}");
}

/// The ray-tracing pipeline's shader binding table is laid out from the device's limits: as laid out it draws no
/// message; moved half a `shaderGroupBaseAlignment` off (the handles still where the regions say, so the driver
/// reads the right ones), the layer reports the misaligned region (VUID-vkCmdTraceRaysKHR-pRayGenShaderBindingTable-03682
/// and its siblings for the other regions).
#[test]
fn a_misaligned_shader_binding_table_is_caught_by_the_layer_and_the_aligned_one_is_clean() {
    use strata::render::frame::{render_frame, FrameOptions};
    use strata::scene::settings::{RenderSettings, Trace};
    let scene =
        strata::load_scene(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml"))).unwrap();
    let settings = RenderSettings { width: 16, height: 16, spp: 1, trace: Trace::Pipeline, ..Default::default() };
    let render_with = |misaligned: bool| {
        let gpu = common::GpuTest::new();
        let device = gpu.device().clone();
        let limits = device.ray_tracing.as_ref().expect("lavapipe has ray-tracing pipelines").limits;
        assert!(limits.base_alignment > limits.handle_alignment, "{limits:?}: no misalignment to make");
        let options = FrameOptions {
            misalign_shader_binding_table: if misaligned { u64::from(limits.base_alignment / 2) } else { 0 },
            ..Default::default()
        };
        let on_gpu = strata::render::SceneOnGpu::upload(&device, &scene).unwrap();
        let frame = render_frame(&device, &scene, &on_gpu, &settings, &options, &mut |_, _| true).unwrap();
        assert_eq!(frame.stats.trace, strata::render::accumulate::TracePath::Pipeline);
        drop((on_gpu, device));
        gpu.finish()
    };
    render_with(false).expect("the shader binding table as laid out draws no message");
    let report = render_with(true).expect_err("a misaligned shader binding table must fail the harness");
    assert!(report.contains("VUID-vkCmdTraceRaysKHR-pRayGenShaderBindingTable-03682"), "report was:\n{report}");
}
