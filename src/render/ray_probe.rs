//! A bare ray-query pass: casts rays from a buffer against a TLAS and returns the closest hits, with no
//! shading. The ray-query smoke test uses it; benchmarks use it as the driver's ray-throughput ceiling.
use crate::shaders;
use crate::shaders::constants::{
    PROBE_WORKGROUP_SIZE, RAY_PROBE_BINDING_HITS, RAY_PROBE_BINDING_RAYS, RAY_PROBE_BINDING_TLAS,
};
use crate::vk::accel::AccelerationStructure;
use crate::vk::commands::{buffer_barrier, labelled, submit_and_wait, Access};
use crate::vk::pipeline::{Binding, Pipeline};
use crate::vk::{Buffer, Device, MemoryLocation};
use anyhow::{bail, Result};
use ash::vk;
use glam::Vec3;
use std::sync::Arc;

/// Mirrors `ProbeRay` in `shaders/ray_probe.comp` (scalar layout).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ProbeRay {
    pub origin: Vec3,
    pub t_min: f32,
    pub direction: Vec3,
    pub t_max: f32,
    /// Ray flags besides opaque: 0 for the closest hit, [`ProbeRay::FIRST_HIT`] for a shadow ray.
    pub flags: u32,
}

impl ProbeRay {
    /// gl_RayFlagsTerminateOnFirstHitEXT: any hit ends the ray (a shadow ray).
    pub const FIRST_HIT: u32 = 4;

    /// A ray that finds the closest hit within `t_min..t_max`.
    pub fn closest(origin: Vec3, direction: Vec3, t_min: f32, t_max: f32) -> Self {
        Self { origin, t_min, direction, t_max, flags: 0 }
    }
}

/// Mirrors `ProbeHit`: `t < 0` and ids of −1 mean a miss.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ProbeHit {
    pub t: f32,
    pub instance_custom_index: i32,
    pub instance_id: i32,
    pub primitive_id: i32,
}

impl ProbeHit {
    pub fn is_hit(&self) -> bool {
        self.instance_id >= 0
    }
}

const LOCAL_SIZE: u32 = PROBE_WORKGROUP_SIZE;

pub struct RayProbe {
    pipeline: Pipeline,
    device: Arc<Device>,
}

impl RayProbe {
    /// The probe's descriptor bindings, as `ray_probe.comp` declares them, read from its SPIR-V.
    pub fn bindings() -> Result<Vec<Binding>> {
        crate::vk::spirv::descriptor_bindings(&[("ray_probe.comp", shaders::RAY_PROBE_COMP)], 1)
    }

    pub fn new(device: &Arc<Device>) -> Result<Self> {
        device.require_ray_queries("the ray probe")?;
        let pipeline =
            Pipeline::compute(device, "ray probe", ("ray_probe.comp", shaders::RAY_PROBE_COMP), &Self::bindings()?, 4)?;
        Ok(Self { pipeline, device: device.clone() })
    }

    /// Casts `rays` against `tlas` and returns one hit record per ray.
    pub fn cast(&self, tlas: &AccelerationStructure, rays: &[ProbeRay]) -> Result<Vec<ProbeHit>> {
        Ok(self.cast_timed(tlas, rays, None)?.0)
    }

    /// Like [`RayProbe::cast`], and with `timer` (two free queries) also the dispatch's GPU time in ms.
    pub fn cast_timed(
        &self,
        tlas: &AccelerationStructure,
        rays: &[ProbeRay],
        timer: Option<&crate::vk::timer::TimestampPool>,
    ) -> Result<(Vec<ProbeHit>, f64)> {
        if rays.is_empty() {
            return Ok((Vec::new(), 0.0));
        }
        if rays.len() > u32::MAX as usize / 2 {
            bail!("{} rays is too many for one probe", rays.len());
        }
        let device = &self.device;
        let ray_buffer = Buffer::with_data(device, "probe rays", rays, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
        let hit_buffer = Buffer::new(
            device,
            "probe hits",
            (rays.len() * std::mem::size_of::<ProbeHit>()) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuToCpu,
            16,
        )?;
        let set = self.pipeline.new_descriptor_set("ray probe set")?;
        set.acceleration_structure(RAY_PROBE_BINDING_TLAS, tlas.raw)
            .storage_buffer(RAY_PROBE_BINDING_RAYS, &ray_buffer)
            .storage_buffer(RAY_PROBE_BINDING_HITS, &hit_buffer);
        let count = rays.len() as u32;
        if let Some(timer) = timer {
            timer.reset();
        }
        submit_and_wait(device, "ray probe", |cmd| {
            if let Some(timer) = timer {
                timer.write(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, 0);
            }
            labelled(device, cmd, "ray probe pass", || {
                self.pipeline.bind(cmd, Some(&set), bytemuck::bytes_of(&count));
                unsafe { device.raw.cmd_dispatch(cmd, count.div_ceil(LOCAL_SIZE), 1, 1) };
            });
            if let Some(timer) = timer {
                timer.write(cmd, vk::PipelineStageFlags2::COMPUTE_SHADER, 1);
            }
            buffer_barrier(device, cmd, &hit_buffer, Access::COMPUTE_WRITE, Access::HOST_READ);
            Ok(())
        })?;
        let mut hits: Vec<ProbeHit> = hit_buffer.read()?;
        hits.truncate(rays.len());
        let ms = match timer {
            Some(timer) => {
                let t = timer.read_ns()?;
                (t[1] - t[0]) / 1e6
            }
            None => 0.0,
        };
        Ok((hits, ms))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_match_the_glsl_scalar_structs() {
        assert_eq!(std::mem::size_of::<ProbeRay>(), 36);
        assert_eq!(std::mem::offset_of!(ProbeRay, flags), 32);
        assert_eq!(std::mem::offset_of!(ProbeRay, direction), 16);
        assert_eq!(std::mem::size_of::<ProbeHit>(), 16);
    }
}
