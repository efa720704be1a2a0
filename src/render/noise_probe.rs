//! Runs `shaders/noise_probe.comp`: noise, fBm and turbulence with gradients at given points on the GPU, to check
//! `noise.glsl` against its CPU twin (`math::noise`).
use crate::shaders;
use crate::shaders::constants::{NOISE_PROBE_BINDING_POINTS, NOISE_PROBE_BINDING_RESULTS, PROBE_WORKGROUP_SIZE};
use crate::vk::commands::{buffer_barrier, labelled, submit_and_wait, Access};
use crate::vk::pipeline::{Binding, Pipeline};
use crate::vk::{Buffer, Device, MemoryLocation};
use anyhow::Result;
use ash::vk;
use glam::{Vec3, Vec4};
use std::sync::Arc;

/// Mirrors `NoiseProbePush`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct NoiseProbePush {
    count: u32,
    octaves: u32,
    lacunarity: f32,
    gain: f32,
}

/// Per point: (noise, fBm, turbulence), each with value in `w` and gradient in `xyz`; then the value-only
/// functions' results (`noise_value`, `fbm_value`, `turbulence_value`) in `xyz`.
pub type NoiseSample = [Vec4; 4];

pub struct NoiseProbe {
    pipeline: Pipeline,
    device: Arc<Device>,
}

impl NoiseProbe {
    /// The probe's descriptor bindings, as `noise_probe.comp` declares them, read from its SPIR-V.
    pub fn bindings() -> Result<Vec<Binding>> {
        crate::vk::spirv::descriptor_bindings(&[("noise_probe.comp", shaders::NOISE_PROBE_COMP)], 1)
    }

    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let pipeline = Pipeline::compute(
            device,
            "noise probe",
            ("noise_probe.comp", shaders::NOISE_PROBE_COMP),
            &Self::bindings()?,
            std::mem::size_of::<NoiseProbePush>() as u32,
        )?;
        Ok(Self { pipeline, device: device.clone() })
    }

    pub fn evaluate(&self, points: &[Vec3], octaves: u32, lacunarity: f32, gain: f32) -> Result<Vec<NoiseSample>> {
        let device = &self.device;
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let padded: Vec<Vec4> = points.iter().map(|p| p.extend(0.0)).collect();
        let input = Buffer::with_data(device, "noise points", &padded, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
        let output = Buffer::new(
            device,
            "noise results",
            (points.len() * std::mem::size_of::<NoiseSample>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuToCpu,
            16,
        )?;
        let set = self.pipeline.new_descriptor_set("noise probe set")?;
        set.storage_buffer(NOISE_PROBE_BINDING_POINTS, &input).storage_buffer(NOISE_PROBE_BINDING_RESULTS, &output);
        let push = NoiseProbePush { count: points.len() as u32, octaves, lacunarity, gain };
        submit_and_wait(device, "noise probe", |cmd| {
            labelled(device, cmd, "noise probe pass", || {
                self.pipeline.bind(cmd, Some(&set), bytemuck::bytes_of(&push));
                unsafe { device.raw.cmd_dispatch(cmd, push.count.div_ceil(PROBE_WORKGROUP_SIZE), 1, 1) };
            });
            buffer_barrier(device, cmd, &output, Access::COMPUTE_WRITE, Access::HOST_READ);
            Ok(())
        })?;
        let flat: Vec<Vec4> = output.read()?;
        Ok(flat.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect())
    }
}
