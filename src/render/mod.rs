//! The frame: joins the CPU scene to Vulkan. Each pass holds its pipeline (compute pipelines are kept by the device
//! and shared by every frame on it) and records into a command buffer.
pub mod accumulate;
pub mod accumulate_layout;
pub mod aov;
pub mod frame;
pub mod gbuffer;
pub mod gbuffer_layout;
pub mod gpu_scene;
pub mod lights;
pub mod noise_probe;
pub mod preview;
pub mod ray_log;
pub mod ray_probe;
pub mod ray_scene;
pub mod resolve;
pub mod solid;
pub mod textures;

pub use gpu_scene::GpuScene;

/// Everything of a scene that lives on the GPU for a whole frame: geometry and textures. Upload it once and
/// hand it to every pass.
pub struct SceneOnGpu {
    pub geometry: GpuScene,
    pub textures: textures::GpuTextures,
}

impl SceneOnGpu {
    pub fn upload(device: &std::sync::Arc<crate::vk::Device>, scene: &crate::scene::Scene) -> anyhow::Result<Self> {
        Ok(Self { geometry: GpuScene::upload(device, scene)?, textures: textures::GpuTextures::upload(device, scene)? })
    }
}
pub use preview::{PreviewPass, PreviewSettings};
