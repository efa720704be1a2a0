//! `shaders/include/sampling.glsl` on the GPU produces the same points as its CPU twin
//! `strata::math::sampling` for every sampler, over many pixels and sample indices.
use crate::common;

use ash::vk;
use glam::Vec4;
use strata::math::sampling::{sample_1d, sample_2d};
use strata::scene::settings::SamplerKind;
use strata::shaders::constants::{PROBE_WORKGROUP_SIZE, SAMPLING_PROBE_BINDING_RESULTS};
use strata::vk::commands::{buffer_barrier, submit_and_wait, Access};
use strata::vk::pipeline::Pipeline;
use strata::vk::{Buffer, MemoryLocation};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    kind: u32,
    seed: u32,
    count: u32,
    pixels: u32,
}

#[test]
fn gpu_samplers_equal_the_rust_twin() {
    let gpu = common::GpuTest::raster_only();
    let device = gpu.device();
    let pipeline = Pipeline::compute(
        device,
        "sampling probe",
        ("sampling_probe.comp", strata::shaders::SAMPLING_PROBE_COMP),
        &strata::vk::spirv::descriptor_bindings(&[("sampling_probe.comp", strata::shaders::SAMPLING_PROBE_COMP)], 1)
            .unwrap(),
        16,
    )
    .unwrap();
    let kinds = [
        SamplerKind::Regular,
        SamplerKind::Random,
        SamplerKind::Jittered,
        SamplerKind::MultiJittered,
        SamplerKind::Sobol,
    ];
    for kind in kinds {
        for count in [1u32, 7, 16, 64] {
            let code = strata::render::frame::sampler_code(kind);
            let push = Push { kind: code, seed: 12345, count, pixels: 1000 };
            let total = (push.count * push.pixels) as usize;
            let output = Buffer::new(
                device,
                "sampling results",
                (total * 32) as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuToCpu,
                16,
            )
            .unwrap();
            let set = pipeline.new_descriptor_set("sampling probe set").unwrap();
            set.storage_buffer(SAMPLING_PROBE_BINDING_RESULTS, &output);
            submit_and_wait(device, "sampling probe", |cmd| {
                pipeline.bind(cmd, Some(&set), bytemuck::bytes_of(&push));
                unsafe { device.raw.cmd_dispatch(cmd, (total as u32).div_ceil(PROBE_WORKGROUP_SIZE), 1, 1) };
                buffer_barrier(device, cmd, &output, Access::COMPUTE_WRITE, Access::HOST_READ);
                Ok(())
            })
            .unwrap();
            let results: Vec<Vec4> = output.read().unwrap();
            let mut worst = 0.0f32;
            for i in 0..total as u32 {
                let (pixel, index) = (i / count, i % count);
                let a = sample_2d(kind, push.seed, pixel, index, count, 0);
                let b = sample_2d(kind, push.seed, pixel, index, count, 1);
                let t = sample_1d(kind, push.seed, pixel, index, count, 2);
                let g = results[2 * i as usize];
                let gt = results[2 * i as usize + 1].x;
                worst = worst.max((g - Vec4::new(a.x, a.y, b.x, b.y)).abs().max_element()).max((gt - t).abs());
            }
            assert!(worst < 1e-6, "{kind:?} with {count} samples: GPU and CPU differ by {worst}");
        }
    }
    drop(pipeline);
    gpu.finish().unwrap();
}
