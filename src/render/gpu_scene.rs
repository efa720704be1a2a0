//! The scene on the GPU: per-primitive vertex, normal and index buffers, device-local.
use crate::scene::Scene;
use crate::vk::accel::BUILD_INPUT_USAGE;
use crate::vk::{Buffer, Device};
use anyhow::Result;
use ash::vk;
use glam::{Vec2, Vec3, Vec4};
use std::sync::Arc;

pub struct GpuPrimitive {
    pub positions: Buffer,
    pub normals: Buffer,
    /// TEXCOORD_0, zeros when the mesh has none.
    pub uvs: Buffer,
    /// TEXCOORD_1, TEXCOORD_0's values when the mesh has none (a material asking for set 1 then reads set 0).
    pub uvs1: Buffer,
    /// COLOR_0 as linear RGBA, white when the mesh has none.
    pub colors: Buffer,
    /// Surface derivatives Q_u and Q_v, zeros when the mesh has no UVs (bump mapping is then off).
    pub dpdu: Buffer,
    pub dpdv: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    pub vertex_count: u32,
    pub material: Option<usize>,
    /// The centre of its vertices' bounding box, in object space: where the G-buffer pass sorts its draws from.
    pub center: Vec3,
}

pub struct GpuMesh {
    pub name: String,
    pub primitives: Vec<GpuPrimitive>,
}

pub struct GpuScene {
    pub meshes: Vec<GpuMesh>,
}

impl GpuScene {
    pub fn upload(device: &Arc<Device>, scene: &Scene) -> Result<Self> {
        let mut meshes = Vec::with_capacity(scene.meshes.len());
        for mesh in &scene.meshes {
            let mut primitives = Vec::new();
            for (i, p) in mesh.primitives.iter().enumerate() {
                if p.indices.is_empty() {
                    continue;
                }
                let name = format!("{}/{i}", mesh.name);
                // Positions and indices also feed BLAS builds later.
                let positions = Buffer::device_local_with_data(
                    device,
                    &format!("{name} positions"),
                    &p.positions,
                    vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER | BUILD_INPUT_USAGE,
                    16,
                )?;
                // Every vertex stream is also read by address where rays hit (render::ray_scene).
                let by_address = vk::BufferUsageFlags::VERTEX_BUFFER
                    | vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
                let normals =
                    Buffer::device_local_with_data(device, &format!("{name} normals"), &p.normals, by_address, 16)?;
                // Streams a mesh may lack are filled for every vertex: zero UVs and derivatives, white colours.
                let n = p.positions.len();
                let uvs = vertex_stream(device, &format!("{name} uvs"), &p.uvs, Vec2::ZERO, n, by_address)?;
                let uvs1 = vertex_stream(device, &format!("{name} uvs1"), p.uvs1_or_uvs(), Vec2::ZERO, n, by_address)?;
                let colors = vertex_stream(device, &format!("{name} colors"), &p.colors, Vec4::ONE, n, by_address)?;
                let dpdu = vertex_stream(device, &format!("{name} dpdu"), &p.dpdu, Vec3::ZERO, n, by_address)?;
                let dpdv = vertex_stream(device, &format!("{name} dpdv"), &p.dpdv, Vec3::ZERO, n, by_address)?;
                let indices = Buffer::device_local_with_data(
                    device,
                    &format!("{name} indices"),
                    &p.indices,
                    vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER | BUILD_INPUT_USAGE,
                    16,
                )?;
                primitives.push(GpuPrimitive {
                    positions,
                    normals,
                    uvs,
                    uvs1,
                    colors,
                    dpdu,
                    dpdv,
                    indices,
                    index_count: p.indices.len() as u32,
                    vertex_count: p.positions.len() as u32,
                    material: p.material,
                    center: bounds_center(&p.positions),
                });
            }
            meshes.push(GpuMesh { name: mesh.name.clone(), primitives });
        }
        Ok(Self { meshes })
    }
}

/// The centre of the box around `positions` (the origin for none).
fn bounds_center(positions: &[Vec3]) -> Vec3 {
    let lo = positions.iter().copied().fold(Vec3::splat(f32::INFINITY), Vec3::min);
    let hi = positions.iter().copied().fold(Vec3::splat(f32::NEG_INFINITY), Vec3::max);
    if lo.x <= hi.x {
        0.5 * (lo + hi)
    } else {
        Vec3::ZERO
    }
}

/// A device-local vertex stream: `values`, or `fill` for each of `count` vertices where the mesh has none.
fn vertex_stream<T: bytemuck::Pod>(
    device: &Arc<Device>,
    name: &str,
    values: &[T],
    fill: T,
    count: usize,
    usage: vk::BufferUsageFlags,
) -> Result<Buffer> {
    if values.is_empty() {
        Buffer::device_local_with_data(device, name, &vec![fill; count], usage, 16)
    } else {
        Buffer::device_local_with_data(device, name, values, usage, 16)
    }
}
