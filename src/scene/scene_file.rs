//! The scene file (`scene.toml`): names a glTF file and adds what glTF has no words for — lens, shutter, area
//! lights, Perlin bump materials, motion, render settings. Unknown keys, wrong types and out-of-range values are
//! errors with the file, line and column. The format is documented in `docs/scene-format.md`.
use super::camera::{look_at, Lens};
use super::environment::Environment;
use super::gltf_import::{load_gltf, LoadOptions};
use super::gltf_uri::UriPolicy;
use super::material::{BumpDerivative, BumpMap, NoiseKind};
use super::settings::{Backdrop, Primary, SamplerKind, SettingsOverrides, ToneMap, Trace};
use super::settings::{MAX_BOUNCES, MAX_IMAGE_SIDE, MAX_SHADING_SAMPLES, MAX_SPP};
use super::{Light, LightShape, NodeMotion, Projection, RigidMotion, Scene};
use anyhow::{anyhow, bail, Result};
use glam::{Vec2, Vec3};
use serde::Deserialize;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

type S<T> = Spanned<T>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileRoot {
    gltf: S<String>,
    #[serde(default)]
    allow_any_uri: bool,
    animation: Option<S<toml::Value>>,
    variant: Option<S<String>>,
    camera: Option<CameraSection>,
    #[serde(default, rename = "light")]
    lights: Vec<LightSection>,
    #[serde(default, rename = "bump")]
    bumps: Vec<BumpSection>,
    #[serde(default, rename = "motion")]
    motions: Vec<MotionSection>,
    #[serde(default, rename = "semantic")]
    semantics: Vec<SemanticSection>,
    render: Option<RenderSection>,
    environment: Option<EnvironmentSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentSection {
    /// An equirectangular .hdr or .exr image, relative to the scene file.
    file: Option<S<String>>,
    /// Or one strata makes: "studio".
    builtin: Option<S<String>>,
    rotation_degrees: Option<S<f32>>,
    intensity: Option<S<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSection {
    gltf_camera: Option<S<toml::Value>>,
    position: Option<S<[f32; 3]>>,
    look_at: Option<S<[f32; 3]>>,
    up: Option<S<[f32; 3]>>,
    yfov_degrees: Option<S<f32>>,
    aperture_radius: Option<S<f32>>,
    f_number: Option<S<f32>>,
    focus_distance: Option<S<f32>>,
    shutter: Option<S<[f32; 2]>>,
    velocity: Option<S<[f32; 3]>>,
    angular_velocity: Option<S<[f32; 3]>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightSection {
    name: Option<String>,
    #[serde(rename = "type")]
    kind: S<String>,
    position: S<[f32; 3]>,
    direction: Option<S<[f32; 3]>>,
    size: Option<S<[f32; 2]>>,
    radius: Option<S<f32>>,
    range: Option<S<f32>>,
    color: Option<S<[f32; 3]>>,
    radiance: Option<S<f32>>,
    power: Option<S<f32>>,
    intensity: Option<S<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BumpSection {
    material: Option<S<String>>,
    kind: Option<S<String>>,
    amplitude: Option<S<f32>>,
    frequency: Option<S<f32>>,
    octaves: Option<S<u32>>,
    lacunarity: Option<S<f32>>,
    gain: Option<S<f32>>,
    derivative: Option<S<String>>,
    epsilon: Option<S<f32>>,
}

/// A semantic class for the nodes whose names match a pattern (`*` any run of characters, `?` one).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SemanticSection {
    nodes: S<String>,
    category_id: S<i64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MotionSection {
    node: S<String>,
    velocity: Option<S<[f32; 3]>>,
    angular_velocity: Option<S<[f32; 3]>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderSection {
    width: Option<S<u32>>,
    height: Option<S<u32>>,
    spp: Option<S<u32>>,
    sampler: Option<S<String>>,
    seed: Option<u64>,
    background: Option<S<toml::Value>>,
    exposure: Option<S<f32>>,
    tone_map: Option<S<String>>,
    primary: Option<S<String>>,
    indirect: Option<bool>,
    bounces: Option<S<u32>>,
    shading_samples: Option<S<u32>>,
    trace: Option<S<String>>,
    output: Option<String>,
}

/// A loaded scene file: the scene with the file's additions applied and its render settings.
#[derive(Debug)]
pub struct SceneFile {
    pub scene: Scene,
    pub settings: SettingsOverrides,
    /// The animation clip the file's `animation` key names (it plays unless the command line names another).
    pub animation: Option<super::animation::AnimationChoice>,
    /// The material variant the file's `variant` key names (unless the command line names another).
    pub variant: Option<String>,
    /// The glTF file it names, resolved against the scene file's directory.
    pub gltf_path: PathBuf,
}

/// Positions in the file's text for error messages: `file:line:column: message`.
struct Source<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Source<'_> {
    fn position(&self, offset: usize) -> (usize, usize) {
        let before = &self.text[..offset.min(self.text.len())];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map(|l| l.chars().count()).unwrap_or(0) + 1;
        (line, column)
    }

    fn error(&self, span: Range<usize>, message: impl std::fmt::Display) -> anyhow::Error {
        let (line, column) = self.position(span.start);
        anyhow!("{}:{line}:{column}: {message}", self.path.display())
    }

    fn finite<const N: usize>(&self, v: &S<[f32; N]>, what: &str) -> Result<[f32; N]> {
        if v.get_ref().iter().all(|x| x.is_finite()) {
            Ok(*v.get_ref())
        } else {
            Err(self.error(v.span(), format!("{what} must be finite numbers")))
        }
    }

    /// A value in `lo..=hi` (or `lo..hi` when `open_hi`), or an error at its position.
    fn in_range(&self, v: &S<f32>, what: &str, lo: f32, hi: f32) -> Result<f32> {
        let x = *v.get_ref();
        if x.is_finite() && x >= lo && x <= hi {
            Ok(x)
        } else {
            Err(self.error(v.span(), format!("{what} = {x} is out of range ({lo} to {hi})")))
        }
    }

    /// An optional whole number in `lo..=hi`, or an error at its position.
    fn count_in_range(&self, v: &Option<S<u32>>, what: &str, lo: u32, hi: u32) -> Result<Option<u32>> {
        match v {
            Some(n) if (lo..=hi).contains(n.get_ref()) => Ok(Some(*n.get_ref())),
            Some(n) => Err(self.error(n.span(), format!("{what} = {} is out of range ({lo} to {hi})", n.get_ref()))),
            None => Ok(None),
        }
    }

    fn positive(&self, v: &S<f32>, what: &str) -> Result<f32> {
        let x = *v.get_ref();
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.error(v.span(), format!("{what} = {x} must be a positive number")))
        }
    }

    fn direction(&self, v: &S<[f32; 3]>, what: &str) -> Result<Vec3> {
        let d = Vec3::from_array(self.finite(v, what)?);
        if d.length_squared() < 1e-12 {
            return Err(self.error(v.span(), format!("{what} must not be the zero vector")));
        }
        Ok(d.normalize())
    }
}

/// The largest scene file read (they are a few hundred bytes; this is far past any real one).
pub const MAX_SCENE_FILE_BYTES: u64 = 16 << 20;

/// Loads `path` (a scene file) and the glTF it names, and applies the file to the scene.
pub fn load_scene_file(path: &Path, uri_policy: Option<UriPolicy>) -> Result<SceneFile> {
    let text = crate::input::read_text_bounded(path, MAX_SCENE_FILE_BYTES, "a scene file")?;
    let source = Source { path, text: &text };
    let root = parse(&source)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let gltf_path = dir.join(root.gltf.get_ref());
    let policy =
        uri_policy.unwrap_or(if root.allow_any_uri { UriPolicy::AnyLocalPath } else { UriPolicy::InsideDirectory });
    if !gltf_path.exists() {
        return Err(source.error(root.gltf.span(), format!("the glTF file {} does not exist", gltf_path.display())));
    }
    if !gltf_path.is_file() {
        let what = if gltf_path.is_dir() { "a directory" } else { "not a regular file" };
        return Err(source.error(root.gltf.span(), format!("the glTF file {} is {what}", gltf_path.display())));
    }
    let mut scene = load_gltf(&gltf_path, &LoadOptions { uri_policy: policy })?;
    apply(&source, &root, &mut scene)?;
    let settings = match &root.render {
        Some(r) => render_settings(&source, r, dir)?,
        None => SettingsOverrides::default(),
    };
    let animation = root.animation.as_ref().map(|a| animation_choice(&source, a)).transpose()?;
    scene.source = path.to_path_buf();
    let variant = root.variant.as_ref().map(|v| v.get_ref().clone());
    Ok(SceneFile { scene, settings, gltf_path, animation, variant })
}

/// The `animation` key: a clip's name or its index.
fn animation_choice(source: &Source<'_>, value: &S<toml::Value>) -> Result<super::animation::AnimationChoice> {
    use super::animation::AnimationChoice;
    match value.get_ref() {
        toml::Value::String(name) => Ok(AnimationChoice::Name(name.clone())),
        toml::Value::Integer(i) if *i >= 0 => Ok(AnimationChoice::Index(*i as usize)),
        other => {
            Err(source
                .error(value.span(), format!("animation = {other} must be a clip's name or its index (0, 1, ...)")))
        }
    }
}

fn parse(source: &Source<'_>) -> Result<FileRoot> {
    toml::from_str(source.text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        source.error(span, e.message().trim_end())
    })
}

/// Parses scene-file `text` (reported as `path`) and applies it to an already loaded `scene`, without loading
/// the glTF its `gltf` key names. For tools and the fuzz target; [`load_scene_file`] is the normal entry.
pub fn apply_scene_text(path: &Path, text: &str, scene: &mut Scene) -> Result<SettingsOverrides> {
    let source = Source { path, text };
    let root = parse(&source)?;
    apply(&source, &root, scene)?;
    match &root.render {
        Some(r) => render_settings(&source, r, path.parent().unwrap_or(Path::new("."))),
        None => Ok(SettingsOverrides::default()),
    }
}

fn apply(source: &Source<'_>, root: &FileRoot, scene: &mut Scene) -> Result<()> {
    if let Some(camera) = &root.camera {
        apply_camera(source, camera, scene)?;
    }
    for light in &root.lights {
        let l = build_light(source, light, scene.lights.len())?;
        scene.lights.push(l);
    }
    apply_bumps(source, &root.bumps, scene)?;
    if let Some(e) = &root.environment {
        scene.environment = Some(environment(source, e)?);
    }
    apply_semantics(source, &root.semantics, scene)?;
    for m in &root.motions {
        let name = m.node.get_ref();
        let matches: Vec<usize> =
            scene.nodes.iter().enumerate().filter(|(_, n)| &n.name == name).map(|(i, _)| i).collect();
        let node = match matches.as_slice() {
            [one] => *one,
            [] => {
                return Err(source.error(
                    m.node.span(),
                    format!("no node is named \"{name}\"; nodes: {}", list(scene.nodes.iter().map(|n| &n.name))),
                ))
            }
            _ => return Err(source.error(m.node.span(), format!("{} nodes are named \"{name}\"", matches.len()))),
        };
        if scene.node_motion.iter().any(|existing| existing.node == node) {
            return Err(source.error(m.node.span(), format!("node \"{name}\" already has a [[motion]] entry")));
        }
        let motion = rigid_motion(source, &m.velocity, &m.angular_velocity)?;
        scene.node_motion.push(NodeMotion { node, motion });
    }
    Ok(())
}

/// A constant linear and angular velocity from optional `velocity` and `angular_velocity` keys (zero if absent).
fn rigid_motion(
    source: &Source<'_>,
    velocity: &Option<S<[f32; 3]>>,
    angular_velocity: &Option<S<[f32; 3]>>,
) -> Result<RigidMotion> {
    let vector = |v: &Option<S<[f32; 3]>>, what: &str| -> Result<Vec3> {
        Ok(v.as_ref().map(|v| source.finite(v, what)).transpose()?.map(Vec3::from_array).unwrap_or_default())
    };
    Ok(RigidMotion {
        velocity: vector(velocity, "velocity")?,
        angular_velocity: vector(angular_velocity, "angular_velocity")?,
    })
}

fn list<'a>(names: impl Iterator<Item = &'a String>) -> String {
    let names: Vec<&String> = names.collect();
    let shown: Vec<String> = names.iter().take(20).map(|n| format!("\"{n}\"")).collect();
    let more = if names.len() > 20 { format!(" and {} more", names.len() - 20) } else { String::new() };
    if shown.is_empty() {
        "(none)".into()
    } else {
        format!("{}{more}", shown.join(", "))
    }
}

fn apply_camera(source: &Source<'_>, c: &CameraSection, scene: &mut Scene) -> Result<()> {
    if let Some(selector) = &c.gltf_camera {
        let index = match selector.get_ref() {
            toml::Value::Integer(i) => {
                usize::try_from(*i).ok().filter(|&i| i < scene.cameras.len()).ok_or_else(|| {
                    source.error(
                        selector.span(),
                        format!("camera index {i} is out of range ({} cameras)", scene.cameras.len()),
                    )
                })?
            }
            toml::Value::String(name) => scene.cameras.iter().position(|cam| &cam.name == name).ok_or_else(|| {
                source.error(
                    selector.span(),
                    format!("no camera is named \"{name}\"; cameras: {}", list(scene.cameras.iter().map(|c| &c.name))),
                )
            })?,
            _ => return Err(source.error(selector.span(), "gltf_camera must be a camera name or an index")),
        };
        if c.position.is_some() {
            return Err(source.error(selector.span(), "give either gltf_camera or position/look_at, not both"));
        }
        scene.camera = Some(scene.cameras[index].clone());
    }
    let mut camera = scene.camera_or_default();
    match (&c.position, &c.look_at) {
        (Some(position), Some(target)) => {
            let eye = Vec3::from_array(source.finite(position, "position")?);
            let target_point = Vec3::from_array(source.finite(target, "look_at")?);
            let up = match &c.up {
                Some(up) => source.direction(up, "up")?,
                None => Vec3::Y,
            };
            let forward = target_point - eye;
            if forward.length_squared() < 1e-12 || forward.normalize().cross(up).length_squared() < 1e-8 {
                return Err(source.error(target.span(), "look_at must differ from position and not lie along up"));
            }
            camera.world_from_camera = look_at(eye, target_point, up);
            camera.name = "scene file camera".into();
            if let Projection::Orthographic { .. } = camera.projection {
                camera.projection = Projection::Perspective { yfov: 45f32.to_radians(), znear: 0.05, zfar: None };
            }
        }
        (Some(p), None) => return Err(source.error(p.span(), "position needs look_at")),
        (None, Some(t)) => return Err(source.error(t.span(), "look_at needs position")),
        (None, None) => {
            if let Some(up) = &c.up {
                return Err(source.error(up.span(), "up needs position and look_at"));
            }
        }
    }
    if let Some(yfov) = &c.yfov_degrees {
        let degrees = source.in_range(yfov, "yfov_degrees", 0.1, 179.0)?;
        camera.projection = match camera.projection {
            Projection::Perspective { znear, zfar, .. } => {
                Projection::Perspective { yfov: degrees.to_radians(), znear, zfar }
            }
            Projection::Orthographic { .. } => {
                return Err(source.error(yfov.span(), "yfov_degrees does not apply to an orthographic camera"));
            }
        };
    }
    let aperture = match (&c.aperture_radius, &c.f_number) {
        (Some(a), None) => Some(source.in_range(a, "aperture_radius", 0.0, 10.0)?),
        (None, Some(n)) => {
            let n_value = source.in_range(n, "f_number", 0.5, 1024.0)?;
            // f-number N = focal length / aperture diameter; the focal length follows from the vertical field of
            // view on a 24 mm-tall (full-frame) sensor: focal = 12 mm / tan(yfov / 2).
            let Projection::Perspective { yfov, .. } = camera.projection else {
                return Err(source.error(n.span(), "f_number needs a perspective camera"));
            };
            let focal_length = 0.012 / (yfov * 0.5).tan();
            Some(focal_length / (2.0 * n_value))
        }
        (Some(a), Some(_)) => return Err(source.error(a.span(), "give aperture_radius or f_number, not both")),
        (None, None) => None,
    };
    let focus = c.focus_distance.as_ref().map(|f| source.positive(f, "focus_distance")).transpose()?;
    if let Some(aperture) = aperture {
        let focus = match (focus, &c.look_at) {
            (Some(f), _) => f,
            (None, Some(target)) => {
                let eye = camera.world_from_camera.w_axis.truncate();
                (Vec3::from_array(*target.get_ref()) - eye).length()
            }
            (None, None) => {
                let span = c.aperture_radius.as_ref().map(|a| a.span()).or(c.f_number.as_ref().map(|n| n.span()));
                return Err(source.error(span.unwrap_or(0..0), "a lens aperture needs focus_distance (or look_at)"));
            }
        };
        camera.lens = Lens { aperture_radius: aperture, focus_distance: focus };
    } else if let Some(f) = focus {
        camera.lens.focus_distance = f;
    }
    if let Some(shutter) = &c.shutter {
        let [open, close] = source.finite(shutter, "shutter")?;
        if open > close || open < 0.0 {
            return Err(
                source.error(shutter.span(), format!("shutter [{open}, {close}] must satisfy 0 ≤ open ≤ close"))
            );
        }
        scene.shutter = (open, close);
    }
    scene.camera_motion = rigid_motion(source, &c.velocity, &c.angular_velocity)?;
    scene.camera = Some(camera);
    Ok(())
}

fn build_light(source: &Source<'_>, l: &LightSection, index: usize) -> Result<Light> {
    let position = Vec3::from_array(source.finite(&l.position, "position")?);
    let direction = match &l.direction {
        Some(d) => source.direction(d, "direction")?,
        None => Vec3::NEG_Y,
    };
    let color = match &l.color {
        Some(c) => {
            let rgb = source.finite(c, "color")?;
            if rgb.iter().any(|&x| x < 0.0) {
                return Err(source.error(c.span(), "color must not be negative"));
            }
            Vec3::from_array(rgb)
        }
        None => Vec3::ONE,
    };
    let kind = l.kind.get_ref().as_str();
    let needs = |field: &Option<S<f32>>, name: &str| -> Result<f32> {
        match field {
            Some(v) => source.in_range(v, name, 0.0, 1e6),
            None => Err(source.error(l.kind.span(), format!("a {kind} light needs {name}"))),
        }
    };
    let forbid = |present: bool, name: &str| -> Result<()> {
        if present {
            Err(source.error(l.kind.span(), format!("a {kind} light has no {name}")))
        } else {
            Ok(())
        }
    };
    let shape = match kind {
        "quad" => {
            let size =
                l.size.as_ref().ok_or_else(|| source.error(l.kind.span(), "a quad light needs size = [w, h]"))?;
            let [w, h] = source.finite(size, "size")?;
            if w <= 0.0 || h <= 0.0 {
                return Err(source.error(size.span(), "size must be positive"));
            }
            forbid(l.radius.is_some(), "radius")?;
            LightShape::Quad { size: Vec2::new(w, h) }
        }
        "disk" => {
            forbid(l.size.is_some(), "size")?;
            LightShape::Disk {
                radius: source.positive(
                    l.radius.as_ref().ok_or_else(|| source.error(l.kind.span(), "a disk light needs radius"))?,
                    "radius",
                )?,
            }
        }
        "sphere" => {
            forbid(l.size.is_some(), "size")?;
            LightShape::Sphere {
                radius: source.positive(
                    l.radius.as_ref().ok_or_else(|| source.error(l.kind.span(), "a sphere light needs radius"))?,
                    "radius",
                )?,
            }
        }
        "point" => {
            forbid(l.size.is_some(), "size")?;
            forbid(l.direction.is_some(), "direction")?;
            LightShape::Point {
                radius: match &l.radius {
                    Some(r) => source.in_range(r, "radius", 0.0, 1e3)?,
                    None => 0.0,
                },
            }
        }
        other => {
            return Err(
                source.error(l.kind.span(), format!("unknown light type \"{other}\" (quad, disk, sphere, point)"))
            )
        }
    };
    // Orient the light's −Z along `direction`.
    let up = if direction.cross(Vec3::Y).length_squared() > 1e-6 { Vec3::Y } else { Vec3::Z };
    let world_from_light = look_at(position, position + direction, up);
    let mut light = Light {
        name: l.name.clone().unwrap_or_else(|| format!("{kind} light {index}")),
        shape,
        emission: Vec3::ZERO,
        world_from_light,
        node: None,
        range: 0.0,
    };
    if let Some(r) = &l.range {
        forbid(!matches!(shape, LightShape::Point { .. }), "range")?;
        light.range = source.positive(r, "range")?;
    }
    let given = [l.radiance.is_some(), l.power.is_some(), l.intensity.is_some()].iter().filter(|&&b| b).count();
    if given != 1 {
        return Err(source.error(l.kind.span(), "give exactly one of radiance, power or intensity"));
    }
    light.emission = match (shape, &l.radiance, &l.power, &l.intensity) {
        (LightShape::Point { .. }, None, Some(_), None) => {
            // An isotropic point source of power Φ has intensity Φ / 4π.
            color * needs(&l.power, "power")? / (4.0 * std::f32::consts::PI)
        }
        (LightShape::Point { .. }, None, None, Some(_)) => color * needs(&l.intensity, "intensity")?,
        (LightShape::Point { .. }, Some(r), _, _) => {
            return Err(source.error(r.span(), "a point light takes power or intensity"))
        }
        (_, Some(_), None, None) => color * needs(&l.radiance, "radiance")?,
        (_, None, Some(_), None) => {
            let area = light.area().unwrap_or(1.0);
            Light::radiance_from_power(color * needs(&l.power, "power")?, area)
        }
        (_, _, _, Some(i)) => return Err(source.error(i.span(), "area lights take radiance or power, not intensity")),
        _ => return Err(source.error(l.kind.span(), "give exactly one of radiance, power or intensity")),
    };
    Ok(light)
}

fn apply_bumps(source: &Source<'_>, bumps: &[BumpSection], scene: &mut Scene) -> Result<()> {
    let mut default: Option<BumpMap> = None;
    let mut assigned = vec![false; scene.materials.len()];
    for b in bumps {
        let mut bump = BumpMap::default();
        if let Some(k) = &b.kind {
            bump.kind = match k.get_ref().as_str() {
                "noise" => NoiseKind::Noise,
                "fbm" => NoiseKind::Fbm,
                "turbulence" => NoiseKind::Turbulence,
                "sine" => NoiseKind::Sine,
                other => {
                    return Err(source
                        .error(k.span(), format!("unknown noise kind \"{other}\" (noise, fbm, turbulence, sine)")))
                }
            };
        }
        if let Some(v) = &b.amplitude {
            bump.amplitude = source.in_range(v, "amplitude", -100.0, 100.0)?;
        }
        if let Some(v) = &b.frequency {
            bump.frequency = source.in_range(v, "frequency", 1e-6, 1e6)?;
        }
        if let Some(v) = &b.octaves {
            bump.octaves = *v.get_ref();
            if !(1..=16).contains(&bump.octaves) {
                return Err(source.error(v.span(), format!("octaves = {} is out of range (1 to 16)", bump.octaves)));
            }
        }
        if let Some(v) = &b.lacunarity {
            bump.lacunarity = source.in_range(v, "lacunarity", 1.0, 16.0)?;
        }
        if let Some(v) = &b.gain {
            bump.gain = source.in_range(v, "gain", 0.0, 1.0)?;
        }
        if let Some(d) = &b.derivative {
            bump.derivative = match d.get_ref().as_str() {
                "central" | "central-differences" => BumpDerivative::CentralDifferences,
                "analytic" => BumpDerivative::Analytic,
                other => {
                    return Err(source.error(d.span(), format!("unknown derivative \"{other}\" (central, analytic)")))
                }
            };
        }
        if let Some(v) = &b.epsilon {
            bump.epsilon = source.in_range(v, "epsilon", 1e-6, 0.5)?;
        }
        match &b.material {
            None => {
                if default.is_some() {
                    return Err(source.error(0..0, "more than one [[bump]] without a material (the default)"));
                }
                default = Some(bump);
            }
            Some(name) => {
                let index = scene.materials.iter().position(|m| &m.name == name.get_ref()).ok_or_else(|| {
                    source.error(
                        name.span(),
                        format!(
                            "no material is named \"{}\"; materials: {}",
                            name.get_ref(),
                            list(scene.materials.iter().map(|m| &m.name))
                        ),
                    )
                })?;
                if assigned[index] {
                    return Err(
                        source.error(name.span(), format!("material \"{}\" already has a [[bump]]", name.get_ref()))
                    );
                }
                assigned[index] = true;
                scene.materials[index].bump = Some(bump);
            }
        }
    }
    if let Some(bump) = default {
        for (m, done) in scene.materials.iter_mut().zip(&assigned) {
            if !done {
                m.bump = Some(bump);
            }
        }
    }
    Ok(())
}

/// `background`: a linear RGB colour `[r, g, b]`, or "environment" or "transparent".
fn background(source: &Source<'_>, b: &S<toml::Value>) -> Result<(Option<Vec3>, Option<Backdrop>)> {
    let wrong = || {
        source
            .error(b.span(), "background must be [r, g, b] (linear, not negative), \"environment\" or \"transparent\"")
    };
    match b.get_ref() {
        toml::Value::String(word) => match word.as_str() {
            "environment" => Ok((None, Some(Backdrop::Environment))),
            "transparent" => Ok((None, Some(Backdrop::Transparent))),
            _ => Err(wrong()),
        },
        toml::Value::Array(items) if items.len() == 3 => {
            let rgb: Vec<f64> = items
                .iter()
                .map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
                .collect::<Option<_>>()
                .ok_or_else(wrong)?;
            if rgb.iter().any(|x| !x.is_finite() || *x < 0.0) {
                return Err(wrong());
            }
            Ok((Some(Vec3::new(rgb[0] as f32, rgb[1] as f32, rgb[2] as f32)), Some(Backdrop::Colour)))
        }
        _ => Err(wrong()),
    }
}

/// The `[environment]` table: a file (relative to the scene file) or a builtin, turned and scaled.
fn environment(source: &Source<'_>, e: &EnvironmentSection) -> Result<Environment> {
    let dir = source.path.parent().unwrap_or(Path::new("."));
    let mut environment = match (&e.file, &e.builtin) {
        (Some(file), None) => {
            let path = dir.join(file.get_ref());
            Environment::load(&path).map_err(|err| source.error(file.span(), format!("{err:#}")))?
        }
        (None, Some(name)) => match name.get_ref().as_str() {
            "studio" => Environment::studio(512, 256),
            other => {
                return Err(
                    source.error(name.span(), format!("unknown builtin environment \"{other}\" (one of: studio)"))
                )
            }
        },
        _ => bail!("{}: [environment] needs one of file = \"...\" or builtin = \"studio\"", source.path.display()),
    };
    if let Some(r) = &e.rotation_degrees {
        environment.rotation_degrees = source.in_range(r, "rotation_degrees", -360.0, 360.0)?;
    }
    if let Some(i) = &e.intensity {
        environment.intensity = source.in_range(i, "intensity", 0.0, 1e9)?;
    }
    Ok(environment)
}

fn render_settings(source: &Source<'_>, r: &RenderSection, dir: &Path) -> Result<SettingsOverrides> {
    let sampler = r
        .sampler
        .as_ref()
        .map(|s| SamplerKind::parse(s.get_ref()).map_err(|e| source.error(s.span(), e)))
        .transpose()?;
    let tone_map =
        r.tone_map.as_ref().map(|s| ToneMap::parse(s.get_ref()).map_err(|e| source.error(s.span(), e))).transpose()?;
    let primary =
        r.primary.as_ref().map(|s| Primary::parse(s.get_ref()).map_err(|e| source.error(s.span(), e))).transpose()?;
    let trace =
        r.trace.as_ref().map(|s| Trace::parse(s.get_ref()).map_err(|e| source.error(s.span(), e))).transpose()?;
    let (background, backdrop) = match &r.background {
        Some(b) => background(source, b)?,
        None => (None, None),
    };
    Ok(SettingsOverrides {
        width: source.count_in_range(&r.width, "width", 1, MAX_IMAGE_SIDE)?,
        height: source.count_in_range(&r.height, "height", 1, MAX_IMAGE_SIDE)?,
        spp: source.count_in_range(&r.spp, "spp", 1, MAX_SPP)?,
        sampler,
        seed: r.seed,
        background,
        backdrop,
        exposure: r.exposure.as_ref().map(|e| source.in_range(e, "exposure", -64.0, 64.0)).transpose()?,
        tone_map,
        primary,
        indirect: r.indirect,
        bounces: source.count_in_range(&r.bounces, "bounces", 0, MAX_BOUNCES)?,
        shading_samples: source.count_in_range(&r.shading_samples, "shading_samples", 1, MAX_SHADING_SAMPLES)?,
        trace,
        output: r.output.as_ref().map(|o| dir.join(o)),
    })
}

/// `[[semantic]]` tables, in file order (a later table wins over an earlier one and over the glTF's extras): each
/// gives its category to every node whose name matches its pattern; a pattern that matches nothing is an error.
fn apply_semantics(source: &Source<'_>, tables: &[SemanticSection], scene: &mut Scene) -> Result<()> {
    for table in tables {
        let id = *table.category_id.get_ref();
        let Ok(id) = u32::try_from(id) else {
            return Err(source.error(table.category_id.span(), format!("category_id = {id} must be 0 to {}", u32::MAX)));
        };
        let pattern = table.nodes.get_ref();
        let mut matched = false;
        for node in scene.nodes.iter_mut().filter(|n| glob_matches(pattern, &n.name)) {
            node.category = Some(id);
            matched = true;
        }
        if !matched {
            let names = list(scene.nodes.iter().map(|n| &n.name));
            return Err(source.error(table.nodes.span(), format!("no node name matches \"{pattern}\"; nodes: {names}")));
        }
    }
    Ok(())
}

/// Whether `name` matches `pattern`, where `*` stands for any run of characters and `?` for one.
pub fn glob_matches(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    // The classic two-pointer match with one backtrack point for the last `*`.
    let (mut i, mut j, mut star, mut mark) = (0, 0, None, 0);
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if let Some(s) = star {
            i = s + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

#[cfg(test)]
mod tests {
    use super::glob_matches;

    #[test]
    fn glob_patterns_match_runs_and_single_characters() {
        for (pattern, name, matches) in [
            ("wheel*", "wheel_front_left", true),
            ("wheel*", "steering wheel", false),
            ("*wheel*", "steering wheel", true),
            ("r?ght", "right", true),
            ("r?ght", "rght", false),
            ("*", "", true),
            ("a*b*c", "aXXbYYc", true),
            ("a*b*c", "aXXbYY", false),
            ("exact", "exact", true),
            ("exact", "exactly", false),
        ] {
            assert_eq!(glob_matches(pattern, name), matches, "{pattern:?} against {name:?}");
        }
    }
}
