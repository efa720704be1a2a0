//! The scene on the GPU: per-primitive vertex, normal and index buffers, device-local.
use crate::scene::Scene;
use crate::vk::accel::BUILD_INPUT_USAGE;
use crate::vk::{Buffer, Device};
use anyhow::Result;
use ash::vk;
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
                let uv_data = if p.uvs.is_empty() { vec![glam::Vec2::ZERO; p.positions.len()] } else { p.uvs.clone() };
                let uvs = Buffer::device_local_with_data(device, &format!("{name} uvs"), &uv_data, by_address, 16)?;
                let uv1_data = if p.uvs1.len() == p.positions.len() { p.uvs1.clone() } else { uv_data };
                let uvs1 = Buffer::device_local_with_data(device, &format!("{name} uvs1"), &uv1_data, by_address, 16)?;
                let color_data =
                    if p.colors.is_empty() { vec![glam::Vec4::ONE; p.positions.len()] } else { p.colors.clone() };
                let colors =
                    Buffer::device_local_with_data(device, &format!("{name} colors"), &color_data, by_address, 16)?;
                let derivative = |name: &str, values: &[glam::Vec3]| {
                    let data =
                        if values.is_empty() { vec![glam::Vec3::ZERO; p.positions.len()] } else { values.to_vec() };
                    Buffer::device_local_with_data(device, name, &data, by_address, 16)
                };
                let dpdu = derivative(&format!("{name} dpdu"), &p.dpdu)?;
                let dpdv = derivative(&format!("{name} dpdv"), &p.dpdv)?;
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
                });
            }
            meshes.push(GpuMesh { name: mesh.name.clone(), primitives });
        }
        Ok(Self { meshes })
    }
}
