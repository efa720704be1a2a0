//! The CPU scene: meshes, materials, placed instances and the camera. Knows nothing about Vulkan.
pub mod camera;
pub mod gltf_export;
pub mod gltf_import;
pub mod library;
pub mod shapes;

pub use camera::{Camera, Projection};
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::path::PathBuf;

/// A triangle list with per-vertex attributes (all the same length as `positions`).
#[derive(Debug, Clone, Default)]
pub struct Primitive {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// TEXCOORD_0; empty when the mesh has none.
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
    pub material: Option<usize>,
}

impl Primitive {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
}

#[derive(Debug, Clone)]
pub struct Material {
    pub name: String,
    /// Linear RGBA base colour factor (glTF `pbrMetallicRoughness.baseColorFactor`).
    pub base_color: Vec4,
}

impl Default for Material {
    fn default() -> Self {
        // glTF's default material: white (glTF 2.0 §3.9.6).
        Self { name: "default".into(), base_color: Vec4::ONE }
    }
}

/// A mesh placed in the world by a node.
#[derive(Debug, Clone)]
pub struct Instance {
    pub name: String,
    pub mesh: usize,
    pub world_from_object: Mat4,
}

#[derive(Debug, Clone)]
pub struct Scene {
    pub source: PathBuf,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub instances: Vec<Instance>,
    /// The glTF's first camera, if it has one.
    pub camera: Option<Camera>,
}

impl Scene {
    /// World-space bounds of every placed vertex; `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for instance in &self.instances {
            for primitive in &self.meshes[instance.mesh].primitives {
                for &p in &primitive.positions {
                    let w = instance.world_from_object.transform_point3(p);
                    lo = lo.min(w);
                    hi = hi.max(w);
                }
            }
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }

    pub fn triangle_count(&self) -> usize {
        self.instances.iter().flat_map(|i| self.meshes[i.mesh].primitives.iter()).map(Primitive::triangle_count).sum()
    }

    /// The scene's camera, or one that frames its bounds (looking down −Z from slightly above).
    pub fn camera_or_default(&self) -> Camera {
        self.camera.clone().unwrap_or_else(|| Camera::framing(self.bounds()))
    }
}
