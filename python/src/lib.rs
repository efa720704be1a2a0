//! `strata._strata`: the native half of the Python package. It wraps the library API (`strata::Renderer`,
//! `strata::Scene`) and hands frames back as raw bytes with their shape and type; `strata/__init__.py` turns them
//! into numpy arrays. The GIL is released while a frame renders; Ctrl-C stops it between sample batches.
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::path::PathBuf;
use strata::render::aov::Aov;
use strata::renderer::{InputError, MaterialFactors};
use strata::scene::camera::Orbit;
use strata::scene::framing::View;
use strata::scene::settings::{Backdrop, Primary, SamplerKind, SettingsOverrides, ToneMap, Trace};

/// strata's error as Python's: bad input is a ValueError, the rest (the device, the layer) a RuntimeError; the
/// message is the command line's.
fn to_py(error: anyhow::Error) -> PyErr {
    if error.downcast_ref::<strata::render::frame::Interrupted>().is_some() {
        return PyKeyboardInterrupt::new_err("render interrupted");
    }
    let message = format!("{error:#}");
    if InputError::is_input(&error) {
        PyValueError::new_err(message)
    } else {
        PyRuntimeError::new_err(message)
    }
}

fn bad(message: String) -> PyErr {
    PyValueError::new_err(message)
}

/// A device, its pipelines and each live scene's uploads, kept across renders.
#[pyclass(module = "strata._strata")]
struct Renderer {
    inner: Option<strata::Renderer>,
}

impl Renderer {
    fn open(&mut self) -> PyResult<&mut strata::Renderer> {
        self.inner.as_mut().ok_or_else(|| PyRuntimeError::new_err("this Renderer is closed"))
    }
}

/// A scene loaded once and changed between renders.
#[pyclass(module = "strata._strata")]
struct Scene {
    inner: strata::Scene,
}

/// The options of one render, as Python passes them (None: the scene file's setting, else strata's default).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct RenderOptions {
    size: Option<(u32, u32)>,
    spp: Option<u32>,
    seed: Option<u64>,
    sampler: Option<String>,
    primary: Option<String>,
    shading_samples: Option<u32>,
    indirect: Option<bool>,
    bounces: Option<u32>,
    exposure: Option<ExposureOption>,
    tone_map: Option<String>,
    background: Option<BackgroundOption>,
    environment: Option<PathBuf>,
    environment_rotation: Option<f32>,
    environment_intensity: Option<f32>,
    orbit: Option<Vec<f32>>,
    target: Option<(f32, f32, f32)>,
    yfov: Option<f32>,
    aperture: Option<f32>,
    focus: Option<f32>,
    time: Option<f32>,
    fps: Option<f32>,
    shutter_angle: Option<f32>,
    aovs: Option<Vec<String>>,
    denoise: Option<bool>,
}

#[derive(FromPyObject)]
enum ExposureOption {
    Stops(f32),
    Named(String),
}

#[derive(FromPyObject)]
enum BackgroundOption {
    Colour((f32, f32, f32)),
    Named(String),
}

fn parse<T>(value: &Option<String>, parse: fn(&str) -> anyhow::Result<T>) -> PyResult<Option<T>> {
    value.as_deref().map(parse).transpose().map_err(|e| bad(format!("{e:#}")))
}

impl RenderOptions {
    fn request(&self) -> PyResult<strata::RenderRequest> {
        let (backdrop, background) = match &self.background {
            None => (None, None),
            Some(BackgroundOption::Colour((r, g, b))) => (Some(Backdrop::Colour), Some(glam::Vec3::new(*r, *g, *b))),
            Some(BackgroundOption::Named(n)) if n == "environment" => (Some(Backdrop::Environment), None),
            Some(BackgroundOption::Named(n)) if n == "transparent" => (Some(Backdrop::Transparent), None),
            Some(BackgroundOption::Named(n)) => {
                return Err(bad(format!(
                    "background {n:?}: give \"environment\", \"transparent\" or an (r, g, b) colour"
                )))
            }
        };
        let (exposure, auto_exposure) = match &self.exposure {
            None => (None, false),
            Some(ExposureOption::Stops(s)) => (Some(*s), false),
            Some(ExposureOption::Named(n)) if n == "auto" => (None, true),
            Some(ExposureOption::Named(n)) => {
                return Err(bad(format!("exposure {n:?}: give a number of stops or \"auto\"")))
            }
        };
        let orbit = match self.orbit.as_deref() {
            None => None,
            Some(&[theta, phi]) => Some(Orbit { theta_degrees: theta, phi_degrees: phi, distance: None }),
            Some(&[theta, phi, distance]) => {
                Some(Orbit { theta_degrees: theta, phi_degrees: phi, distance: Some(distance) })
            }
            Some(other) => {
                return Err(bad(format!(
                    "orbit {other:?}: give (theta, phi) or (theta, phi, distance), degrees and metres"
                )))
            }
        };
        if let Some(o) = &orbit {
            if !o.theta_degrees.is_finite()
                || !o.phi_degrees.is_finite()
                || o.distance.is_some_and(|d| !(d > 0.0 && d.is_finite()))
            {
                return Err(bad("orbit: angles must be finite and the distance positive".into()));
            }
        }
        let aovs = match &self.aovs {
            None => Vec::new(),
            Some(names) if names.is_empty() => Vec::new(),
            Some(names) => Aov::parse_list(&names.join(",")).map_err(|e| bad(format!("{e:#}")))?,
        };
        let defaults = strata::RenderRequest::default();
        Ok(strata::RenderRequest {
            settings: SettingsOverrides {
                width: self.size.map(|s| s.0),
                height: self.size.map(|s| s.1),
                spp: self.spp,
                sampler: parse(&self.sampler, SamplerKind::parse)?,
                seed: self.seed,
                background,
                backdrop,
                exposure,
                tone_map: parse(&self.tone_map, ToneMap::parse)?,
                primary: parse(&self.primary, Primary::parse)?,
                indirect: self.indirect,
                bounces: self.bounces,
                shading_samples: self.shading_samples,
                trace: None,
                output: None,
            },
            auto_exposure,
            view: View {
                orbit,
                target: self.target.map(|(x, y, z)| glam::Vec3::new(x, y, z)),
                yfov_degrees: self.yfov,
                turntable: false,
            },
            lens: strata::scene::settings::CameraOverrides {
                aperture_radius: self.aperture,
                focus_distance: self.focus,
                shutter: None,
            },
            time: self.time,
            fps: self.fps.unwrap_or(defaults.fps),
            shutter_angle: self.shutter_angle.unwrap_or(defaults.shutter_angle),
            environment: self.environment.clone(),
            environment_rotation: self.environment_rotation,
            environment_intensity: self.environment_intensity,
            aovs,
            denoise: self.denoise.unwrap_or(false),
        })
    }
}

/// One array's raw data: (bytes, shape, numpy dtype name).
fn array<'py>(
    py: Python<'py>,
    frame: &strata::output::Frame,
    channels: usize,
    label: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let mut bytes = Vec::with_capacity(w * h * channels * 4);
    for p in &frame.pixels {
        for &v in &p[..channels] {
            let word = if label { (v as u32).to_le_bytes() } else { v.to_le_bytes() };
            bytes.extend_from_slice(&word);
        }
    }
    let shape: Vec<usize> = if channels == 1 { vec![h, w] } else { vec![h, w, channels] };
    let dtype = if label { "<u4" } else { "<f4" };
    Ok((PyBytes::new(py, &bytes), shape, dtype).into_pyobject(py)?.into_any())
}

fn rendered_to_dict<'py>(py: Python<'py>, r: &strata::Rendered) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("color", array(py, &r.color, 4, false)?)?;
    if let Some(noisy) = &r.noisy {
        dict.set_item("noisy", array(py, noisy, 4, false)?)?;
    }
    let (w, h) = (r.color.width as usize, r.color.height as usize);
    dict.set_item("display", (PyBytes::new(py, &r.display), vec![h, w, 4], "|u1"))?;
    for (aov, frame) in &r.aovs {
        dict.set_item(aov.name(), array(py, frame, aov.channels(), aov.is_label())?)?;
    }
    dict.set_item("camera", r.camera.to_json().to_string())?;
    let stats = PyDict::new(py);
    stats.set_item("seconds", r.stats.seconds)?;
    stats.set_item("samples", r.stats.samples)?;
    stats.set_item("trace", r.stats.trace.name())?;
    stats.set_item("shadow_rays", r.stats.shadow_rays)?;
    stats.set_item("secondary_rays", r.stats.secondary_rays)?;
    stats.set_item("camera_rays", r.stats.camera_rays)?;
    stats.set_item("exposure", r.camera.exposure)?;
    dict.set_item("stats", stats)?;
    dict.set_item("warnings", PyList::new(py, &r.warnings)?)?;
    Ok(dict)
}

#[pymethods]
impl Renderer {
    #[new]
    #[pyo3(signature = (*, validation = false, device = None, trace = "auto"))]
    fn new(py: Python<'_>, validation: bool, device: Option<String>, trace: &str) -> PyResult<Self> {
        let trace = Trace::parse(trace).map_err(|e| bad(format!("{e:#}")))?;
        let options = strata::RendererOptions { validation, echo_messages: false, device, trace };
        let inner = py.allow_threads(|| strata::Renderer::new(&options)).map_err(to_py)?;
        Ok(Self { inner: Some(inner) })
    }

    /// The device's name, its driver and how it traces rays.
    #[getter]
    fn device(&mut self) -> PyResult<String> {
        let report = &self.open()?.gpu().device.report;
        Ok(format!("{} ({} {})", report.name, report.driver_name, report.driver_info))
    }

    /// Bytes of device memory held now.
    #[getter]
    fn device_bytes(&mut self) -> PyResult<u64> {
        Ok(self.open()?.device_bytes())
    }

    #[pyo3(signature = (path, *, animation = None, variant = None, allow_any_uri = false))]
    fn load(
        &self,
        py: Python<'_>,
        path: PathBuf,
        animation: Option<String>,
        variant: Option<String>,
        allow_any_uri: bool,
    ) -> PyResult<Scene> {
        let animation = animation.as_deref().map(strata::scene::animation::AnimationChoice::parse);
        let options = strata::LoadOptions { allow_any_uri: allow_any_uri.then_some(true), animation, variant };
        let inner = py.allow_threads(|| strata::Scene::load(&path, &options)).map_err(to_py)?;
        Ok(Scene { inner })
    }

    /// Renders and returns the raw arrays (see strata.Renderer.render).
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        scene: &mut Scene,
        options: RenderOptions,
    ) -> PyResult<Bound<'py, PyDict>> {
        let request = options.request()?;
        let renderer = self.open()?;
        let scene = &mut scene.inner;
        let mut signal: Option<PyErr> = None;
        let rendered = py.allow_threads(|| {
            // Between sample batches: take the GIL for a moment to see whether Ctrl-C was pressed.
            let mut progress = |_: u32, _: u32| match Python::with_gil(|py| py.check_signals()) {
                Ok(()) => true,
                Err(e) => {
                    signal = Some(e);
                    false
                }
            };
            renderer.render(scene, &request, &mut progress)
        });
        match (rendered, signal) {
            (Ok(r), _) => rendered_to_dict(py, &r),
            (Err(_), Some(signal)) => Err(signal),
            (Err(e), None) => Err(to_py(e)),
        }
    }

    /// Frees the scenes' uploads and the device; with validation, raises if the layer reported anything.
    fn close(&mut self) -> PyResult<()> {
        match self.inner.take() {
            Some(inner) => inner.close().map_err(to_py),
            None => Ok(()),
        }
    }
}

/// A 4x4 matrix given as Python rows; `what` names it in the error.
fn mat4_from_rows(rows: Vec<Vec<f32>>, what: &str) -> PyResult<glam::Mat4> {
    if rows.len() != 4 || rows.iter().any(|r| r.len() != 4) {
        return Err(bad(format!("{what} is 4 rows of 4 numbers")));
    }
    let flat: Vec<f32> = rows.into_iter().flatten().collect();
    Ok(glam::Mat4::from_cols_slice(&flat).transpose())
}

fn node_of(scene: &strata::Scene, node: &Bound<'_, PyAny>) -> PyResult<usize> {
    if let Ok(name) = node.extract::<String>() {
        return scene.node_index(&name).map_err(to_py);
    }
    node.extract::<usize>().map_err(|_| bad("a node is its name (str) or its index (int)".into()))
}

fn material_of(scene: &strata::Scene, material: &Bound<'_, PyAny>) -> PyResult<usize> {
    if let Ok(name) = material.extract::<String>() {
        return scene.material_index(&name).map_err(to_py);
    }
    material.extract::<usize>().map_err(|_| bad("a material is its name (str) or its index (int)".into()))
}

#[pymethods]
impl Scene {
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.path().to_path_buf()
    }

    #[getter]
    fn node_names(&self) -> Vec<String> {
        self.inner.scene().nodes.iter().map(|n| n.name.clone()).collect()
    }

    #[getter]
    fn material_names(&self) -> Vec<String> {
        self.inner.scene().materials.iter().map(|m| m.name.clone()).collect()
    }

    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.scene().warnings.clone()
    }

    /// A node's local transform (4x4 rows, relative to its parent).
    fn node_transform(&self, node: &Bound<'_, PyAny>) -> PyResult<Vec<[f32; 4]>> {
        let m = self.inner.node_transform(node_of(&self.inner, node)?).map_err(to_py)?;
        Ok((0..4).map(|r| m.row(r).to_array()).collect())
    }

    /// Sets a node's local transform (4x4 rows): it moves in the next render, with no reload.
    fn set_node_transform(&mut self, node: &Bound<'_, PyAny>, matrix: Vec<Vec<f32>>) -> PyResult<()> {
        let index = node_of(&self.inner, node)?;
        let m = mat4_from_rows(matrix, "a transform")?;
        self.inner.set_node_transform(index, m).map_err(to_py)
    }

    /// Changes a material's factors; None leaves one as it is.
    #[pyo3(signature = (material, *, base_color = None, metallic = None, roughness = None, emissive = None))]
    fn set_material(
        &mut self,
        material: &Bound<'_, PyAny>,
        base_color: Option<[f32; 4]>,
        metallic: Option<f32>,
        roughness: Option<f32>,
        emissive: Option<[f32; 3]>,
    ) -> PyResult<()> {
        let index = material_of(&self.inner, material)?;
        let factors = MaterialFactors {
            base_color: base_color.map(glam::Vec4::from_array),
            metallic,
            roughness,
            emissive: emissive.map(glam::Vec3::from_array),
        };
        self.inner.set_material(index, &factors).map_err(to_py)
    }

    /// Sets the scene's environment: "studio", an image file, or None.
    #[pyo3(signature = (environment, *, rotation = None, intensity = None))]
    fn set_environment(
        &mut self,
        environment: Option<PathBuf>,
        rotation: Option<f32>,
        intensity: Option<f32>,
    ) -> PyResult<()> {
        let mut loaded = match environment {
            Some(path) => {
                Some(strata::scene::environment::Environment::named(&path).map_err(|e| bad(format!("{e:#}")))?)
            }
            None => None,
        };
        if let Some(e) = &mut loaded {
            e.rotation_degrees = rotation.unwrap_or(e.rotation_degrees);
            e.intensity = intensity.unwrap_or(e.intensity);
        }
        self.inner.set_environment(loaded);
        Ok(())
    }

    /// Adds a directional light shining along `direction` with irradiance `irradiance` (linear RGB, W/m²).
    fn add_directional_light(&mut self, direction: [f32; 3], irradiance: [f32; 3]) -> PyResult<()> {
        let d = glam::Vec3::from_array(direction);
        if !d.is_finite() || d.length() < 1e-6 {
            return Err(bad("a light's direction must be a finite, non-zero vector".into()));
        }
        let d = d.normalize();
        let up = if d.y.abs() > 0.99 { glam::Vec3::Z } else { glam::Vec3::Y };
        let mut lights = self.inner.scene().lights.clone();
        lights.push(strata::scene::Light {
            name: format!("directional light {}", lights.len()),
            shape: strata::scene::LightShape::Directional,
            emission: glam::Vec3::from_array(irradiance),
            world_from_light: strata::scene::camera::look_at(glam::Vec3::ZERO, d, up),
            node: None,
            range: 0.0,
        });
        self.inner.set_lights(lights).map_err(to_py)
    }

    /// Sets a perspective camera: its pose (4x4 rows, glTF axes: looking down its -Z, +Y up), vertical field of
    /// view in degrees, clip planes in metres (zfar None: infinite) and thin lens (aperture radius 0: pinhole).
    #[pyo3(signature = (world_from_camera, *, yfov = 45.0, znear = 0.01, zfar = None, aperture = 0.0, focus = 1.0))]
    fn set_camera(
        &mut self,
        world_from_camera: Vec<Vec<f32>>,
        yfov: f32,
        znear: f32,
        zfar: Option<f32>,
        aperture: f32,
        focus: f32,
    ) -> PyResult<()> {
        let camera = strata::scene::Camera {
            name: "Python camera".into(),
            world_from_camera: mat4_from_rows(world_from_camera, "a camera pose")?,
            projection: strata::scene::Projection::Perspective { yfov: yfov.to_radians(), znear, zfar },
            lens: strata::scene::camera::Lens { aperture_radius: aperture, focus_distance: focus },
        };
        self.inner.set_camera(Some(camera)).map_err(to_py)
    }

    /// Removes every light (emissive surfaces and the environment stay).
    fn clear_lights(&mut self) -> PyResult<()> {
        self.inner.set_lights(Vec::new()).map_err(to_py)
    }

    fn __repr__(&self) -> String {
        let s = self.inner.scene();
        format!(
            "<strata.Scene {} : {} nodes, {} triangles, {} materials, {} lights>",
            self.inner.path().display(),
            s.nodes.len(),
            s.triangle_count(),
            s.materials.len(),
            s.lights.len()
        )
    }
}

#[pymodule]
fn _strata(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Renderer>()?;
    m.add_class::<Scene>()?;
    m.add("AOV_NAMES", Aov::NAMES.to_vec())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
