//! What the host writes for each sample of a batch before the batch goes to the GPU (docs/architecture.md, "One
//! frame"): the camera sample (pixel jitter, shutter time, lens point), the instances and lights at that time
//! (TLAS instances, draw records, light records), the reference mode's camera, and the accumulation pass's push
//! constants. A batch's samples each have a slot of these buffers; the host refills them once per batch.
use super::accumulate::counter_bytes;
use super::accumulate_layout::{
    AccumulatePush, GpuCamera, GpuLight, COUNTERS_PER_SLOT, COUNTER_SECONDARY_RAYS, COUNTER_SHADOW_RAYS,
};
use super::deformed::{DeformedRays, DEFORMED_STREAMS};
use super::gbuffer::GBufferInputs;
use super::lights::LightSet;
use super::ray_scene::RayScene;
use crate::math::lens::{camera_sample, CameraSample};
use crate::math::sampling::{sample_1d, sample_2d};
use crate::scene::settings::RenderSettings;
use crate::scene::{Projection, Scene};
use crate::vk::accel::DynamicTlas;
use crate::vk::commands::Access;
use crate::vk::frame_graph::{FrameGraph, Use};
use crate::vk::{Buffer, Device, MemoryLocation};
use anyhow::Result;
use ash::vk;
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::sync::Arc;

/// Sampler dimensions the host draws once per sample for the whole image (docs/architecture.md's order).
use crate::shaders::constants::{DIM_LENS, DIM_PIXEL, DIM_TIME};

/// What a frame graph knows the TLAS and the deformed instances' BLASes by (the builds write them, with their
/// scratch; ray queries read them through the TLAS's handle): their barriers are global memory barriers.
pub const ACCELERATION_STRUCTURES: &str = "acceleration structures";

/// The 32-bit seed the shaders hash from the 64-bit setting.
pub fn seed32(seed: u64) -> u32 {
    (seed ^ (seed >> 32)) as u32
}

/// Sample `index` of `count`'s shutter time, lens point and camera matrices (the same for every pixel).
pub fn camera_sample_at(
    scene: &Scene,
    settings: &RenderSettings,
    index: u32,
) -> (f32, CameraSample, crate::scene::Camera) {
    let (kind, seed, count) = (settings.sampler, seed32(settings.seed), settings.spp);
    let jitter = sample_2d(kind, seed, 0, index, count, DIM_PIXEL) - Vec2::splat(0.5);
    let (open, close) = scene.shutter;
    // A closed shutter interval is the still frame exactly.
    let t = if close > open { open + (close - open) * sample_1d(kind, seed, 0, index, count, DIM_TIME) } else { open };
    let lens = sample_2d(kind, seed, 0, index, count, DIM_LENS);
    let camera = scene.camera_at(t);
    let sample = camera_sample(&camera, settings.width, settings.height, lens, jitter);
    (t, sample, camera)
}

/// The key the G-buffer pass hashes with each pixel and triangle for BLEND's stochastic coverage in sample `index`
/// (gbuffer.frag): every sample draws its own.
pub fn coverage_key(seed: u32, index: u32) -> u32 {
    seed ^ index.wrapping_mul(0x9e37_79b9)
}

/// The camera the reference mode's primary rays start from (`camera_ray` in accumulate.comp).
pub fn gpu_camera(camera: &crate::scene::Camera, width: u32, height: u32) -> GpuCamera {
    let m = camera.world_from_camera;
    // Half the image's extent, read off the raster pass's own projection (x_c = x / half_x, y_c = -y / half_y
    // on the plane at distance 1, or in metres orthographically), so both modes frame the image alike.
    let clip_from_view = camera.clip_from_view(width as f32 / height as f32);
    let half = Vec2::new(1.0 / clip_from_view.x_axis.x, -1.0 / clip_from_view.y_axis.y);
    let (orthographic, near, far) = match camera.projection {
        Projection::Perspective { znear, zfar, .. } => (false, znear, zfar.unwrap_or(f32::MAX)),
        Projection::Orthographic { znear, zfar, .. } => (true, znear, zfar),
    };
    let (aperture, focus) =
        if orthographic { (0.0, 1.0) } else { (camera.lens.aperture_radius, camera.lens.focus_distance) };
    GpuCamera {
        world_from_camera: [m.x_axis, m.y_axis, m.z_axis, m.w_axis],
        lens: Vec4::new(half.x, half.y, aperture, focus),
        range: Vec4::new(near, far, if orthographic { 1.0 } else { 0.0 }, 0.0),
    }
}

/// One sample as the batch's command buffer records it.
pub struct SampleRecord {
    pub camera: CameraSample,
    pub push: AccumulatePush,
}

/// The per-sample buffers of a batch (one slot per sample) and what fills them.
pub struct SampleSlots<'a> {
    scene: &'a Scene,
    settings: &'a RenderSettings,
    ray_scene: &'a RayScene,
    /// Node transforms at rest (lights on nodes move from there) and the scene's radius (a directional light's
    /// power for selection).
    rest: Vec<Mat4>,
    radius: f32,
    pub tlas: DynamicTlas,
    /// Deformed instances' BLASes and the primitive records with theirs; None when nothing deforms.
    pub deformed_rays: Option<DeformedRays>,
    pub lights: Buffer,
    pub counters: Buffer,
    pub cameras: Buffer,
    /// The G-buffer pass's draw records.
    pub draws: GBufferInputs<'a>,
    light_capacity: usize,
    skipped_warned: bool,
}

impl<'a> SampleSlots<'a> {
    pub fn new(
        device: &Arc<Device>,
        scene: &'a Scene,
        settings: &'a RenderSettings,
        ray_scene: &'a RayScene,
        draws: GBufferInputs<'a>,
        batch: u32,
    ) -> Result<Self> {
        let tlas = DynamicTlas::new(device, "scene TLAS", ray_scene.traced_instances.len() as u32, batch)?;
        let deformed_rays = match draws.deformed.is_empty() {
            true => None,
            false => Some(DeformedRays::new(device, scene, draws.geometry(), ray_scene, &draws.deformed)?),
        };
        let rest = scene.node_world_transforms(None);
        let radius = scene.bounds().map(|(lo, hi)| (hi - lo).length() * 0.5).unwrap_or(1.0);
        let first = lights_at(scene, &rest, radius, scene.shutter.0).0;
        // Room for the analytic lights (the environment, then the scene's lights: some may drop out at a time
        // where their node's transform is not finite) and the emissive lights, whose count does not change.
        let analytic_capacity = usize::from(scene.environment.is_some()) + scene.lights.len();
        let light_capacity = (analytic_capacity + first.lights.len() - first.analytic).max(1);
        let per_slot = |name: &str, bytes_per_slot: u64, location: MemoryLocation| {
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
            Buffer::new(device, name, bytes_per_slot * u64::from(batch), usage, location, 16)
        };
        let light_bytes = (light_capacity * std::mem::size_of::<GpuLight>()) as u64;
        Ok(Self {
            lights: per_slot("lights", light_bytes, MemoryLocation::CpuToGpu)?,
            counters: per_slot("sample counters", counter_bytes(1), MemoryLocation::GpuToCpu)?,
            cameras: per_slot("sample cameras", std::mem::size_of::<GpuCamera>() as u64, MemoryLocation::CpuToGpu)?,
            scene,
            settings,
            ray_scene,
            rest,
            radius,
            tlas,
            deformed_rays,
            draws,
            light_capacity,
            skipped_warned: false,
        })
    }

    /// Writes sample `index` into `slot`: the TLAS instances, lights and draws at its shutter time and its
    /// camera. `frame` holds the push constants every sample shares; the sample's own are filled in.
    pub fn fill(&mut self, slot: u32, index: u32, frame: &AccumulatePush) -> Result<SampleRecord> {
        let (width, height) = (self.settings.width, self.settings.height);
        let (t, camera_sample, camera) = camera_sample_at(self.scene, self.settings, index);
        // Node transforms once per sample: instances (TLAS, draws) and lights all come from them.
        let (set, node_world, transforms) = lights_at(self.scene, &self.rest, self.radius, t);
        // Deformed instances first: their BLAS and records in this slot stand in for their mesh's.
        self.draws.write_slot(slot, self.scene, (t, &node_world), &transforms, coverage_key(frame.seed, index))?;
        let own = |i: usize| {
            let rays = self.deformed_rays.as_ref()?;
            let k = self.draws.deformed.index_of(i)?;
            Some(rays.instance_in_slot(k, slot))
        };
        let instances = self.ray_scene.tlas_instances_with(self.scene, &transforms, own);
        self.tlas.write_slot(slot, &instances)?;
        if set.skipped_triangles > 0 && !self.skipped_warned {
            self.skipped_warned = true;
            eprintln!(
                "warning: {} emissive triangles beyond the first {} are not sampled as lights",
                set.skipped_triangles,
                super::lights::MAX_EMISSIVE_TRIANGLES
            );
        }
        let light_count = set.lights.len().min(self.light_capacity);
        let light_bytes = (self.light_capacity * std::mem::size_of::<GpuLight>()) as u64;
        self.lights.write(u64::from(slot) * light_bytes, bytemuck::cast_slice(&set.lights[..light_count]))?;
        let camera_bytes = std::mem::size_of::<GpuCamera>() as u64;
        self.cameras.write(u64::from(slot) * camera_bytes, bytemuck::bytes_of(&gpu_camera(&camera, width, height)))?;
        let orthographic = matches!(camera.projection, Projection::Orthographic { .. });
        let forward = camera.world_from_camera.transform_vector3(-Vec3::Z).normalize_or_zero();
        let push = AccumulatePush {
            eye: camera_sample.eye.extend(if orthographic { 1.0 } else { 0.0 }),
            forward: forward.extend(0.0),
            sample_index: index,
            light_offset: (slot as usize * self.light_capacity) as u32,
            light_count: light_count as u32,
            analytic_light_count: set.analytic.min(light_count) as u32,
            counter_slot: slot,
            total_light_power: set.total_power,
            ray_log: if index == 0 { frame.ray_log } else { 0 },
            ..*frame
        };
        Ok(SampleRecord { camera: camera_sample, push })
    }

    /// The primitive records the accumulation pass reads: the scene's, with the deformed instances' per slot.
    pub fn primitive_records(&self) -> &Buffer {
        self.deformed_rays.as_ref().map_or(&self.ray_scene.records, |d| &d.records)
    }

    /// Records sample `slot`'s acceleration-structure builds as passes of `graph`: the deformed instances'
    /// BLASes, then the TLAS, which refers to them. Each writes [`ACCELERATION_STRUCTURES`].
    pub fn record_builds(&self, graph: &mut FrameGraph, cmd: vk::CommandBuffer, slot: u32) {
        let builds = [Use::write_memory(ACCELERATION_STRUCTURES, Access::AS_BUILD_READ_WRITE)];
        if let Some(deformed) = &self.deformed_rays {
            let uses = [builds[0], Use::read_memory(DEFORMED_STREAMS, Access::AS_BUILD_INPUT_READ)];
            graph.pass(cmd, "deformed BLAS builds", &uses, || deformed.record_builds(cmd, slot));
        }
        graph.pass(cmd, "TLAS build", &builds, || self.tlas.record_build(cmd, slot));
    }

    /// Zeroes the ray counters (and the queues of pixel runs) of `slots` slots before a batch.
    pub fn reset_counters(&mut self, slots: u32) -> Result<()> {
        self.counters.write(0, &vec![0u8; counter_bytes(slots) as usize])
    }

    /// The shadow and secondary rays the first `slots` slots counted.
    pub fn rays_counted(&self, slots: u32) -> Result<(u64, u64)> {
        let counts: Vec<u32> = self.counters.read()?;
        let slot = |s: usize, counter: usize| u64::from(counts[s * COUNTERS_PER_SLOT + counter]);
        let slots = 0..slots as usize;
        Ok(slots.fold((0, 0), |(shadow, secondary), s| {
            (shadow + slot(s, COUNTER_SHADOW_RAYS), secondary + slot(s, COUNTER_SECONDARY_RAYS))
        }))
    }
}

/// The lights at time `t`, and the node and instance transforms they come from.
fn lights_at(scene: &Scene, rest: &[Mat4], radius: f32, t: f32) -> (LightSet, Vec<Mat4>, Vec<Mat4>) {
    let moved = scene.node_world_transforms(Some(t));
    let transforms = scene.instance_transforms_from(&moved);
    (LightSet::at(scene, (Some(t), &moved), &transforms, rest, radius), moved, transforms)
}
