//! Render settings: what the scene file's `[render]` table and the command line set. Defaults live here, once.
use anyhow::{bail, Result};
use glam::Vec3;
use std::path::PathBuf;

/// How sample points are placed (Cook, Porter and Carpenter 1984 and after).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SamplerKind {
    /// Strata centres: aliases on regular patterns.
    Regular,
    /// Independent uniform points.
    Random,
    /// n×n strata, one random point in each (Cook's jitter).
    Jittered,
    /// Correlated multi-jittered sampling (Kensler 2013).
    MultiJittered,
    /// Shuffled, Owen-scrambled Sobol points (Burley 2020).
    Sobol,
}

impl SamplerKind {
    pub const NAMES: [&'static str; 5] = ["regular", "random", "jittered", "multi-jittered", "sobol"];

    /// The name `parse` reads.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "regular" => Self::Regular,
            "random" => Self::Random,
            "jittered" => Self::Jittered,
            "multi-jittered" => Self::MultiJittered,
            "sobol" => Self::Sobol,
            other => bail!("unknown sampler \"{other}\" (one of: {})", Self::NAMES.join(", ")),
        })
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToneMap {
    /// Clamp to [0, 1].
    Clamp,
    /// A filmic curve (ACES fit, Narkowicz 2015).
    Filmic,
}

impl ToneMap {
    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "none" | "clamp" => Self::Clamp,
            "filmic" => Self::Filmic,
            other => bail!("unknown tone map \"{other}\" (one of: clamp, filmic)"),
        })
    }
}

/// Where each sample's visible surface comes from (docs/architecture.md, "One frame").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Primary {
    /// The raster G-buffer pass: fast, but within one sample every pixel shares the pixel jitter and lens point.
    Raster,
    /// A ray query per pixel (the reference mode): each pixel draws its own jitter and lens point, so regular
    /// patterns turn into noise instead of moiré. The shutter time stays shared (one TLAS per sample time).
    Rays,
}

impl Primary {
    pub const NAMES: [&'static str; 2] = ["raster", "rays"];

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "raster" => Self::Raster,
            "rays" => Self::Rays,
            other => bail!("unknown primary visibility \"{other}\" (one of: {})", Self::NAMES.join(", ")),
        })
    }
}

/// How the accumulation pass traces its rays. Both ways run the same shading code (shaders/include/path_tracer.glsl)
/// and, on lavapipe, give the same bits; what differs is which devices have them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Trace {
    /// Ray queries where the device has them, else a ray-tracing pipeline.
    #[default]
    Auto,
    /// Ray queries (`VK_KHR_ray_query`) in a compute shader.
    Query,
    /// A ray-tracing pipeline (`VK_KHR_ray_tracing_pipeline`): what NVIDIA's data-centre GPUs (H100, H200) have.
    Pipeline,
}

impl Trace {
    pub const NAMES: [&'static str; 3] = ["auto", "query", "pipeline"];

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    pub fn parse(name: &str) -> Result<Self> {
        Ok(match name {
            "auto" => Self::Auto,
            "query" => Self::Query,
            "pipeline" => Self::Pipeline,
            other => bail!("unknown way to trace \"{other}\" (one of: {})", Self::NAMES.join(", ")),
        })
    }
}

/// What pixels no surface covers show.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backdrop {
    /// The background colour (`RenderSettings::background`).
    Colour,
    /// The scene's environment, as escaping rays see it.
    Environment,
    /// Nothing: alpha 0 (PNG and EXR keep coverage in alpha); the scene is still lit as before.
    Transparent,
}

impl Backdrop {
    /// The value the accumulation pass reads (`BACKGROUND_*` in shared_constants.glsl).
    pub fn code(self) -> u32 {
        use crate::shaders::constants::{BACKGROUND_COLOUR, BACKGROUND_ENVIRONMENT, BACKGROUND_TRANSPARENT};
        match self {
            Backdrop::Colour => BACKGROUND_COLOUR,
            Backdrop::Environment => BACKGROUND_ENVIRONMENT,
            Backdrop::Transparent => BACKGROUND_TRANSPARENT,
        }
    }
}

/// Largest image side strata accepts before asking the device (which may allow less).
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Largest samples-per-pixel count accepted: more is a typo, not a render.
pub const MAX_SPP: u32 = 65536;
/// The largest exposure, in stops either way (2^64: far past any picture; beyond it the PNG is all black or all
/// white).
pub const MAX_EXPOSURE_STOPS: f32 = 64.0;
/// Most bounces a path may take after the visible surface (each costs a ray and a shadow ray per pixel).
pub const MAX_BOUNCES: u32 = 16;
/// Most paths one camera sample may trace from its visible surface (`RenderSettings::shading_samples`).
pub const MAX_SHADING_SAMPLES: u32 = 256;

#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub sampler: SamplerKind,
    pub seed: u64,
    /// Linear RGB seen where rays escape (without an environment).
    pub background: Vec3,
    /// What pixels no surface covers show; None: the environment when the scene has one, else the colour.
    pub backdrop: Option<Backdrop>,
    /// Exposure in stops: radiance is scaled by 2^exposure before tone mapping.
    pub exposure: f32,
    /// Choose the exposure from the picture instead: its log-average luminance to middle grey (`exposure` is then
    /// ignored; the frame reports what it used).
    pub auto_exposure: bool,
    pub tone_map: ToneMap,
    pub primary: Primary,
    /// Paths also go on by the diffuse lobe: diffuse interreflection (Kajiya 1986) on top of Cook's effects.
    pub indirect: bool,
    /// Most bounces after the visible surface: gloss and translucency rays (and diffuse ones with `indirect`).
    /// 0 is direct light alone; the default 3 sees through a glass sphere (in, out, and what lies behind).
    pub bounces: u32,
    /// Paths traced from each camera sample's visible surface, each with its own light, BSDF and bounce samples
    /// (stratified over `spp × shading_samples`); the pixel jitter, lens point and shutter time stay one per
    /// camera sample. 1 is Cook's distribution, every sample a G-buffer pass of its own; more pays where the noise
    /// is in the lighting, not in edges, defocus or motion (docs/performance.md).
    pub shading_samples: u32,
    /// How rays are traced (ray queries or a ray-tracing pipeline); the picture does not depend on it.
    pub trace: Trace,
    /// Default output path (the command line's `-o` wins).
    pub output: Option<PathBuf>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 960,
            height: 540,
            spp: 16,
            sampler: SamplerKind::MultiJittered,
            seed: 0,
            background: Vec3::new(0.02, 0.02, 0.025),
            backdrop: None,
            exposure: 0.0,
            auto_exposure: false,
            tone_map: ToneMap::Filmic,
            primary: Primary::Raster,
            indirect: false,
            bounces: 3,
            shading_samples: 1,
            trace: Trace::Auto,
            output: None,
        }
    }
}

/// Settings some source gives; unset fields leave the layer below alone.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SettingsOverrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub sampler: Option<SamplerKind>,
    pub seed: Option<u64>,
    pub background: Option<Vec3>,
    pub backdrop: Option<Backdrop>,
    pub exposure: Option<f32>,
    pub tone_map: Option<ToneMap>,
    pub primary: Option<Primary>,
    pub indirect: Option<bool>,
    pub bounces: Option<u32>,
    pub shading_samples: Option<u32>,
    pub trace: Option<Trace>,
    pub output: Option<PathBuf>,
}

impl RenderSettings {
    /// What pixels no surface covers show, for a scene with or without an environment.
    pub fn backdrop_for(&self, has_environment: bool) -> Backdrop {
        self.backdrop.unwrap_or(if has_environment { Backdrop::Environment } else { Backdrop::Colour })
    }

    /// Checks every setting against its range (the command line's and the scene file's parsers check the same
    /// bounds; a program's settings come here).
    pub fn check(&self) -> Result<()> {
        for (side, name) in [(self.width, "width"), (self.height, "height")] {
            if side == 0 || side > MAX_IMAGE_SIDE {
                bail!("{name} {side} is outside 1..={MAX_IMAGE_SIDE} pixels");
            }
        }
        if self.spp == 0 || self.spp > MAX_SPP {
            bail!("spp {} is outside 1..={MAX_SPP}", self.spp);
        }
        if self.bounces > MAX_BOUNCES {
            bail!("bounces {} is above the most, {MAX_BOUNCES}", self.bounces);
        }
        if self.shading_samples == 0 || self.shading_samples > MAX_SHADING_SAMPLES {
            bail!("shading samples {} is outside 1..={MAX_SHADING_SAMPLES}", self.shading_samples);
        }
        if !self.exposure.is_finite() || self.exposure.abs() > MAX_EXPOSURE_STOPS {
            bail!("exposure {} stops is outside ±{MAX_EXPOSURE_STOPS}", self.exposure);
        }
        if !self.background.is_finite() || self.background.min_element() < 0.0 {
            bail!("background {} must be finite and not negative", self.background);
        }
        Ok(())
    }

    /// These settings with `overrides` applied on top.
    pub fn with(mut self, overrides: &SettingsOverrides) -> Self {
        let o = overrides.clone();
        self.width = o.width.unwrap_or(self.width);
        self.height = o.height.unwrap_or(self.height);
        self.spp = o.spp.unwrap_or(self.spp);
        self.sampler = o.sampler.unwrap_or(self.sampler);
        self.seed = o.seed.unwrap_or(self.seed);
        self.background = o.background.unwrap_or(self.background);
        self.backdrop = o.backdrop.or(self.backdrop);
        self.exposure = o.exposure.unwrap_or(self.exposure);
        self.tone_map = o.tone_map.unwrap_or(self.tone_map);
        self.primary = o.primary.unwrap_or(self.primary);
        self.indirect = o.indirect.unwrap_or(self.indirect);
        self.bounces = o.bounces.unwrap_or(self.bounces);
        self.shading_samples = o.shading_samples.unwrap_or(self.shading_samples);
        self.trace = o.trace.unwrap_or(self.trace);
        self.output = o.output.or(self.output);
        self
    }
}

/// Lens and shutter settings from the command line, applied to the scene's camera on top of the scene file.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CameraOverrides {
    /// Thin-lens aperture radius in metres (0: pinhole).
    pub aperture_radius: Option<f32>,
    /// Distance of the plane in focus, in metres.
    pub focus_distance: Option<f32>,
    /// Shutter open and close times in seconds.
    pub shutter: Option<(f32, f32)>,
}

impl CameraOverrides {
    pub fn apply(&self, scene: &mut super::Scene) -> Result<()> {
        if let Some(a) = self.aperture_radius {
            if !a.is_finite() || a < 0.0 {
                bail!("aperture radius {a} must be a finite number of metres, 0 or more");
            }
        }
        if let Some(f) = self.focus_distance {
            if !f.is_finite() || f <= 0.0 {
                bail!("focus distance {f} must be a positive number of metres");
            }
        }
        if let Some((open, close)) = self.shutter {
            if !open.is_finite() || !close.is_finite() || close < open {
                bail!("shutter {open}:{close} must be two finite times with open <= close");
            }
            scene.shutter = (open, close);
        }
        if self.aperture_radius.is_some() || self.focus_distance.is_some() {
            let mut camera = scene.camera_or_default();
            if let Some(a) = self.aperture_radius {
                camera.lens.aperture_radius = a;
            }
            if let Some(f) = self.focus_distance {
                camera.lens.focus_distance = f;
            }
            if camera.lens.aperture_radius > 0.0 && !matches!(camera.projection, super::Projection::Perspective { .. })
            {
                bail!("a lens aperture needs a perspective camera; this scene's camera is orthographic");
            }
            scene.camera = Some(camera);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_sampler_name_parses_to_the_kind_that_bears_it() {
        for name in SamplerKind::NAMES {
            assert_eq!(SamplerKind::parse(name).unwrap().name(), name);
        }
        assert!(SamplerKind::parse("halton").unwrap_err().to_string().contains("sobol"));
    }
}
