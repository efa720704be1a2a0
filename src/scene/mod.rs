//! The CPU scene: meshes, materials, textures, the node hierarchy with animations, cameras and lights.
//! Knows nothing about Vulkan.
pub mod animation;
pub mod camera;
pub mod environment;
pub mod fixtures;
pub mod framing;
pub mod gltf_accessors;
mod gltf_draco;
pub mod gltf_export;
pub mod gltf_import;
mod gltf_instancing;
mod gltf_layers;
mod gltf_material;
mod gltf_mesh;
mod gltf_meshopt;
mod gltf_skin;
pub mod gltf_uri;
pub mod image_decode;
pub mod library;
pub mod light;
pub mod material;
pub mod morph;
pub mod motion;
pub mod scene_file;
pub mod settings;
pub mod shapes;
pub mod skin;
pub mod surface;

pub use animation::{Animation, Channel, Interpolation, Property};
pub use camera::{Camera, Projection};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
pub use light::{Light, LightShape};
pub use material::{
    AlphaMode, Anisotropy, BumpDerivative, BumpMap, Clearcoat, DiffuseTransmission, Iridescence, Material, MipFilter,
    NoiseKind, Sampler, Sheen, Texture, TextureImage, TextureRef, UvTransform, Wrap,
};
pub use motion::{NodeMotion, RigidMotion};
use std::path::PathBuf;

/// A triangle list with per-vertex attributes. Optional attributes are empty when absent, else the same length
/// as `positions`.
#[derive(Debug, Clone, Default)]
pub struct Primitive {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// TANGENT (xyz, w = handedness ±1).
    pub tangents: Vec<Vec4>,
    /// TEXCOORD_0.
    pub uvs: Vec<Vec2>,
    /// TEXCOORD_1.
    pub uvs1: Vec<Vec2>,
    /// COLOR_0 as linear RGBA (RGB inputs get alpha 1).
    pub colors: Vec<Vec4>,
    /// Surface derivatives Q_u = ∂P/∂u and Q_v = ∂P/∂v per vertex, unnormalized (Blinn 1978 needs |Q_u × Q_v|);
    /// empty without UVs. Zero where the UVs are degenerate.
    pub dpdu: Vec<Vec3>,
    pub dpdv: Vec<Vec3>,
    pub indices: Vec<u32>,
    pub material: Option<usize>,
    /// `KHR_materials_variants`: (variant, material) pairs; the chosen variant's material replaces `material`
    /// (Scene::select_variant).
    pub variant_materials: Vec<(usize, usize)>,
    /// `JOINTS_n`/`WEIGHTS_n`, one entry per set (each as long as `positions`); empty for a mesh without skin data.
    pub skin_influences: Vec<skin::JointInfluences>,
    /// The unmorphed attributes and morph targets, for clips that animate the weights; None without targets.
    pub morph: Option<Box<morph::MorphSource>>,
}

impl Primitive {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The coordinates textures on the second UV set read: TEXCOORD_1, or TEXCOORD_0 where the mesh has no
    /// TEXCOORD_1 for every vertex (a material naming a set its mesh lacks reads the first).
    pub fn uvs1_or_uvs(&self) -> &[Vec2] {
        if self.uvs1.len() == self.positions.len() {
            &self.uvs1
        } else {
            &self.uvs
        }
    }
}

#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
}

/// A node's local transform: glTF allows a matrix or TRS; only TRS can be animated (glTF 2.0 §3.5.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NodeTransform {
    Matrix(Mat4),
    Trs { translation: Vec3, rotation: Quat, scale: Vec3 },
}

impl NodeTransform {
    pub fn matrix(&self) -> Mat4 {
        match *self {
            NodeTransform::Matrix(m) => m,
            NodeTransform::Trs { translation, rotation, scale } => {
                Mat4::from_scale_rotation_translation(scale, rotation, translation)
            }
        }
    }
}

#[derive(Debug, Clone)]
pub struct Node {
    pub name: String,
    pub parent: Option<usize>,
    pub children: Vec<usize>,
    pub transform: NodeTransform,
    pub mesh: Option<usize>,
    pub camera: Option<usize>,
    pub light: Option<usize>,
    /// Its semantic class (`--aov semantic`): the glTF node's `extras.category_id`, or what a scene file's
    /// `[[semantic]]` table gives it; None: its parent's.
    pub category: Option<u32>,
    /// The skin (index into `Scene::skins`) that deforms the node's mesh.
    pub skin: Option<usize>,
}

/// A mesh placed in the world by a node (at the rest pose, without animation).
#[derive(Debug, Clone)]
pub struct Instance {
    pub name: String,
    pub mesh: usize,
    /// The node that places it; `None` for instances made without a hierarchy.
    pub node: Option<usize>,
    pub world_from_object: Mat4,
    /// Where it sits in its node's space: the identity, or one of the node's `EXT_mesh_gpu_instancing`
    /// transforms (the node's animation moves all of them).
    pub node_from_object: Mat4,
}

#[derive(Debug, Clone, Default)]
pub struct Scene {
    pub source: PathBuf,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub images: Vec<TextureImage>,
    pub nodes: Vec<Node>,
    /// The nodes of the rendered glTF scene.
    pub roots: Vec<usize>,
    pub instances: Vec<Instance>,
    /// Every camera placed in the scene, in traversal order; the first is the default.
    pub cameras: Vec<Camera>,
    /// The camera to render with, when the scene has one.
    pub camera: Option<Camera>,
    pub lights: Vec<Light>,
    pub animations: Vec<Animation>,
    pub skins: Vec<skin::Skin>,
    /// Extra motion of nodes over the shutter (scene file), on top of glTF animation.
    pub node_motion: Vec<NodeMotion>,
    /// Camera motion over the shutter (scene file).
    pub camera_motion: RigidMotion,
    /// Shutter open and close times in seconds (equal: no motion blur).
    pub shutter: (f32, f32),
    /// Light from infinitely far away (an HDR image or a generated one), and what escaping rays see.
    pub environment: Option<environment::Environment>,
    /// Things the loader skipped (unknown optional extensions, unsupported channels), for the user to read.
    pub warnings: Vec<String>,
    /// What the loader chose where the file left a choice (which animation clip plays), for the user to read.
    pub notes: Vec<String>,
    /// `KHR_materials_variants`' variant names, in the file's order.
    pub variants: Vec<String>,
}

impl Scene {
    /// World-space bounds of every placed vertex; `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let rest = if self.skins.is_empty() { Vec::new() } else { self.node_world_transforms(None) };
        for (i, instance) in self.instances.iter().enumerate() {
            // A skinned instance at its rest pose: its vertices where its joints place them, in the world.
            if let Some(deformed) = self.instance_skin(i).and_then(|_| self.deform_instance(i, &rest, None)) {
                for &w in deformed.iter().flat_map(|d| &d.positions) {
                    lo = lo.min(w);
                    hi = hi.max(w);
                }
                continue;
            }
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

    /// Whether some material refracts each colour channel by its own index (KHR_materials_dispersion).
    pub fn disperses(&self) -> bool {
        self.materials.iter().any(|m| m.disperses())
    }

    /// Whether some material has a layer over its base (a clear coat or a sheen: `Material::is_layered`).
    pub fn layered(&self) -> bool {
        self.materials.iter().any(Material::is_layered)
    }

    pub fn triangle_count(&self) -> usize {
        self.instances.iter().flat_map(|i| self.meshes[i.mesh].primitives.iter()).map(Primitive::triangle_count).sum()
    }

    /// Gives every primitive the material `KHR_materials_variants` maps to the variant named `name` (a primitive
    /// without a mapping for it keeps its default material). An unknown name is an error listing the variants.
    pub fn select_variant(&mut self, name: &str) -> anyhow::Result<()> {
        let Some(variant) = self.variants.iter().position(|v| v == name) else {
            let list =
                if self.variants.is_empty() { "the scene has none".to_string() } else { self.variants.join(", ") };
            anyhow::bail!("no material variant \"{name}\" ({list})");
        };
        for primitive in self.meshes.iter_mut().flat_map(|m| &mut m.primitives) {
            if let Some(&(_, material)) = primitive.variant_materials.iter().find(|(v, _)| *v == variant) {
                primitive.material = Some(material);
            }
        }
        Ok(())
    }

    /// Each node's semantic class: its own `category`, else its nearest ancestor's, else 0 (unlabelled).
    pub fn node_categories(&self) -> Vec<u32> {
        (0..self.nodes.len())
            .map(|mut i| {
                // At most as many steps as there are nodes (the hierarchy is acyclic).
                for _ in 0..self.nodes.len() {
                    if let Some(c) = self.nodes[i].category {
                        return c;
                    }
                    match self.nodes[i].parent {
                        Some(p) => i = p,
                        None => break,
                    }
                }
                0
            })
            .collect()
    }

    /// The scene's camera, or one that frames its bounds (looking down −Z from slightly above).
    pub fn camera_or_default(&self) -> Camera {
        self.camera.clone().unwrap_or_else(|| Camera::framing(self.bounds()))
    }

    /// World transforms of every node at time `t` in seconds, with every animation applied (`None`: rest pose).
    pub fn node_world_transforms(&self, t: Option<f32>) -> Vec<Mat4> {
        let mut locals: Vec<NodeTransform> = self.nodes.iter().map(|n| n.transform).collect();
        if let Some(t) = t {
            for animation in &self.animations {
                animation.apply(t, &mut locals);
            }
            for m in &self.node_motion {
                if let Some(local) = locals.get_mut(m.node) {
                    *local = NodeTransform::Matrix(m.motion.apply(local.matrix(), t));
                }
            }
        }
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        let mut done = vec![false; self.nodes.len()];
        // Parents before children: walk from each root (the hierarchy was checked acyclic on load).
        let mut stack: Vec<(usize, Mat4)> = self
            .nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.parent.is_none())
            .map(|(i, _)| (i, Mat4::IDENTITY))
            .collect();
        while let Some((i, parent)) = stack.pop() {
            if done[i] {
                continue;
            }
            done[i] = true;
            world[i] = parent * locals[i].matrix();
            stack.extend(self.nodes[i].children.iter().map(|&c| (c, world[i])));
        }
        world
    }

    /// Whether anything in the scene gives light: a light, or an emissive material.
    pub fn has_light(&self) -> bool {
        !self.lights.is_empty()
            || self.environment.is_some()
            || self.materials.iter().any(|m| m.emissive.max_element() > 0.0)
    }

    /// Readies the scene's lighting for a render whose background is `backdrop`: the environment must exist to be
    /// shown, and a scene with no light at all gets the default key light. Returns the warning to show then.
    pub fn light_for_render(&mut self, backdrop: Option<settings::Backdrop>) -> anyhow::Result<Option<String>> {
        if backdrop == Some(settings::Backdrop::Environment) && self.environment.is_none() {
            anyhow::bail!(
                "--background environment needs an environment (--environment FILE, [environment] in the scene \
                 file, or environment= in Python)"
            );
        }
        if self.has_light() {
            return Ok(None);
        }
        self.add_default_light();
        Ok(Some(
            "the scene has no lights or emissive surfaces; lighting it with a default key light (add [[light]] \
             tables in a scene file, or an environment, see docs/scene-format.md)"
                .to_string(),
        ))
    }

    /// Adds a directional key light from above and behind the camera's left shoulder (irradiance π, so a white
    /// Lambertian surface facing it reflects radiance 1): what a scene with no light of its own is lit by.
    pub fn add_default_light(&mut self) {
        let camera = self.camera_or_default();
        let direction = camera.world_from_camera.transform_vector3(Vec3::new(-0.4, 1.0, 0.8)).normalize();
        self.lights.push(Light {
            name: "default key light".into(),
            shape: LightShape::Directional,
            emission: Vec3::splat(std::f32::consts::PI),
            world_from_light: camera::look_at(
                Vec3::ZERO,
                -direction,
                if direction.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y },
            ),
            node: None,
            range: 0.0,
        });
    }

    /// The camera at time `t` (its scene-file motion applied).
    pub fn camera_at(&self, t: f32) -> Camera {
        let mut camera = self.camera_or_default();
        camera.world_from_camera = self.camera_motion.apply(camera.world_from_camera, t);
        camera
    }

    /// Each instance's world transform at time `t` (animation applied), in `instances` order.
    pub fn instance_transforms_at(&self, t: f32) -> Vec<Mat4> {
        self.instance_transforms_from(&self.node_world_transforms(Some(t)))
    }

    /// Each instance's world transform given every node's (from `node_world_transforms`). A skinned instance's
    /// is the identity: its joints place its vertices in the world (§3.7.3.3, `skin`).
    pub fn instance_transforms_from(&self, node_world: &[Mat4]) -> Vec<Mat4> {
        (0..self.instances.len())
            .map(|index| {
                let i = &self.instances[index];
                if self.instance_skin(index).is_some() {
                    return Mat4::IDENTITY;
                }
                i.node.and_then(|n| node_world.get(n)).map_or(i.world_from_object, |w| *w * i.node_from_object)
            })
            .collect()
    }
}
