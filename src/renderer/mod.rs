//! The library's front door: a [`Renderer`] a program holds (the device, its pipelines, each scene's uploads)
//! and [`Scene`]s it loads once and changes between renders. `strata render` and the Python package are built
//! on it (docs/architecture.md, "Library API").
//!
//! ```no_run
//! # fn main() -> anyhow::Result<()> {
//! use strata::render::aov::Aov;
//! let mut renderer = strata::Renderer::new(&strata::RendererOptions::default())?;
//! let mut scene = strata::Scene::load("scenes/cornell.toml".as_ref(), &Default::default())?;
//! let request = strata::RenderRequest { aovs: vec![Aov::Depth, Aov::Instance], ..Default::default() };
//! let first = renderer.render(&mut scene, &request, &mut |_, _| true)?;
//! // Move a node and render again: nothing is uploaded twice.
//! let node = scene.node_index("tall box")?;
//! let moved = glam::Mat4::from_translation(glam::Vec3::X * 0.1) * scene.node_transform(node)?;
//! scene.set_node_transform(node, moved)?;
//! let second = renderer.render(&mut scene, &request, &mut |_, _| true)?;
//! assert_eq!(first.color.width, second.color.width);
//! renderer.close()
//! # }
//! ```
mod request;
mod scene;

pub use request::{RenderRequest, Rendered};
pub use scene::{MaterialFactors, Scene};

use crate::render::SceneOnGpu;
use crate::scene::environment::Environment;
use crate::scene::settings::Trace;
use crate::vk::{Gpu, GpuOptions};
use anyhow::{anyhow, Context as _, Result};
use std::path::PathBuf;
use std::sync::{Arc, Weak};

/// Bad input (a file, a name, an option): the caller's to fix, not the device's. Python raises `ValueError` for
/// it and `RuntimeError` for everything else.
#[derive(Debug)]
pub struct InputError(String);

impl InputError {
    pub fn new(message: String) -> Self {
        Self(message)
    }

    /// Whether `error` (or what it wraps) is bad input.
    pub fn is_input(error: &anyhow::Error) -> bool {
        error.downcast_ref::<InputError>().is_some()
    }
}

impl From<anyhow::Error> for InputError {
    fn from(error: anyhow::Error) -> Self {
        Self(format!("{error:#}"))
    }
}

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for InputError {}

/// How to open the device.
#[derive(Debug, Clone, Default)]
pub struct RendererOptions {
    /// Run under the Khronos validation layer; every render then fails on any message it reports.
    pub validation: bool,
    /// Echo the layer's messages to stderr as they arrive.
    pub echo_messages: bool,
    /// A device name (substring) or index; None: the first that can trace rays.
    pub device: Option<String>,
    /// How rays are traced.
    pub trace: Trace,
}

/// A scene's uploads, kept while the scene lives.
struct Upload {
    scene_id: u64,
    alive: Weak<()>,
    on_gpu: SceneOnGpu,
    /// The environment `on_gpu` holds: a scene whose environment changed uploads it again.
    environment: Option<Environment>,
}

/// The device, its pipelines (built by the first render and kept) and each live scene's geometry, textures and
/// acceleration structures.
pub struct Renderer {
    uploads: Vec<Upload>,
    /// The last environment file read for a request, with its modification time.
    environment_file: Option<(PathBuf, Option<std::time::SystemTime>, Environment)>,
    denoiser: Option<crate::denoise::Denoiser>,
    validation: bool,
    /// Declared last: dropped after the uploads that live on it.
    gpu: Gpu,
}

impl Renderer {
    /// Opens the device (and the validation layer when asked).
    pub fn new(options: &RendererOptions) -> Result<Self> {
        let gpu = Gpu::new(&GpuOptions {
            validation: options.validation,
            echo_messages: options.echo_messages,
            device: options.device.clone(),
            needs: crate::render::accumulate::TracePath::device_needs(options.trace),
        })?;
        Ok(Self { uploads: Vec::new(), environment_file: None, denoiser: None, validation: options.validation, gpu })
    }

    /// The device, for programs that drive the passes themselves.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// Fails with the layer's report if it said anything (with validation on).
    pub fn check_validation(&self) -> Result<()> {
        if !self.validation {
            return Ok(());
        }
        self.gpu.validation_log().check().map_err(|report| anyhow!("{report}"))
    }

    /// Frees every upload and the device, then checks what the layer said during teardown.
    pub fn close(self) -> Result<()> {
        let (log, validation) = (self.gpu.validation_log(), self.validation);
        drop(self);
        if validation {
            log.check().map_err(|report| anyhow!("{report}"))?;
        }
        Ok(())
    }

    /// Bytes of device memory the renderer holds now (uploads and kept buffers).
    pub fn device_bytes(&self) -> u64 {
        self.gpu.device.allocator().generate_report().total_allocated_bytes
    }

    /// `scene`'s uploads: made by its first render, kept while it lives; its environment uploaded again when it
    /// changed. Uploads of scenes that were dropped are freed here.
    pub fn upload(&mut self, scene: &Scene) -> Result<&SceneOnGpu> {
        let index = self.upload_index(scene)?;
        Ok(&self.uploads[index].on_gpu)
    }

    /// Where `scene`'s upload sits in `uploads`, made or refreshed as [`Renderer::upload`] says.
    fn upload_index(&mut self, scene: &Scene) -> Result<usize> {
        self.uploads.retain(|u| u.alive.strong_count() > 0);
        let device = &self.gpu.device;
        let index = match self.uploads.iter().position(|u| u.scene_id == scene.id) {
            Some(i) => i,
            None => {
                let on_gpu = SceneOnGpu::upload(device, &scene.scene)
                    .with_context(|| format!("{}: uploading the scene", scene.path().display()))?;
                let environment = scene.scene.environment.clone();
                self.uploads.push(Upload {
                    scene_id: scene.id,
                    alive: Arc::downgrade(&scene.alive),
                    on_gpu,
                    environment,
                });
                self.uploads.len() - 1
            }
        };
        let upload = &mut self.uploads[index];
        if upload.environment != scene.scene.environment {
            upload.on_gpu.environment = crate::render::environment::upload(device, scene.scene.environment.as_ref())?;
            upload.environment = scene.scene.environment.clone();
        }
        Ok(index)
    }

    /// Renders `scene` as `request` asks. The scene comes back as it was: the request's camera, environment,
    /// default light and shutter hold for this render only. `progress(done, total)` is called as samples finish;
    /// returning `false` stops the render with [`crate::render::frame::Interrupted`].
    pub fn render(
        &mut self,
        scene: &mut Scene,
        request: &RenderRequest,
        progress: &mut dyn FnMut(u32, u32) -> bool,
    ) -> Result<Rendered> {
        let settings = request.settings_over(&scene.file_settings)?;
        let environment = self.request_environment(request)?;
        let kept = Kept::of(&scene.scene, request);
        let warnings = prepare(&mut scene.scene, request, &settings, environment).map_err(InputError::from);
        let rendered = match warnings {
            Ok(warnings) => self.render_prepared(scene, request, settings, warnings, progress),
            Err(e) => Err(e.into()),
        };
        kept.restore(&mut scene.scene);
        let rendered = rendered?;
        self.check_validation()?;
        Ok(rendered)
    }

    /// The environment file a request names, read once while it stays unchanged on disk.
    fn request_environment(&mut self, request: &RenderRequest) -> Result<Option<Environment>> {
        let Some(path) = &request.environment else { return Ok(None) };
        let modified = std::fs::metadata(path).and_then(|m| m.modified()).ok();
        if let Some((p, m, environment)) = &self.environment_file {
            if p == path && *m == modified && path.as_os_str() != "studio" {
                return Ok(Some(environment.clone()));
            }
        }
        let environment = Environment::named(path).map_err(InputError::from)?;
        self.environment_file = Some((path.clone(), modified, environment.clone()));
        Ok(Some(environment))
    }

    fn render_prepared(
        &mut self,
        scene: &Scene,
        request: &RenderRequest,
        settings: crate::scene::settings::RenderSettings,
        warnings: Vec<String>,
        progress: &mut dyn FnMut(u32, u32) -> bool,
    ) -> Result<Rendered> {
        if request.denoise && self.denoiser.is_none() {
            self.denoiser = Some(crate::denoise::Denoiser::load()?);
        }
        let index = self.upload_index(scene)?;
        let on_gpu = &self.uploads[index].on_gpu;
        let (device, scene) = (&self.gpu.device, &scene.scene);
        let options = crate::render::frame::FrameOptions::default();
        let mut frame = crate::render::frame::render_frame(device, scene, on_gpu, &settings, &options, progress)?;
        let size = (settings.width, settings.height);
        let aovs = if request.aovs.is_empty() {
            Vec::new()
        } else {
            crate::render_aovs(device, scene, on_gpu, size, &request.aovs, 1.0 / request.fps)?
        };
        let noisy = match &self.denoiser {
            Some(denoiser) if request.denoise => {
                Some(crate::denoise_frame(denoiser, device, scene, on_gpu, &settings, &mut frame)?)
            }
            _ => None,
        };
        let camera = crate::scene::camera::CameraMetadata {
            width: settings.width,
            height: settings.height,
            camera: scene.camera_at(scene.shutter.0),
            time: scene.shutter.0,
            exposure: frame.exposure,
        };
        Ok(Rendered {
            color: frame.linear,
            display: frame.display,
            noisy,
            aovs,
            camera,
            stats: frame.stats,
            settings,
            warnings,
        })
    }
}

/// Lays a request over the scene for one render: its environment, lighting, camera, lens and shutter. Returns
/// the warnings to pass on.
fn prepare(
    scene: &mut crate::scene::Scene,
    request: &RenderRequest,
    settings: &crate::scene::settings::RenderSettings,
    environment: Option<Environment>,
) -> Result<Vec<String>> {
    if environment.is_some() {
        scene.environment = environment;
    }
    match &mut scene.environment {
        Some(e) => {
            e.rotation_degrees = request.environment_rotation.unwrap_or(e.rotation_degrees);
            e.intensity = request.environment_intensity.unwrap_or(e.intensity);
            if !e.rotation_degrees.is_finite() || !e.intensity.is_finite() || e.intensity < 0.0 {
                anyhow::bail!("environment rotation and intensity must be finite, the intensity not negative");
            }
        }
        None if request.environment_rotation.is_some() || request.environment_intensity.is_some() => {
            anyhow::bail!("an environment rotation or intensity needs an environment");
        }
        None => {}
    }
    let warnings = scene.light_for_render(settings.backdrop)?.into_iter().collect();
    let aspect = settings.width as f32 / settings.height as f32;
    crate::scene::framing::Framing::of(&request.view, scene, aspect)?.apply(scene);
    if let Some(t) = request.time {
        scene.shutter = crate::scene::framing::frame_shutter(t, request.fps, request.shutter_angle);
    }
    request.lens.apply(scene)?;
    Ok(warnings)
}

/// What a render changes in a scene for itself, to put back afterwards.
struct Kept {
    camera: Option<crate::scene::Camera>,
    shutter: (f32, f32),
    lights: usize,
    /// The scene's environment, kept only when the request changes it (its texels are the one large part).
    environment: Option<Option<Environment>>,
}

impl Kept {
    fn of(scene: &crate::scene::Scene, request: &RenderRequest) -> Self {
        let changes_environment = request.environment.is_some()
            || request.environment_rotation.is_some()
            || request.environment_intensity.is_some();
        Self {
            camera: scene.camera.clone(),
            shutter: scene.shutter,
            lights: scene.lights.len(),
            environment: changes_environment.then(|| scene.environment.clone()),
        }
    }

    fn restore(self, scene: &mut crate::scene::Scene) {
        scene.camera = self.camera;
        scene.shutter = self.shutter;
        scene.lights.truncate(self.lights);
        if let Some(environment) = self.environment {
            scene.environment = environment;
        }
    }
}
