//! Where a frame's camera comes from: the scene's own, or one strata places around the scene's bounds (an orbit,
//! a target, a turntable, or a scene without a camera). Shared by `strata render` and the library's renderer, so
//! the same options frame the same picture.
use super::camera::{Orbit, FRAMING_DIRECTION, FRAMING_YFOV_DEGREES};
use super::{Camera, Projection, Scene};
use anyhow::{bail, Result};
use glam::Vec3;

/// How the caller asks to see the scene.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct View {
    /// Orbit the target: azimuth, elevation and distance (None: the scene's camera, or the default framing).
    pub orbit: Option<Orbit>,
    /// The point the camera looks at (None: the centre of the scene's bounds).
    pub target: Option<Vec3>,
    /// Vertical field of view in degrees, of a placed camera or the scene's perspective one.
    pub yfov_degrees: Option<f32>,
    /// A turntable's views turn an orbit, so strata places the camera even without `orbit` or `target`.
    pub turntable: bool,
}

/// The elevation of a turntable, or of a target alone, in degrees.
pub const DEFAULT_ELEVATION: f32 = 20.0;

/// The camera placement a [`View`] asks for, fitted to a scene's bounds and an image's shape.
#[derive(Debug, Clone)]
pub struct Framing {
    /// Whether strata places the camera.
    places: bool,
    /// An explicit orbit (given, or a turntable's): its azimuth turns per view.
    orbit: Option<Orbit>,
    /// Otherwise the default framing direction.
    direction: Vec3,
    target: Option<Vec3>,
    /// Vertical field of view, radians.
    yfov: f32,
    /// Degrees for the scene's own perspective camera, when strata does not place one.
    own_yfov_degrees: Option<f32>,
    bounds: Option<(Vec3, Vec3)>,
    aspect: f32,
}

impl Framing {
    /// The framing of `view` for `scene` in an image of width/height `aspect`. A field of view for a scene's
    /// orthographic camera is an error.
    pub fn of(view: &View, scene: &Scene, aspect: f32) -> Result<Self> {
        if let Some(d) = view.yfov_degrees {
            if !d.is_finite() || d <= 0.0 || d >= 180.0 {
                bail!("field of view {d} must be between 0 and 180 degrees");
            }
        }
        let explicit = view.orbit.is_some() || view.target.is_some() || view.turntable;
        let places = explicit || scene.camera.is_none();
        if !places && view.yfov_degrees.is_some() {
            if let Some(camera) = &scene.camera {
                if !matches!(camera.projection, Projection::Perspective { .. }) {
                    bail!("a field of view needs a perspective camera; this scene's camera is orthographic");
                }
            }
        }
        let yfov = view.yfov_degrees.unwrap_or(FRAMING_YFOV_DEGREES).to_radians();
        let orbit = explicit.then(|| {
            view.orbit.unwrap_or(Orbit { theta_degrees: 0.0, phi_degrees: DEFAULT_ELEVATION, distance: None })
        });
        Ok(Self {
            places,
            orbit,
            direction: FRAMING_DIRECTION.normalize(),
            target: view.target,
            yfov,
            own_yfov_degrees: if places { None } else { view.yfov_degrees },
            bounds: scene.bounds(),
            aspect,
        })
    }

    /// The camera of a frame (turned to azimuth `theta` for a turntable's view); None: keep the scene's.
    pub fn camera(&self, theta: Option<f32>) -> Option<Camera> {
        if !self.places {
            return None;
        }
        let (direction, distance) = match self.orbit {
            Some(o) => (Orbit { theta_degrees: theta.unwrap_or(o.theta_degrees), ..o }.direction(), o.distance),
            None => (self.direction, None),
        };
        Some(Camera::around(self.bounds, self.target, direction, distance, self.yfov, self.aspect))
    }

    /// Puts the first frame's camera into `scene`: a placed one, or the scene's own with the asked field of view.
    pub fn apply(&self, scene: &mut Scene) {
        match self.camera(None) {
            Some(camera) => scene.camera = Some(camera),
            None => {
                if let (Some(d), Some(camera)) = (self.own_yfov_degrees, scene.camera.as_mut()) {
                    if let Projection::Perspective { yfov, .. } = &mut camera.projection {
                        *yfov = d.to_radians();
                    }
                }
            }
        }
    }
}

/// The shutter of the animation frame at time `t`: open at t for `shutter_angle`/360 of a frame at `fps`.
pub fn frame_shutter(t: f32, fps: f32, shutter_angle: f32) -> (f32, f32) {
    (t, t + shutter_angle / 360.0 / fps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_without_a_camera_is_framed_and_one_with_a_camera_keeps_it() {
        let mut scene = Scene::default();
        let framing = Framing::of(&View::default(), &scene, 1.0).unwrap();
        assert!(framing.camera(None).is_some());
        scene.camera = Some(Camera::framing(None));
        let framing = Framing::of(&View { yfov_degrees: Some(30.0), ..View::default() }, &scene, 1.0).unwrap();
        assert!(framing.camera(None).is_none());
        framing.apply(&mut scene);
        let Projection::Perspective { yfov, .. } = scene.camera.as_ref().unwrap().projection else { panic!() };
        assert!((yfov - 30f32.to_radians()).abs() < 1e-6);
    }

    #[test]
    fn an_absurd_field_of_view_is_refused() {
        let error = Framing::of(&View { yfov_degrees: Some(190.0), ..View::default() }, &Scene::default(), 1.0);
        assert!(error.unwrap_err().to_string().contains("between 0 and 180"));
    }
}
