//! The frame: joins the CPU scene to Vulkan. Each pass owns its pipeline and records into a command buffer.
pub mod aov;
pub mod gbuffer;
pub mod gbuffer_layout;
pub mod gpu_scene;
pub mod noise_probe;
pub mod preview;
pub mod ray_probe;
pub mod solid;
pub mod textures;

pub use gpu_scene::GpuScene;
pub use preview::{PreviewPass, PreviewSettings};
