//! The frame: joins the CPU scene to Vulkan. Each pass holds its pipeline (compute pipelines are kept by the device
//! and shared by every frame on it) and records into a command buffer.
pub mod accumulate;
pub mod accumulate_layout;
pub mod aov;
pub mod deformed;
pub mod environment;
pub mod frame;
pub mod gbuffer;
pub mod gbuffer_encoding;
pub mod gbuffer_layout;
pub mod gpu_scene;
pub mod lights;
pub mod motion;
pub mod noise_probe;
pub mod preview;
pub mod ray_log;
pub mod ray_probe;
pub mod ray_scene;
pub mod resolve;
pub mod sample_slots;
pub mod skinning;
pub mod solid;
pub mod textures;

pub use gpu_scene::GpuScene;

/// Everything of a scene that lives on the GPU for a whole frame: geometry and textures. Upload it once and
/// hand it to every pass.
pub struct SceneOnGpu {
    pub geometry: GpuScene,
    pub textures: textures::GpuTextures,
    /// The environment's texels and sampling distribution (environment.glsl), or a header saying there is none.
    pub environment: crate::vk::Buffer,
    /// The BLASes and primitive records, built by the first frame and kept for the next ones (a turntable or an
    /// animation's frames build them once); rebuilt if the materials' alpha modes change.
    ray_scene: std::sync::Mutex<Option<(Vec<crate::scene::AlphaMode>, std::sync::Arc<ray_scene::RayScene>)>>,
}

impl SceneOnGpu {
    pub fn upload(device: &std::sync::Arc<crate::vk::Device>, scene: &crate::scene::Scene) -> anyhow::Result<Self> {
        Ok(Self {
            geometry: GpuScene::upload(device, scene)?,
            textures: textures::GpuTextures::upload(device, scene)?,
            environment: environment::upload(device, scene.environment.as_ref())?,
            ray_scene: std::sync::Mutex::new(None),
        })
    }

    /// The scene's BLASes and primitive records: built once, by the first frame that asks.
    pub fn ray_scene(
        &self,
        device: &std::sync::Arc<crate::vk::Device>,
        scene: &crate::scene::Scene,
    ) -> anyhow::Result<std::sync::Arc<ray_scene::RayScene>> {
        let key: Vec<crate::scene::AlphaMode> = scene.materials.iter().map(|m| m.alpha_mode).collect();
        let mut kept = self.ray_scene.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some((k, built)) = kept.as_ref() {
            if *k == key {
                return Ok(built.clone());
            }
        }
        let built = std::sync::Arc::new(ray_scene::RayScene::build(
            device,
            scene,
            &self.geometry,
            scene.materials.len() as u32,
        )?);
        *kept = Some((key, built.clone()));
        Ok(built)
    }
}
pub use preview::{PreviewPass, PreviewSettings};
