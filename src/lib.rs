//! strata: a headless Vulkan renderer. Floors, top to bottom: `main.rs` → this API → `render/` →
//! {`vk/`, `scene/`, `output`}; nothing on a lower floor imports a higher one.
pub mod bench;
pub mod check;
pub mod denoise;
pub mod fatal_signals;
pub mod hash;
pub mod input;
pub mod math;
pub mod output;
pub mod partial;
pub mod render;
pub mod renderer;
pub mod scene;
pub mod shaders;
pub mod vk;
pub mod write_plan;

pub use renderer::{RenderRequest, Rendered, Renderer, RendererOptions, Scene};

use anyhow::{bail, Context as _, Result};
use std::path::Path;

/// A scene ready to render, with the settings its file asked for.
#[derive(Debug)]
pub struct LoadedScene {
    pub scene: scene::Scene,
    /// What a scene file's `[render]` table sets (empty for a bare glTF).
    pub settings: scene::settings::SettingsOverrides,
}

/// How to load a scene.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Allow glTF URIs outside the file's directory (absolute paths, `..`); `None`: what the scene file says.
    pub allow_any_uri: Option<bool>,
    /// The animation clip that plays; `None`: what the scene file says, else the first (as viewers do).
    pub animation: Option<scene::animation::AnimationChoice>,
    /// The `KHR_materials_variants` variant whose materials the meshes take; `None`: what the scene file says,
    /// else the file's default materials.
    pub variant: Option<String>,
}

/// Loads a `.gltf` / `.glb` file, or a scene file (`.toml`) and the glTF it names.
pub fn load(path: &Path, options: &LoadOptions) -> Result<LoadedScene> {
    use scene::gltf_uri::UriPolicy;
    let policy =
        options.allow_any_uri.map(|any| if any { UriPolicy::AnyLocalPath } else { UriPolicy::InsideDirectory });
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let (mut loaded, file_clip, file_variant) = match ext.as_deref() {
        Some("gltf") | Some("glb") => {
            let options = scene::gltf_import::LoadOptions { uri_policy: policy.unwrap_or_default() };
            let scene = scene::gltf_import::load_gltf(path, &options)?;
            (LoadedScene { scene, settings: Default::default() }, None, None)
        }
        Some("toml") => {
            let file = scene::scene_file::load_scene_file(path, policy)?;
            (LoadedScene { scene: file.scene, settings: file.settings }, file.animation, file.variant)
        }
        Some(other) => bail!("{}: unknown scene extension \".{other}\" (use .gltf, .glb or .toml)", path.display()),
        None => bail!("{}: scene file has no extension (use .gltf, .glb or .toml)", path.display()),
    };
    // One clip plays: the command line's, else the scene file's, else the first.
    let choice = options.animation.as_ref().or(file_clip.as_ref());
    let note = scene::animation::select_clip(&mut loaded.scene.animations, choice)
        .with_context(|| format!("{}: choosing the animation clip", path.display()))?;
    loaded.scene.notes.extend(note);
    if let Some(variant) = options.variant.as_ref().or(file_variant.as_ref()) {
        loaded
            .scene
            .select_variant(variant)
            .with_context(|| format!("{}: choosing the material variant", path.display()))?;
    }
    Ok(loaded)
}

/// Loads a scene with default options and without its settings.
pub fn load_scene(path: &Path) -> Result<scene::Scene> {
    Ok(load(path, &LoadOptions::default())?.scene)
}

/// Renders `scene` (already on the GPU as `on_gpu`) with the preview pass and returns the linear frame.
pub fn render_preview(
    gpu: &vk::Gpu,
    scene: &scene::Scene,
    on_gpu: &render::SceneOnGpu,
    settings: &render::PreviewSettings,
) -> Result<output::Frame> {
    let pass = render::PreviewPass::new(&gpu.device)?;
    pass.render(scene, &on_gpu.geometry, &on_gpu.textures, settings)
}

/// The G-buffer through each of `jitters` (sub-pixel offsets, pixels) with a pinhole at the shutter's opening,
/// read back: what the AOVs and the denoiser's guides are made of. Also the pixel-centre camera.
fn pinhole_gbuffers(
    device: &std::sync::Arc<vk::Device>,
    scene: &scene::Scene,
    on_gpu: &render::SceneOnGpu,
    (width, height): (u32, u32),
    jitters: &[glam::Vec2],
) -> Result<Vec<render::gbuffer::GBufferFrame>> {
    let pass = render::gbuffer::GBufferPass::new(device)?;
    let gbuffer = render::gbuffer::GBuffer::new(device, width, height)?;
    let materials = pass.materials(scene, &on_gpu.textures)?;
    let inputs = pass.inputs(scene, &on_gpu.geometry, &on_gpu.textures, &materials, scene.shutter.0)?;
    let camera = pinhole_at(scene, scene.shutter.0);
    jitters
        .iter()
        .map(|&jitter| {
            let sample = math::lens::camera_sample(&camera, width, height, glam::Vec2::splat(0.5), jitter);
            pass.render_to_host(&gbuffer, &inputs, &sample)
        })
        .collect()
}

/// The scene's camera at time `t` with its lens closed to a pinhole.
fn pinhole_at(scene: &scene::Scene, t: f32) -> scene::Camera {
    let mut camera = scene.camera_at(t);
    camera.lens.aperture_radius = 0.0;
    camera
}

/// Renders the G-buffer once (pinhole through the pixel centres, at the shutter's opening) and returns the
/// requested AOVs as raw values; `frame_interval` (seconds) is how far ahead the motion AOV looks.
pub fn render_aovs(
    device: &std::sync::Arc<vk::Device>,
    scene: &scene::Scene,
    on_gpu: &render::SceneOnGpu,
    (width, height): (u32, u32),
    aovs: &[render::aov::Aov],
    frame_interval: f32,
) -> Result<Vec<(render::aov::Aov, output::Frame)>> {
    let frames = pinhole_gbuffers(device, scene, on_gpu, (width, height), &[glam::Vec2::ZERO])?;
    let (now, next) = (scene.shutter.0, scene.shutter.0 + frame_interval);
    let centre_sample = |t: f32| {
        math::lens::camera_sample(&pinhole_at(scene, t), width, height, glam::Vec2::splat(0.5), glam::Vec2::ZERO)
    };
    let labels = scene.instances.iter().map(|i| i.node.map_or(0, |n| n as u32 + 1)).collect();
    let node_categories = scene.node_categories();
    let categories = scene.instances.iter().map(|i| i.node.and_then(|n| node_categories.get(n)).copied().unwrap_or(0));
    let (camera_now, camera_next) = (centre_sample(now), centre_sample(next));
    let deformed_flow = if aovs.contains(&render::aov::Aov::Motion) {
        let interval = render::motion::FlowInterval { now: (now, &camera_now), next: (next, &camera_next) };
        render::motion::deformed_flow(device, scene, on_gpu, (width, height), &interval)?
    } else {
        None
    };
    let aov_scene = render::aov::AovScene {
        instance_labels: labels,
        categories: categories.collect(),
        moves: render::aov::AovScene::moves(&scene.instance_transforms_at(now), &scene.instance_transforms_at(next)),
        camera_now,
        camera_next,
        deformed_flow,
    };
    aovs.iter().map(|&aov| Ok((aov, aov.extract(&frames[0], &aov_scene)?))).collect()
}

/// The denoiser's guides (the first-hit albedo and shading normal), anti-aliased as the picture is: the mean of
/// G-buffer passes through a 4×4 grid of sub-pixel points with a pinhole at the shutter's opening. Open Image
/// Denoise asks for guides filtered like the colour; one pass through pixel centres would leave hard edges where
/// the picture's are soft.
pub fn denoise_guides(
    device: &std::sync::Arc<vk::Device>,
    scene: &scene::Scene,
    on_gpu: &render::SceneOnGpu,
    (width, height): (u32, u32),
) -> Result<(output::Frame, output::Frame)> {
    use render::gbuffer_layout::{ALBEDO, SHADING_NORMAL};
    const GRID: u32 = 4;
    let jitters: Vec<glam::Vec2> = (0..GRID * GRID)
        .map(|k| glam::Vec2::new((k % GRID) as f32 + 0.5, (k / GRID) as f32 + 0.5) / GRID as f32 - 0.5)
        .collect();
    let frames = pinhole_gbuffers(device, scene, on_gpu, (width, height), &jitters)?;
    let pixels = (width * height) as usize;
    let (mut albedo, mut normal) = (vec![[0.0f32; 4]; pixels], vec![[0.0f32; 4]; pixels]);
    let weight = 1.0 / jitters.len() as f32;
    for frame in &frames {
        for i in 0..pixels {
            let (x, y) = (i as u32 % width, i as u32 / width);
            if !frame.covered(x, y) {
                continue;
            }
            let (a, n) = (frame.at(ALBEDO, x, y), frame.at(SHADING_NORMAL, x, y));
            for c in 0..3 {
                albedo[i][c] += weight * a[c];
                normal[i][c] += weight * n[c];
            }
        }
    }
    Ok((output::Frame::new(width, height, albedo)?, output::Frame::new(width, height, normal)?))
}

/// Denoises a rendered frame in place (its linear radiance and its display image, made as the resolve makes it)
/// with the albedo and normal guides of [`denoise_guides`]; returns the noisy radiance.
pub fn denoise_frame(
    denoiser: &denoise::Denoiser,
    device: &std::sync::Arc<vk::Device>,
    scene: &scene::Scene,
    on_gpu: &render::SceneOnGpu,
    settings: &scene::settings::RenderSettings,
    rendered: &mut render::frame::RenderedFrame,
) -> Result<output::Frame> {
    let (albedo, normal) = denoise_guides(device, scene, on_gpu, (settings.width, settings.height))?;
    let denoised = denoiser.denoise(&rendered.linear, &albedo, &normal)?;
    let filmic = settings.tone_map == scene::settings::ToneMap::Filmic;
    let transparent = settings.backdrop_for(scene.environment.is_some()) == scene::settings::Backdrop::Transparent;
    rendered.display = output::display_rgba8(&denoised, rendered.exposure, filmic, transparent);
    Ok(std::mem::replace(&mut rendered.linear, denoised))
}

/// Renders `scene` with distributed ray tracing: `settings.spp` samples of G-buffer + accumulation, then the
/// resolve pass. `progress(done, total)` is called as samples finish; returning `false` stops the render with
/// [`render::frame::Interrupted`].
pub fn render(
    gpu: &vk::Gpu,
    scene: &scene::Scene,
    on_gpu: &render::SceneOnGpu,
    settings: &scene::settings::RenderSettings,
    options: &render::frame::FrameOptions,
    progress: &mut dyn FnMut(u32, u32) -> bool,
) -> Result<render::frame::RenderedFrame> {
    render::frame::render_frame(&gpu.device, scene, on_gpu, settings, options, progress)
}

/// What a part of this render belongs to (`partial::file::Provenance`): parts merge only when all of it agrees.
/// The scene and settings are fingerprinted as rendered (their debug text, hashed as it is written; not the paths
/// they came from), the device with its driver and the way it traces, since another device may round differently.
pub fn part_provenance(
    gpu: &vk::Gpu,
    scene: &scene::Scene,
    settings: &scene::settings::RenderSettings,
) -> Result<partial::file::Provenance> {
    use std::fmt::Write as _;
    let path = render::accumulate::TracePath::choose(settings.trace, &gpu.device)?;
    let report = &gpu.device.report;
    let device: String = format!("{} / {} {} / {}", report.name, report.driver_name, report.driver_info, path.name())
        .chars()
        .map(|c| if c.is_ascii() && !c.is_ascii_control() { c } else { '?' })
        .collect();
    // Everything that shapes the picture, spelled out so that a new field of the scene does not compile until it
    // is placed here; not where the files were read from (shards may see the same files under other paths).
    let scene::Scene {
        source: _,
        warnings: _,
        notes: _,
        variants: _,
        meshes,
        materials,
        textures,
        images,
        nodes,
        roots,
        instances,
        cameras,
        camera,
        lights,
        animations,
        skins,
        node_motion,
        camera_motion,
        shutter,
        environment,
    } = scene;
    let mut scene_hash = hash::Fnv1a::default();
    write!(scene_hash, "{meshes:?}{materials:?}{textures:?}{images:?}{nodes:?}{roots:?}{instances:?}{cameras:?}")?;
    write!(scene_hash, "{camera:?}{lights:?}{animations:?}{node_motion:?}{camera_motion:?}{shutter:?}")?;
    if !skins.is_empty() {
        write!(scene_hash, "{skins:?}")?;
    }
    if let Some(scene::environment::Environment { name: _, width, height, texels, rotation_degrees, intensity }) =
        environment
    {
        write!(scene_hash, "{width} {height} {texels:?} {rotation_degrees:?} {intensity:?}")?;
    }
    // The settings that change the picture: not where it is written, nor how rays are traced (the device says).
    let picture = scene::settings::RenderSettings { output: None, trace: Default::default(), ..settings.clone() };
    let mut settings_hash = hash::Fnv1a::default();
    write!(settings_hash, "{picture:?}")?;
    Ok(partial::file::Provenance {
        strata_version: env!("CARGO_PKG_VERSION").to_string(),
        device,
        scene: scene_hash.text(),
        settings: settings_hash.text(),
        seed: settings.seed,
    })
}

/// An empty directory of a unit test's own under the system's temporary directory (each test names its own).
#[cfg(test)]
pub(crate) fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("strata-unit-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
