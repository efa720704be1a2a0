//! The scene for ray queries: one BLAS per mesh (its primitives as geometries, built once per render) and the
//! primitive records the accumulation shader reads at a hit. Instances go into a TLAS per sample time.
use super::accumulate_layout::GpuPrimitiveRecord;
use super::gpu_scene::GpuScene;
use crate::scene::{AlphaMode, Scene};
use crate::vk::accel::{AccelerationStructure, TlasInstance, TriangleGeometry};
use crate::vk::{Buffer, Device};
use anyhow::{Context as _, Result};
use ash::vk;
use glam::Mat4;
use std::sync::Arc;

pub struct RayScene {
    /// Per mesh: its BLAS (`None` for a mesh without triangles) and the index of its first primitive record.
    blases: Vec<Option<(AccelerationStructure, u32)>>,
    pub records: Buffer,
    /// Instances that have geometry, in scene order: what the TLAS holds.
    pub traced_instances: Vec<usize>,
    /// Some geometry is alpha-tested (glTF MASK or BLEND): not opaque to rays, so ray queries must look at its
    /// candidate triangles.
    pub alpha_tested: bool,
}

impl RayScene {
    /// Builds every BLAS. `default_material` is the index of the material primitives without one use.
    pub fn build(device: &Arc<Device>, scene: &Scene, geometry: &GpuScene, default_material: u32) -> Result<Self> {
        let mut blases = Vec::with_capacity(geometry.meshes.len());
        let mut records = Vec::new();
        // As the raster pass sees them: MASK cuts out below its cutoff, BLEND keeps alpha of the samples
        // (material.glsl's alpha_test_passes).
        let opaque = |material: Option<usize>| {
            material.and_then(|m| scene.materials.get(m)).is_none_or(|m| m.alpha_mode == AlphaMode::Opaque)
        };
        let mut alpha_tested = false;
        for mesh in &geometry.meshes {
            if mesh.primitives.is_empty() {
                blases.push(None);
                continue;
            }
            let first = records.len() as u32;
            let geometries: Vec<TriangleGeometry> = mesh
                .primitives
                .iter()
                .map(|p| TriangleGeometry {
                    vertex_address: p.positions.address,
                    vertex_stride: 12,
                    vertex_count: p.vertex_count,
                    index_address: p.indices.address,
                    triangle_count: p.index_count / 3,
                    opaque: opaque(p.material),
                })
                .collect();
            alpha_tested |= geometries.iter().any(|g| !g.opaque);
            for p in &mesh.primitives {
                records.push(GpuPrimitiveRecord {
                    positions: p.positions.address,
                    normals: p.normals.address,
                    uvs: p.uvs.address,
                    indices: p.indices.address,
                    colors: p.colors.address,
                    dpdu: p.dpdu.address,
                    dpdv: p.dpdv.address,
                    material: p.material.map(|m| m as u32).unwrap_or(default_material),
                    pad: 0,
                    uvs1: p.uvs1.address,
                });
            }
            let blas = AccelerationStructure::build_blas(device, &format!("{} BLAS", mesh.name), &geometries)
                .with_context(|| format!("building the BLAS of mesh \"{}\"", mesh.name))?;
            blases.push(Some((blas, first)));
        }
        if records.is_empty() {
            records.push(bytemuck::Zeroable::zeroed());
        }
        let records =
            Buffer::with_data(device, "primitive records", &records, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
        let traced_instances = scene
            .instances
            .iter()
            .enumerate()
            .filter(|(_, i)| matches!(blases.get(i.mesh), Some(Some(_))))
            .map(|(index, _)| index)
            .collect();
        Ok(Self { blases, records, traced_instances, alpha_tested })
    }

    /// TLAS instances for the scene's instance transforms at one time (`transforms` in scene instance order).
    pub fn tlas_instances<'a>(&'a self, scene: &Scene, transforms: &[Mat4]) -> Vec<TlasInstance<'a>> {
        self.traced_instances
            .iter()
            .filter_map(|&i| {
                let (blas, first) = self.blases[scene.instances[i].mesh].as_ref()?;
                let transform = transforms.get(i).copied().filter(|m| m.is_finite()).unwrap_or(Mat4::ZERO);
                Some(TlasInstance { blas, transform, custom_index: *first, mask: 0xFF })
            })
            .collect()
    }
}
