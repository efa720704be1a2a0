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
    /// `records` on the host, for frames that append deformed instances' records (render::deformed).
    pub record_list: Vec<GpuPrimitiveRecord>,
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
        let opaque = |material: Option<usize>| is_opaque(scene, material);
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
        let record_list = records;
        let records =
            Buffer::with_data(device, "primitive records", &record_list, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
        let traced_instances = scene
            .instances
            .iter()
            .enumerate()
            .filter(|(_, i)| matches!(blases.get(i.mesh), Some(Some(_))))
            .map(|(index, _)| index)
            .collect();
        Ok(Self { blases, records, record_list, traced_instances, alpha_tested })
    }

    /// TLAS instances for the scene's instance transforms at one time (`transforms` in scene instance order).
    pub fn tlas_instances<'a>(&'a self, scene: &Scene, transforms: &[Mat4]) -> Vec<TlasInstance<'a>> {
        self.tlas_instances_with(scene, transforms, |_| None)
    }

    /// `tlas_instances`, with the BLAS and first primitive record of some instances replaced: `own(i)` gives scene
    /// instance i's own (a deformed instance's, for one sample), or None for its mesh's.
    pub fn tlas_instances_with<'a>(
        &'a self,
        scene: &Scene,
        transforms: &[Mat4],
        own: impl Fn(usize) -> Option<(&'a AccelerationStructure, u32)>,
    ) -> Vec<TlasInstance<'a>> {
        self.traced_instances
            .iter()
            .filter_map(|&i| {
                let (blas, first) = match own(i) {
                    Some(own) => own,
                    None => self.blases[scene.instances[i].mesh].as_ref().map(|(b, f)| (b, *f))?,
                };
                let transform = transforms.get(i).copied().filter(|m| m.is_finite()).unwrap_or(Mat4::ZERO);
                Some(TlasInstance { blas, transform, custom_index: first, mask: 0xFF })
            })
            .collect()
    }
}

/// Whether rays may take a primitive with `material` as opaque, as the raster pass sees it: MASK cuts out below its
/// cutoff, BLEND keeps alpha of the samples (material.glsl's alpha_test_passes), so both need their candidates
/// looked at.
pub fn is_opaque(scene: &Scene, material: Option<usize>) -> bool {
    material.and_then(|m| scene.materials.get(m)).is_none_or(|m| m.alpha_mode == AlphaMode::Opaque)
}
