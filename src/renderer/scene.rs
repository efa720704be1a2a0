//! A scene a program loads once and changes between renders: node transforms, material factors, lights, the
//! camera and the environment. Geometry and textures are fixed once loaded, so a [`super::Renderer`] uploads them
//! once per scene and keeps them for every render of it.
use super::InputError;
use crate::scene::{self, environment::Environment, Camera, Light};
use anyhow::{bail, Result};
use glam::{Mat4, Vec3, Vec4};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Source of [`Scene`] ids: a renderer keys its uploads by them.
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// A loaded scene and the render settings its file gives.
#[derive(Debug)]
pub struct Scene {
    pub(super) id: u64,
    /// Dropped with the scene: a renderer holding its upload sees it gone and frees the upload.
    pub(super) alive: Arc<()>,
    pub(super) scene: scene::Scene,
    pub(super) file_settings: scene::settings::SettingsOverrides,
    path: PathBuf,
}

/// The material factors a program may change (glTF 2.0 §3.9.2); None leaves a factor as it is.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MaterialFactors {
    /// Linear RGBA base colour factor, each component 0 to 1.
    pub base_color: Option<Vec4>,
    pub metallic: Option<f32>,
    pub roughness: Option<f32>,
    /// Linear emitted radiance factor (not negative).
    pub emissive: Option<Vec3>,
}

impl Scene {
    /// Loads a `.gltf` / `.glb` file, or a scene file (`.toml`) and the glTF it names ([`crate::load`]).
    pub fn load(path: &Path, options: &crate::LoadOptions) -> Result<Self> {
        let loaded = crate::load(path, options).map_err(InputError::from)?;
        Ok(Self::with_settings(loaded.scene, loaded.settings, path))
    }

    /// A scene a program built itself, with no file settings.
    pub fn from_scene(scene: scene::Scene) -> Self {
        let path = scene.source.clone();
        Self::with_settings(scene, Default::default(), &path)
    }

    fn with_settings(scene: scene::Scene, file_settings: scene::settings::SettingsOverrides, path: &Path) -> Self {
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        Self { id, alive: Arc::new(()), scene, file_settings, path: path.to_path_buf() }
    }

    /// The scene as loaded (and as changed since).
    pub fn scene(&self) -> &scene::Scene {
        &self.scene
    }

    /// What the scene file's `[render]` table sets (empty for a bare glTF).
    pub fn file_settings(&self) -> &scene::settings::SettingsOverrides {
        &self.file_settings
    }

    /// The file it was loaded from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The index of the node called `name`; an error names the nodes there are.
    pub fn node_index(&self, name: &str) -> Result<usize> {
        find(self.scene.nodes.iter().map(|n| n.name.as_str()), name, "node", &self.path)
    }

    /// The index of the material called `name`.
    pub fn material_index(&self, name: &str) -> Result<usize> {
        find(self.scene.materials.iter().map(|m| m.name.as_str()), name, "material", &self.path)
    }

    /// A node's local transform (relative to its parent) at rest, before animation.
    pub fn node_transform(&self, node: usize) -> Result<Mat4> {
        self.check_index(node, self.scene.nodes.len(), "node")?;
        Ok(self.scene.nodes[node].transform.matrix())
    }

    /// Sets a node's local transform (relative to its parent): it and its children move in the next render.
    /// An animation that drives the node still overrides the channels it animates.
    pub fn set_node_transform(&mut self, node: usize, local: Mat4) -> Result<()> {
        self.check_index(node, self.scene.nodes.len(), "node")?;
        if !local.is_finite() || local.row(3) != Vec4::W {
            let name = &self.scene.nodes[node].name;
            return Err(InputError::new(format!(
                "node {node} ({name:?}): a transform must be finite and affine (last row 0 0 0 1)"
            ))
            .into());
        }
        let (scale, rotation, translation) = local.to_scale_rotation_translation();
        // A TRS keeps the node animatable (glTF 2.0 §3.5.2) when the matrix is one.
        let trs = Mat4::from_scale_rotation_translation(scale, rotation, translation);
        let largest = local.to_cols_array().into_iter().fold(1.0f32, |m, v| m.max(v.abs()));
        self.scene.nodes[node].transform = if trs.abs_diff_eq(local, 1e-5 * largest) {
            scene::NodeTransform::Trs { translation, rotation, scale }
        } else {
            scene::NodeTransform::Matrix(local)
        };
        Ok(())
    }

    /// Changes a material's factors (its textures stay).
    pub fn set_material(&mut self, material: usize, factors: &MaterialFactors) -> Result<()> {
        self.check_index(material, self.scene.materials.len(), "material")?;
        let unit = |v: f32| v.is_finite() && (0.0..=1.0).contains(&v);
        let bad = |what: &str| -> anyhow::Error { InputError::new(format!("material {material}: {what}")).into() };
        if let Some(c) = factors.base_color {
            if !c.to_array().into_iter().all(unit) {
                return Err(bad("base_color components must be between 0 and 1"));
            }
        }
        for (value, name) in [(factors.metallic, "metallic"), (factors.roughness, "roughness")] {
            if value.is_some_and(|v| !unit(v)) {
                return Err(bad(&format!("{name} must be between 0 and 1")));
            }
        }
        if let Some(e) = factors.emissive {
            if !e.is_finite() || e.min_element() < 0.0 {
                return Err(bad("emissive must be finite and not negative"));
            }
        }
        let m = &mut self.scene.materials[material];
        m.base_color = factors.base_color.unwrap_or(m.base_color);
        m.metallic = factors.metallic.unwrap_or(m.metallic);
        m.roughness = factors.roughness.unwrap_or(m.roughness);
        m.emissive = factors.emissive.unwrap_or(m.emissive);
        Ok(())
    }

    /// Replaces the scene's lights (an empty list and no emitter or environment: the default key light).
    pub fn set_lights(&mut self, lights: Vec<Light>) -> Result<()> {
        for light in &lights {
            if !light.emission.is_finite() || light.emission.min_element() < 0.0 || !light.world_from_light.is_finite()
            {
                return Err(InputError::new(format!(
                    "light {:?}: emission must be finite and not negative, its frame finite",
                    light.name
                ))
                .into());
            }
        }
        self.scene.lights = lights;
        Ok(())
    }

    /// Sets the camera (None: the scene's bounds framed, unless a render places one). Its pose must be finite and
    /// affine, a perspective field of view between 0 and 180 degrees, the clip planes ordered and positive.
    pub fn set_camera(&mut self, camera: Option<Camera>) -> Result<()> {
        if let Some(c) = &camera {
            let bad = |what: &str| -> anyhow::Error { InputError::new(format!("camera {:?}: {what}", c.name)).into() };
            if !c.world_from_camera.is_finite() || c.world_from_camera.row(3) != Vec4::W {
                return Err(bad("world_from_camera must be finite and affine (last row 0 0 0 1)"));
            }
            if c.world_from_camera.determinant().abs() < 1e-12 {
                return Err(bad("world_from_camera must be invertible"));
            }
            let (near, far) = match c.projection {
                scene::Projection::Perspective { yfov, znear, zfar } => {
                    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                        return Err(bad("yfov must be between 0 and 180 degrees"));
                    }
                    (znear, zfar)
                }
                scene::Projection::Orthographic { xmag, ymag, znear, zfar } => {
                    if !(xmag > 0.0 && ymag > 0.0 && xmag.is_finite() && ymag.is_finite()) {
                        return Err(bad("xmag and ymag must be positive"));
                    }
                    (znear, Some(zfar))
                }
            };
            if !(near > 0.0 && near.is_finite()) || far.is_some_and(|f| !(f > near && f.is_finite())) {
                return Err(bad("znear must be positive and zfar beyond it"));
            }
            let lens = c.lens;
            let aperture_ok = lens.aperture_radius >= 0.0 && lens.aperture_radius.is_finite();
            let focus_ok = lens.focus_distance > 0.0 && lens.focus_distance.is_finite();
            if !(aperture_ok && focus_ok) {
                return Err(bad("the aperture must be 0 or more and the focus distance positive"));
            }
        }
        self.scene.camera = camera;
        Ok(())
    }

    /// Sets the environment (None: none); a renderer uploads a changed environment before the next render.
    pub fn set_environment(&mut self, environment: Option<Environment>) {
        self.scene.environment = environment;
    }

    fn check_index(&self, index: usize, count: usize, what: &str) -> Result<()> {
        if index >= count {
            return Err(InputError::new(format!(
                "{}: no {what} {index} (the scene has {count} {what}s)",
                self.path.display()
            ))
            .into());
        }
        Ok(())
    }
}

/// The index of `name` among `names`, or an input error listing them.
fn find<'a>(names: impl Iterator<Item = &'a str>, name: &str, what: &str, path: &Path) -> Result<usize> {
    let names: Vec<&str> = names.collect();
    if let Some(i) = names.iter().position(|n| *n == name) {
        return Ok(i);
    }
    let listed = names.iter().filter(|n| !n.is_empty()).take(20).map(|n| format!("{n:?}")).collect::<Vec<_>>();
    let there = if listed.is_empty() { "none has a name".to_string() } else { listed.join(", ") };
    bail!(InputError::new(format!("{}: no {what} called {name:?} ({what}s: {there})", path.display())))
}
