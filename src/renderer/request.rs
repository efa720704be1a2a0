//! What one render asks for and what it returns.
use super::InputError;
use crate::output::Frame;
use crate::render::aov::Aov;
use crate::scene::camera::CameraMetadata;
use crate::scene::framing::View;
use crate::scene::settings::{CameraOverrides, RenderSettings, SettingsOverrides};
use anyhow::Result;
use std::path::PathBuf;

/// One render's options. The settings lie over strata's defaults and the scene file's `[render]` table, as the
/// command line's do; everything else changes the scene for this render only.
#[derive(Debug, Clone)]
pub struct RenderRequest {
    pub settings: SettingsOverrides,
    /// Choose the exposure from the picture (its log-average luminance to middle grey).
    pub auto_exposure: bool,
    /// Where the camera is (the scene's, or one strata places).
    pub view: View,
    /// The lens (aperture, focus) and an explicit shutter.
    pub lens: CameraOverrides,
    /// The frame's time in seconds: the shutter opens then for `shutter_angle`/360 of a frame at `fps`.
    pub time: Option<f32>,
    /// Frames per second: how far ahead the motion AOV looks (1/fps), and the shutter's length with `time`.
    pub fps: f32,
    /// Degrees of a frame the shutter stays open with `time` (180: half a frame).
    pub shutter_angle: f32,
    /// An environment (`studio`, or an image file) in place of the scene's.
    pub environment: Option<PathBuf>,
    /// Degrees the environment turns about +Y, and its intensity, in place of the scene's.
    pub environment_rotation: Option<f32>,
    pub environment_intensity: Option<f32>,
    /// Extra outputs made from a pinhole G-buffer pass through the pixel centres.
    pub aovs: Vec<Aov>,
    /// Denoise the colour with Open Image Denoise, guided by albedo and normal (the noisy colour is kept).
    pub denoise: bool,
}

impl Default for RenderRequest {
    fn default() -> Self {
        Self {
            settings: SettingsOverrides::default(),
            auto_exposure: false,
            view: View::default(),
            lens: CameraOverrides::default(),
            time: None,
            fps: 24.0,
            shutter_angle: 180.0,
            environment: None,
            environment_rotation: None,
            environment_intensity: None,
            aovs: Vec::new(),
            denoise: false,
        }
    }
}

impl RenderRequest {
    /// The settings this request renders with over `file` (a scene file's), checked.
    pub fn settings_over(&self, file: &SettingsOverrides) -> Result<RenderSettings> {
        let mut settings = RenderSettings::default().with(file).with(&self.settings);
        settings.auto_exposure = self.auto_exposure;
        settings.check().map_err(InputError::from)?;
        if !self.fps.is_finite() || self.fps <= 0.0 || self.fps > 1000.0 {
            return Err(InputError::new(format!("fps {} must be above 0 and at most 1000", self.fps)).into());
        }
        if !self.shutter_angle.is_finite() || !(0.0..=360.0).contains(&self.shutter_angle) {
            return Err(
                InputError::new(format!("shutter angle {} must be 0 to 360 degrees", self.shutter_angle)).into()
            );
        }
        if let Some(t) = self.time {
            if !t.is_finite() || t.abs() > 1e9 {
                return Err(InputError::new(format!("time {t} must be a finite number of seconds")).into());
            }
        }
        Ok(settings)
    }
}

/// A finished render.
#[derive(Debug)]
pub struct Rendered {
    /// Linear RGBA radiance (denoised when asked), alpha the coverage.
    pub color: Frame,
    /// The display image as the PNG holds it: RGBA8, exposed and tone mapped.
    pub display: Vec<u8>,
    /// The colour before denoising, when denoised.
    pub noisy: Option<Frame>,
    /// Each AOV asked for, raw (docs/outputs.md).
    pub aovs: Vec<(Aov, Frame)>,
    /// The camera the frame was rendered with.
    pub camera: CameraMetadata,
    /// The settings it was rendered with.
    pub settings: RenderSettings,
    pub stats: crate::render::frame::FrameStats,
    /// What a user should hear about (a default light added, ...).
    pub warnings: Vec<String>,
}
