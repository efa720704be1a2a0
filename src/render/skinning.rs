//! The skinning pass (`shaders/skin.comp`; docs/architecture.md, "Deformed meshes"): each sample's skinned
//! vertices, computed on the GPU from the sample's joint matrices, which are all the host writes per sample. One
//! dispatch per skinned primitive, one invocation per vertex. The host's `scene::skin::skin_vertices` is its twin.
use crate::scene::skin::JointInfluences;
use crate::shaders;
use crate::shaders::constants::SKIN_WORKGROUP_SIZE;
use crate::vk::pipeline::Pipeline;
use crate::vk::Device;
use anyhow::Result;
use ash::vk;
use std::sync::Arc;

/// Mirrors `SkinPush` in `skin.comp`: where one primitive's streams are for one sample, by device address.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkinPush {
    /// The streams skinning starts from (the mesh's, or the sample's morphed copy).
    pub positions: u64,
    pub normals: u64,
    pub dpdu: u64,
    pub dpdv: u64,
    /// The sample's copy of the skinned streams.
    pub out_positions: u64,
    pub out_normals: u64,
    pub out_dpdu: u64,
    pub out_dpdv: u64,
    /// `vertex_count` × `set_count` [`GpuInfluence`]s, vertex by vertex.
    pub influences: u64,
    /// The sample's `joint_count` joint matrices (column-major `Mat4`s).
    pub joint_matrices: u64,
    pub vertex_count: u32,
    pub set_count: u32,
    pub joint_count: u32,
    pub pad: u32,
}

/// Mirrors `GpuInfluence` in `skin.comp`: one vertex's four joints of one `JOINTS_n`/`WEIGHTS_n` pair (16 bits
/// each, the first of a pair in the low half) and their weights.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuInfluence {
    pub joints01: u32,
    pub joints23: u32,
    pub weights: [f32; 4],
}

/// A primitive's influence sets as the pass reads them: for each of `vertex_count` vertices, one entry per set.
/// A set shorter than the vertex count (the loader rejects such files) gives the missing vertices no weight.
pub fn gpu_influences(sets: &[JointInfluences], vertex_count: usize) -> Vec<GpuInfluence> {
    let pair = |a: u16, b: u16| u32::from(a) | (u32::from(b) << 16);
    (0..vertex_count)
        .flat_map(|v| {
            sets.iter().map(move |set| match (set.joints.get(v), set.weights.get(v)) {
                (Some(j), Some(w)) => {
                    GpuInfluence { joints01: pair(j[0], j[1]), joints23: pair(j[2], j[3]), weights: w.to_array() }
                }
                _ => GpuInfluence::default(),
            })
        })
        .collect()
}

pub struct SkinningPass {
    pipeline: Pipeline,
    device: Arc<Device>,
}

impl SkinningPass {
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let pipeline = Pipeline::compute(
            device,
            "skinning pipeline",
            ("skin.comp", shaders::SKIN_COMP),
            &[],
            std::mem::size_of::<SkinPush>() as u32,
        )?;
        Ok(Self { pipeline, device: device.clone() })
    }

    /// Records one primitive's skinning (inside a pass the caller declares to the frame graph).
    pub fn record(&self, cmd: vk::CommandBuffer, push: &SkinPush) {
        self.pipeline.bind(cmd, None, bytemuck::bytes_of(push));
        let groups = push.vertex_count.div_ceil(SKIN_WORKGROUP_SIZE);
        unsafe { self.device.raw.cmd_dispatch(cmd, groups, 1, 1) };
    }
}
