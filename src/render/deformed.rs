//! Deformed instances on the GPU (docs/architecture.md, "Deformed meshes"): a skinned or morphing instance's
//! positions, normals and surface derivatives change with time, so each sample of a batch gets its own copy of
//! them and its own BLAS, rebuilt from that copy in the sample's commands before the TLAS that places it. A
//! skinned instance's copy is written by the skinning pass (`render::skinning`) from the sample's joint matrices,
//! the one thing the host writes for it per sample (with its morphed streams where a clip animates its morph
//! weights); a morphing instance without a skin has its copy written by the host (`scene::morph`). The streams
//! that do not move (UVs, colours, indices) stay the mesh's.
use super::accumulate_layout::GpuPrimitiveRecord;
use super::gpu_scene::{GpuPrimitive, GpuScene};
use super::ray_scene::{is_opaque, RayScene};
use super::skinning::{gpu_influences, SkinPush, SkinningPass};
use crate::scene::skin::DeformedVertices;
use crate::scene::{Primitive, Scene};
use crate::vk::accel::{AccelerationStructure, DynamicBlas, TriangleGeometry, BUILD_INPUT_USAGE};
use crate::vk::commands::Access;
use crate::vk::frame_graph::{FrameGraph, Use};
use crate::vk::{Buffer, Device, MemoryLocation};
use anyhow::{bail, Context as _, Result};
use ash::vk;
use glam::{Mat4, Vec3};
use std::sync::Arc;

/// What a frame graph knows the deformed instances' vertex streams by: the skinning pass writes them, the BLAS
/// builds, the G-buffer pass and the rays read them (through many buffers and device addresses, so their barriers
/// are global memory barriers).
pub const DEFORMED_STREAMS: &str = "deformed vertex streams";

/// Positions, normals, dpdu and dpdv: the four streams that deform, each of 12-byte vectors.
type Streams = [Buffer; 4];

/// One primitive's moving streams: `slots` copies of `vertex_count` vertices each.
pub struct DeformedPrimitive {
    pub positions: Buffer,
    pub normals: Buffer,
    pub dpdu: Buffer,
    pub dpdv: Buffer,
    pub vertex_count: u32,
    /// Where the primitive is skinned on the GPU: what the skinning pass reads.
    skinning: Option<SkinnedPrimitive>,
}

/// What the skinning pass reads for one primitive: its influences, and the streams it skins from.
struct SkinnedPrimitive {
    influences: Buffer,
    set_count: u32,
    /// The mesh's streams (one copy, device-local), or, where its instance morphs (`DeformedInstance::morphs`),
    /// `slots` copies the host morphs into (host-visible).
    source: Streams,
}

impl DeformedPrimitive {
    /// `slots` copies of `vertex_count` vertices, written by the skinning pass where `skinning` is given (then
    /// device-local) and by the host otherwise (host-visible).
    fn new(
        device: &Arc<Device>,
        name: &str,
        vertex_count: u32,
        slots: u32,
        skinning: Option<SkinnedPrimitive>,
    ) -> Result<Self> {
        let usage = vk::BufferUsageFlags::VERTEX_BUFFER
            | vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | BUILD_INPUT_USAGE;
        let location = if skinning.is_some() { MemoryLocation::GpuOnly } else { MemoryLocation::CpuToGpu };
        let bytes = (u64::from(vertex_count) * 12 * u64::from(slots)).max(12);
        let stream = |what: &str| Buffer::new(device, &format!("{name} deformed {what}"), bytes, usage, location, 16);
        Ok(DeformedPrimitive {
            positions: stream("positions")?,
            normals: stream("normals")?,
            dpdu: stream("dpdu")?,
            dpdv: stream("dpdv")?,
            vertex_count,
            skinning,
        })
    }

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
    /// A skinned instance's joint matrices, `joint_count` per slot (host-visible).
    joints: Option<Buffer>,
    joint_count: u32,
    /// A clip animates its morph weights: the host morphs it per slot.
    morphs: bool,
}

/// The moving vertex streams of every deformed instance, `slots` samples' worth.
pub struct DeformedStreams {
    pub instances: Vec<DeformedInstance>,
    /// Per scene instance: its index in `instances`, if it deforms.
    index_of: Vec<Option<usize>>,
    slots: u32,
    /// Present where some instance is skinned.
    skinning: Option<SkinningPass>,
}

impl SkinnedPrimitive {
    /// What the skinning pass reads for `loaded` (its `vertex_count` vertices as GpuScene holds them): its
    /// influences, and its streams once, or room for `slots` morphed copies where the clip animates its weights.
    fn new(
        device: &Arc<Device>,
        name: &str,
        loaded: &Primitive,
        vertex_count: u32,
        slots: u32,
        morphs: bool,
    ) -> Result<Self> {
        let count = vertex_count as usize;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let bytes = (u64::from(vertex_count) * 12 * u64::from(slots)).max(12);
        let loaded_streams = streams_of(loaded);
        let stream = |k: usize| -> Result<Buffer> {
            let what = STREAM_NAMES[k];
            if morphs {
                let name = format!("{name} morphed {what}");
                Buffer::new(device, &name, bytes, usage, MemoryLocation::CpuToGpu, 16)
            } else {
                let name = format!("{name} rest {what}");
                Buffer::device_local_with_data(device, &name, &padded(loaded_streams[k], count.max(1)), usage, 16)
            }
        };
        let source = [stream(0)?, stream(1)?, stream(2)?, stream(3)?];
        let mut influences = gpu_influences(&loaded.skin_influences, count);
        if influences.is_empty() {
            influences.push(Default::default());
        }
        let influences =
            Buffer::device_local_with_data(device, &format!("{name} joint influences"), &influences, usage, 16)?;
        Ok(Self { influences, set_count: loaded.skin_influences.len() as u32, source })
    }
}

/// `values` padded with zeros to `count` vectors (a stream a primitive lacks is zeros, as GpuScene fills it).
fn padded(values: &[Vec3], count: usize) -> Vec<Vec3> {
    let mut out = values.to_vec();
    out.resize(count, Vec3::ZERO);
    out
}

/// A primitive's four deforming streams, in `Streams` order.
fn streams_of(p: &Primitive) -> [&[Vec3]; 4] {
    [&p.positions, &p.normals, &p.dpdu, &p.dpdv]
}

const STREAM_NAMES: [&str; 4] = ["positions", "normals", "dpdu", "dpdv"];

impl DeformedStreams {
    pub fn new(device: &Arc<Device>, scene: &Scene, geometry: &GpuScene, slots: u32) -> Result<Self> {
        let slots = slots.max(1);
        let mut index_of = vec![None; scene.instances.len()];
        let mut instances = Vec::new();
        for instance in scene.deformed_instances() {
            let name = &scene.instances[instance].name;
            let skin = scene.instance_skin(instance);
            let morphs = scene.has_animated_weights(instance);
            let mesh = scene.instances[instance].mesh;
            // GpuScene leaves out primitives without triangles; so do the streams.
            let kept = scene.meshes[mesh].primitives.iter().filter(|p| !p.indices.is_empty());
            let primitives = geometry.meshes[mesh]
                .primitives
                .iter()
                .zip(kept)
                .enumerate()
                .map(|(p, (gpu, loaded))| {
                    let name = format!("{name}/{p}");
                    let skinning = match skin {
                        Some(_) => Some(SkinnedPrimitive::new(device, &name, loaded, gpu.vertex_count, slots, morphs)?),
                        None => None,
                    };
                    DeformedPrimitive::new(device, &name, gpu.vertex_count, slots, skinning)
                })
                .collect::<Result<Vec<_>>>()?;
            let joint_count = skin.map_or(0, |s| s.joints.len() as u32);
            let joints = match skin {
                Some(_) => Some(Buffer::new(
                    device,
                    &format!("{name} joint matrices"),
                    u64::from(joint_count.max(1)) * 64 * u64::from(slots),
                    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
                    MemoryLocation::CpuToGpu,
                    16,
                )?),
                None => None,
            };
            index_of[instance] = Some(instances.len());
            instances.push(DeformedInstance { instance, primitives, joints, joint_count, morphs });
        }
        let any_skin = instances.iter().any(|i| i.joints.is_some());
        let skinning = if any_skin { Some(SkinningPass::new(device)?) } else { None };
        Ok(Self { instances, index_of, slots, skinning })
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

    /// Writes what `slot` deforms from at time `t`, whose node transforms are `node_world`: a skinned instance's
    /// joint matrices (and its morphed streams where the clip animates its weights), a morphing instance's
    /// morphed streams themselves. The skinning pass (`record_skinning`) does the rest on the GPU.
    pub fn write_slot(&mut self, slot: u32, scene: &Scene, node_world: &[Mat4], t: f32) -> Result<()> {
        if slot >= self.slots {
            bail!("deformed streams: slot {slot} of {}", self.slots);
        }
        for deformed in &mut self.instances {
            let instance = deformed.instance;
            if let (Some(joints), Some(skin)) = (&mut deformed.joints, scene.instance_skin(instance)) {
                let matrices = skin.joint_matrices(node_world);
                joints
                    .write(u64::from(slot) * u64::from(deformed.joint_count) * 64, bytemuck::cast_slice(&matrices))?;
            }
            // A deformed instance that does not morph is skinned: its joint matrices are all it needs.
            if !deformed.morphs {
                continue;
            }
            // Morphed at t (GpuScene leaves out primitives without triangles; so do the streams), then written
            // where the skinning pass reads them or, without a skin, where everything else does.
            let mesh = &scene.meshes[scene.instances[instance].mesh];
            let morphed = scene.morph_instance(instance, Some(t));
            let kept = mesh.primitives.iter().zip(morphed).filter(|(p, _)| !p.indices.is_empty());
            for (gpu, (loaded, morphed)) in deformed.primitives.iter_mut().zip(kept) {
                let count = gpu.vertex_count as usize;
                let offset = gpu.offset(slot);
                let values = streams_of(morphed.as_ref().unwrap_or(loaded)).map(|s| padded(s, count));
                let targets: [&mut Buffer; 4] = match &mut gpu.skinning {
                    Some(skinning) => {
                        let [a, b, c, d] = &mut skinning.source;
                        [a, b, c, d]
                    }
                    None => [&mut gpu.positions, &mut gpu.normals, &mut gpu.dpdu, &mut gpu.dpdv],
                };
                for (target, values) in targets.into_iter().zip(&values) {
                    target.write(offset, bytemuck::cast_slice(values))?;
                }
            }
        }
        Ok(())
    }

    /// Records `slot`'s skinning, before anything reads the slot's streams (the BLAS builds first).
    pub fn record_skinning(&self, graph: &mut FrameGraph, cmd: vk::CommandBuffer, slot: u32) {
        let Some(pass) = &self.skinning else { return };
        let written = [Use::write_memory(DEFORMED_STREAMS, Access::COMPUTE_WRITE)];
        graph.pass(cmd, "skinning pass", &written, || {
            for deformed in &self.instances {
                let Some(joints) = &deformed.joints else { continue };
                for gpu in &deformed.primitives {
                    let Some(skinning) = &gpu.skinning else { continue };
                    if gpu.vertex_count == 0 {
                        continue;
                    }
                    let offset = gpu.offset(slot);
                    let source_offset = if deformed.morphs { offset } else { 0 };
                    let [positions, normals, dpdu, dpdv] =
                        skinning.source.each_ref().map(|b| b.address + source_offset);
                    let push = SkinPush {
                        positions,
                        normals,
                        dpdu,
                        dpdv,
                        out_positions: gpu.positions.address + offset,
                        out_normals: gpu.normals.address + offset,
                        out_dpdu: gpu.dpdu.address + offset,
                        out_dpdv: gpu.dpdv.address + offset,
                        influences: skinning.influences.address,
                        joint_matrices: joints.address + u64::from(slot) * u64::from(deformed.joint_count) * 64,
                        vertex_count: gpu.vertex_count,
                        set_count: skinning.set_count,
                        joint_count: deformed.joint_count,
                        pad: 0,
                    };
                    pass.record(cmd, &push);
                }
            }
        });
    }

    /// `slot`'s deformed streams read back to the host, per deformed instance and primitive (what the skinning
    /// pass or the host wrote there): for tests that hold the GPU's skinning to its host twin.
    pub fn read_slot(&self, device: &Arc<Device>, slot: u32) -> Result<Vec<Vec<DeformedVertices>>> {
        let after = Access::COMPUTE_WRITE;
        let mut out = Vec::with_capacity(self.instances.len());
        for deformed in &self.instances {
            let mut primitives = Vec::with_capacity(deformed.primitives.len());
            for gpu in &deformed.primitives {
                let range = |all: Vec<Vec3>| -> Vec<Vec3> {
                    let first = slot as usize * gpu.vertex_count as usize;
                    all[first..first + gpu.vertex_count as usize].to_vec()
                };
                let read = |b: &Buffer| -> Result<Vec<Vec3>> {
                    Ok(range(
                        crate::vk::readback::read_buffer::<f32>(device, b, after)?
                            .chunks_exact(3)
                            .map(Vec3::from_slice)
                            .collect(),
                    ))
                };
                primitives.push(DeformedVertices {
                    positions: read(&gpu.positions)?,
                    normals: read(&gpu.normals)?,
                    dpdu: read(&gpu.dpdu)?,
                    dpdv: read(&gpu.dpdv)?,
                });
            }
            out.push(primitives);
        }
        Ok(out)
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
