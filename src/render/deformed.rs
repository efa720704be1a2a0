//! Deformed instances on the GPU (docs/architecture.md, "Deformed meshes"): a skinned or morphing instance's positions, normals
//! and surface derivatives change with time, so each sample of a batch gets its own copy of them, written by the
//! host at the sample's shutter time (`scene::skin`, `scene::morph`), and its own BLAS, rebuilt from that copy in the sample's
//! commands before the TLAS that places it. The streams that do not move (UVs, colours, indices) stay the mesh's.
use super::accumulate_layout::GpuPrimitiveRecord;
use super::gpu_scene::{GpuPrimitive, GpuScene};
use super::ray_scene::{is_opaque, RayScene};
use crate::scene::Scene;
use crate::vk::accel::{AccelerationStructure, DynamicBlas, TriangleGeometry, BUILD_INPUT_USAGE};
use crate::vk::{Buffer, Device, MemoryLocation};
use anyhow::{bail, Context as _, Result};
use ash::vk;
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// One primitive's moving streams: `slots` copies of `vertex_count` vertices each, host-visible.
pub struct DeformedPrimitive {
    pub positions: Buffer,
    pub normals: Buffer,
    pub dpdu: Buffer,
    pub dpdv: Buffer,
    pub vertex_count: u32,
}

impl DeformedPrimitive {
    /// Where `slot`'s copy starts in each stream (all four hold 12-byte vectors).
    pub fn offset(&self, slot: u32) -> u64 {
        u64::from(slot) * u64::from(self.vertex_count) * 12
    }
}

/// A deformed scene instance: its mesh's primitives as GpuScene holds them (those with triangles), each with
/// streams of its own.
pub struct DeformedInstance {
    pub instance: usize,
    pub primitives: Vec<DeformedPrimitive>,
}

/// The moving vertex streams of every deformed instance, `slots` samples' worth.
pub struct DeformedStreams {
    pub instances: Vec<DeformedInstance>,
    /// Per scene instance: its index in `instances`, if it deforms.
    index_of: Vec<Option<usize>>,
    slots: u32,
}

impl DeformedStreams {
    pub fn new(device: &Arc<Device>, scene: &Scene, geometry: &GpuScene, slots: u32) -> Result<Self> {
        let slots = slots.max(1);
        let mut index_of = vec![None; scene.instances.len()];
        let mut instances = Vec::new();
        for instance in scene.deformed_instances() {
            let name = &scene.instances[instance].name;
            let usage = vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER | BUILD_INPUT_USAGE;
            let primitives = geometry.meshes[scene.instances[instance].mesh]
                .primitives
                .iter()
                .enumerate()
                .map(|(p, gpu)| {
                    let bytes = (u64::from(gpu.vertex_count) * 12 * u64::from(slots)).max(12);
                    let stream = |what: &str| {
                        let name = format!("{name}/{p} deformed {what}");
                        Buffer::new(device, &name, bytes, usage, MemoryLocation::CpuToGpu, 16)
                    };
                    Ok(DeformedPrimitive {
                        positions: stream("positions")?,
                        normals: stream("normals")?,
                        dpdu: stream("dpdu")?,
                        dpdv: stream("dpdv")?,
                        vertex_count: gpu.vertex_count,
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            index_of[instance] = Some(instances.len());
            instances.push(DeformedInstance { instance, primitives });
        }
        Ok(Self { instances, index_of, slots })
    }

    pub fn is_empty(&self) -> bool {
        self.instances.is_empty()
    }

    /// The streams of scene instance `instance`, if it deforms.
    pub fn of_instance(&self, instance: usize) -> Option<&DeformedInstance> {
        self.index_of(instance).map(|i| &self.instances[i])
    }

    /// Where scene instance `instance` is in `instances`, if it deforms.
    pub fn index_of(&self, instance: usize) -> Option<usize> {
        self.index_of.get(instance).copied().flatten()
    }

    /// Deforms every instance at time `t`, whose node transforms are `node_world`, into `slot`.
    pub fn write_slot(&mut self, slot: u32, scene: &Scene, node_world: &[Mat4], t: f32) -> Result<()> {
        if slot >= self.slots {
            bail!("deformed streams: slot {slot} of {}", self.slots);
        }
        for deformed in &mut self.instances {
            let vertices = scene.deform_instance(deformed.instance, node_world, Some(t)).unwrap_or_default();
            // GpuScene leaves out primitives without triangles; so do the streams.
            let mesh = &scene.meshes[scene.instances[deformed.instance].mesh];
            let kept = mesh.primitives.iter().zip(vertices).filter(|(p, _)| !p.indices.is_empty()).map(|(_, v)| v);
            for (gpu, v) in deformed.primitives.iter_mut().zip(kept) {
                let count = gpu.vertex_count as usize;
                let offset = gpu.offset(slot);
                let padded = |values: &[Vec3]| -> Vec<Vec3> {
                    let mut out = values.to_vec();
                    out.resize(count, Vec3::ZERO);
                    out
                };
                gpu.positions.write(offset, bytemuck::cast_slice(&padded(&v.positions)))?;
                gpu.normals.write(offset, bytemuck::cast_slice(&padded(&v.normals)))?;
                gpu.dpdu.write(offset, bytemuck::cast_slice(&padded(&v.dpdu)))?;
                gpu.dpdv.write(offset, bytemuck::cast_slice(&padded(&v.dpdv)))?;
            }
        }
        Ok(())
    }
}

/// What rays see of the deformed instances: a BLAS each, rebuilt per sample from that sample's streams, and the
/// primitive records of every slot after the scene's own (`records`, which then replaces `RayScene::records`).
pub struct DeformedRays {
    blases: Vec<DynamicBlas>,
    /// Per deformed instance and slot, the geometries its BLAS builds from.
    geometries: Vec<Vec<Vec<TriangleGeometry>>>,
    /// The first primitive record of (slot, deformed instance).
    first_record: Vec<Vec<u32>>,
    pub records: Buffer,
}

impl DeformedRays {
    pub fn new(
        device: &Arc<Device>,
        scene: &Scene,
        geometry: &GpuScene,
        ray_scene: &RayScene,
        streams: &DeformedStreams,
    ) -> Result<Self> {
        let mut records = ray_scene.record_list.clone();
        let default_material = scene.materials.len() as u32;
        let mut first_record = Vec::with_capacity(streams.slots as usize);
        for slot in 0..streams.slots {
            let mut firsts = Vec::with_capacity(streams.instances.len());
            for deformed in &streams.instances {
                firsts.push(records.len() as u32);
                let mesh = &geometry.meshes[scene.instances[deformed.instance].mesh];
                for (moving, fixed) in deformed.primitives.iter().zip(&mesh.primitives) {
                    records.push(record(moving, fixed, slot, default_material));
                }
            }
            first_record.push(firsts);
        }
        let mut blases = Vec::with_capacity(streams.instances.len());
        let mut geometries = Vec::with_capacity(streams.instances.len());
        for deformed in &streams.instances {
            let instance = &scene.instances[deformed.instance];
            let mesh = &geometry.meshes[instance.mesh];
            let per_slot: Vec<Vec<TriangleGeometry>> = (0..streams.slots)
                .map(|slot| {
                    let pairs = deformed.primitives.iter().zip(&mesh.primitives);
                    pairs
                        .map(|(moving, fixed)| TriangleGeometry {
                            vertex_address: moving.positions.address + moving.offset(slot),
                            vertex_stride: 12,
                            vertex_count: moving.vertex_count,
                            index_address: fixed.indices.address,
                            triangle_count: fixed.index_count / 3,
                            opaque: is_opaque(scene, fixed.material),
                        })
                        .collect()
                })
                .collect();
            let name = format!("{} deformed BLAS", instance.name);
            blases.push(DynamicBlas::new(device, &name, &per_slot[0]).with_context(|| name.clone())?);
            geometries.push(per_slot);
        }
        let records = Buffer::with_data(
            device,
            "primitive records with deformed instances",
            &records,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            16,
        )?;
        Ok(Self { blases, geometries, first_record, records })
    }

    /// The BLAS and first primitive record that deformed instance `k` (of `DeformedStreams::instances`) has in
    /// `slot`.
    pub fn instance_in_slot(&self, k: usize, slot: u32) -> (&AccelerationStructure, u32) {
        (&self.blases[k].structure, self.first_record[slot as usize][k])
    }

    /// Records the rebuild of every deformed BLAS from `slot`'s streams (before that slot's TLAS build).
    pub fn record_builds(&self, cmd: vk::CommandBuffer, slot: u32) {
        for (blas, geometries) in self.blases.iter().zip(&self.geometries) {
            blas.record_build(cmd, &geometries[slot as usize]);
        }
    }
}

/// A deformed primitive's record in `slot`: the moving streams at the slot's copy, the rest the mesh's.
fn record(moving: &DeformedPrimitive, fixed: &GpuPrimitive, slot: u32, default_material: u32) -> GpuPrimitiveRecord {
    let offset = moving.offset(slot);
    GpuPrimitiveRecord {
        positions: moving.positions.address + offset,
        normals: moving.normals.address + offset,
        uvs: fixed.uvs.address,
        indices: fixed.indices.address,
        colors: fixed.colors.address,
        dpdu: moving.dpdu.address + offset,
        dpdv: moving.dpdv.address + offset,
        material: fixed.material.map(|m| m as u32).unwrap_or(default_material),
        pad: 0,
        uvs1: fixed.uvs1.address,
    }
}
