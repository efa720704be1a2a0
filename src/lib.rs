//! strata: a headless Vulkan renderer. Floors, top to bottom: `main.rs` → this API → `render/` →
//! {`vk/`, `scene/`, `output`}; nothing on a lower floor imports a higher one.
pub mod output;
pub mod render;
pub mod scene;
pub mod shaders;
pub mod vk;

use anyhow::{bail, Result};
use std::path::Path;

/// Loads a scene from a `.gltf` / `.glb` file.
pub fn load_scene(path: &Path) -> Result<scene::Scene> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("gltf") | Some("glb") => scene::gltf_import::load_gltf(path, &Default::default()),
        Some(other) => bail!("{}: unknown scene extension \".{other}\" (use .gltf or .glb)", path.display()),
        None => bail!("{}: scene file has no extension (use .gltf or .glb)", path.display()),
    }
}

/// What `render_preview` needs besides the scene.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    pub gpu: vk::GpuOptions,
    pub preview: render::PreviewSettings,
}

/// Loads nothing, writes nothing: renders `scene` with the preview pass and returns the linear frame.
pub fn render_preview(
    gpu: &vk::Gpu,
    scene: &scene::Scene,
    settings: &render::PreviewSettings,
) -> Result<output::Frame> {
    let gpu_scene = render::GpuScene::upload(&gpu.device, scene)?;
    let pass = render::PreviewPass::new(&gpu.device)?;
    pass.render(scene, &gpu_scene, settings)
}
