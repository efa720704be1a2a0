//! Cameras in glTF's convention (right-handed, +Y up, looking down −Z) and their Vulkan projections
//! (clip-space Y down, depth in [0, 1]).
use glam::{Mat4, Vec3, Vec4};

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// Vertical field of view in radians; no `zfar` means an infinite far plane (glTF 2.0 §3.10.2).
    Perspective { yfov: f32, znear: f32, zfar: Option<f32> },
    /// Half extents of the view volume (glTF's xmag/ymag).
    Orthographic { xmag: f32, ymag: f32, znear: f32, zfar: f32 },
}

/// A thin lens (docs/architecture.md, "Thin lens"): aperture radius A in metres and the distance f of the plane in focus.
/// A = 0 is the pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    pub aperture_radius: f32,
    pub focus_distance: f32,
}

impl Lens {
    pub const PINHOLE: Lens = Lens { aperture_radius: 0.0, focus_distance: 1.0 };

    /// Diameter of the circle of confusion on the focus plane for a point at depth `d`: 2A·|d − f| / d.
    pub fn circle_of_confusion(&self, depth: f32) -> f32 {
        2.0 * self.aperture_radius * (depth - self.focus_distance).abs() / depth
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub name: String,
    pub world_from_camera: Mat4,
    pub projection: Projection,
    pub lens: Lens,
}

/// Where a camera sits on an orbit around what it looks at: the azimuth θ about +Y, from +Z towards +X (θ = 0
/// looks along −Z, as a glTF camera does by default), the elevation φ above the horizontal plane, in degrees, and
/// the distance (None: far enough to frame the scene).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    pub theta_degrees: f32,
    pub phi_degrees: f32,
    pub distance: Option<f32>,
}

impl Orbit {
    /// The unit direction from the target to the camera.
    pub fn direction(&self) -> Vec3 {
        let (theta, phi) = (self.theta_degrees.to_radians(), self.phi_degrees.to_radians());
        Vec3::new(theta.sin() * phi.cos(), phi.sin(), theta.cos() * phi.cos())
    }
}

/// The vertical field of view of framing cameras.
pub const FRAMING_YFOV_DEGREES: f32 = 45.0;
/// How much farther than just touching the image's edges a framing camera stands (10%).
pub const FRAMING_MARGIN: f32 = 1.1;
/// The direction a default framing camera looks from: in front, a little to the right and above.
pub const FRAMING_DIRECTION: Vec3 = Vec3::new(0.35, 0.45, 1.0);

impl Camera {
    /// A perspective camera that frames the given bounds: looking at their centre along −Z, raised a little,
    /// far enough that the bounding sphere fits the vertical field of view (a square image's).
    pub fn framing(bounds: Option<(Vec3, Vec3)>) -> Self {
        Self::around(bounds, None, FRAMING_DIRECTION.normalize(), None, FRAMING_YFOV_DEGREES.to_radians(), 1.0)
    }

    /// A perspective camera with vertical field of view `yfov` (radians) looking at `target` (None: the centre of
    /// `bounds`) from the unit `direction`, at `distance` or, without one, far enough that the sphere about the
    /// target holding all of `bounds` fits both the vertical and the horizontal field of view of an image of
    /// `aspect` (width / height), with [`FRAMING_MARGIN`].
    pub fn around(
        bounds: Option<(Vec3, Vec3)>,
        target: Option<Vec3>,
        direction: Vec3,
        distance: Option<f32>,
        yfov: f32,
        aspect: f32,
    ) -> Self {
        let (lo, hi) = bounds.unwrap_or((Vec3::splat(-1.0), Vec3::splat(1.0)));
        let center = target.unwrap_or((lo + hi) * 0.5);
        // The farthest corner of the box from the target: the sphere holding all of it.
        let radius = (0..8)
            .map(|i| {
                let corner = Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                (corner - center).length()
            })
            .fold(0.0f32, f32::max)
            .max(1e-3);
        let xfov = 2.0 * ((yfov * 0.5).tan() * aspect.max(1e-3)).atan();
        let half = 0.5 * yfov.min(xfov);
        let distance = distance.unwrap_or(radius / half.sin() * FRAMING_MARGIN);
        let eye = center + direction * distance;
        let up = if direction.cross(Vec3::Y).length() > 1e-4 { Vec3::Y } else { Vec3::NEG_Z };
        Self {
            name: "framing camera".into(),
            world_from_camera: look_at(eye, center, up),
            projection: Projection::Perspective {
                yfov,
                znear: (distance - radius).max(distance * 1e-3),
                zfar: Some(distance + radius * 2.0),
            },
            lens: Lens::PINHOLE,
        }
    }

    pub fn view_from_world(&self) -> Mat4 {
        self.world_from_camera.inverse()
    }

    /// Vulkan clip-from-view for an image of the given aspect (width / height): clip Y points down (the view's
    /// Y up), depth maps to [0, 1] with the near plane at 0.
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective { yfov, znear, zfar } => perspective(yfov, aspect, znear, zfar),
            Projection::Orthographic { ymag, znear, zfar, .. } => {
                // Keep the vertical extent; the horizontal one follows the image's aspect.
                orthographic(ymag * aspect, ymag, znear, zfar)
            }
        }
    }
}

/// The camera-to-world transform of a camera at `eye` looking at `target` (its −Z towards the target).
pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let forward = (target - eye).normalize();
    let right = forward.cross(up).normalize();
    let true_up = right.cross(forward);
    Mat4::from_cols(right.extend(0.0), true_up.extend(0.0), (-forward).extend(0.0), eye.extend(1.0))
}

/// Perspective projection for a view looking down −Z; `zfar = None` is the infinite-far limit.
/// x_c = f/a·x, y_c = −f·y, w_c = −z, depth = 0 at z = −near and 1 at z = −far, f = 1/tan(yfov/2).
pub fn perspective(yfov: f32, aspect: f32, znear: f32, zfar: Option<f32>) -> Mat4 {
    let f = 1.0 / (yfov * 0.5).tan();
    let (a, b) = match zfar {
        Some(zfar) => (zfar / (znear - zfar), znear * zfar / (znear - zfar)),
        None => (-1.0, -znear),
    };
    Mat4::from_cols(
        Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -f, 0.0, 0.0),
        Vec4::new(0.0, 0.0, a, -1.0),
        Vec4::new(0.0, 0.0, b, 0.0),
    )
}

/// Orthographic projection of the box |x| ≤ half_width, |y| ≤ half_height, −far ≤ z ≤ −near.
pub fn orthographic(half_width: f32, half_height: f32, znear: f32, zfar: f32) -> Mat4 {
    let depth = 1.0 / (zfar - znear);
    Mat4::from_cols(
        Vec4::new(1.0 / half_width, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -1.0 / half_height, 0.0, 0.0),
        Vec4::new(0.0, 0.0, -depth, 0.0),
        Vec4::new(0.0, 0.0, -znear * depth, 1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ndc(m: Mat4, p: Vec3) -> Vec3 {
        let c = m * p.extend(1.0);
        c.truncate() / c.w
    }

    #[test]
    fn perspective_maps_near_and_far_to_vulkan_depth() {
        let m = perspective(90f32.to_radians(), 2.0, 0.5, Some(10.0));
        assert!((ndc(m, Vec3::new(0.0, 0.0, -0.5)).z - 0.0).abs() < 1e-6);
        assert!((ndc(m, Vec3::new(0.0, 0.0, -10.0)).z - 1.0).abs() < 1e-6);
        // 90° vertical fov: y = −z lands on the top edge, which is −1 in Vulkan clip space (Y down).
        assert!((ndc(m, Vec3::new(0.0, 2.0, -2.0)).y + 1.0).abs() < 1e-6);
        // aspect 2: x = 2·(−z) lands on the right edge.
        assert!((ndc(m, Vec3::new(4.0, 0.0, -2.0)).x - 1.0).abs() < 1e-6);
        let inf = perspective(90f32.to_radians(), 1.0, 0.5, None);
        assert!(ndc(inf, Vec3::new(0.0, 0.0, -0.5)).z.abs() < 1e-6);
        assert!((ndc(inf, Vec3::new(0.0, 0.0, -1e6)).z - 1.0).abs() < 1e-5);
    }

    #[test]
    fn orthographic_maps_the_box_to_the_unit_volume() {
        let m = orthographic(2.0, 1.0, 1.0, 3.0);
        assert!((ndc(m, Vec3::new(2.0, 1.0, -1.0)) - Vec3::new(1.0, -1.0, 0.0)).length() < 1e-6);
        assert!((ndc(m, Vec3::new(-2.0, -1.0, -3.0)) - Vec3::new(-1.0, 1.0, 1.0)).length() < 1e-6);
    }

    #[test]
    fn look_at_points_minus_z_at_the_target() {
        let m = look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y);
        let forward = m.transform_vector3(-Vec3::Z);
        assert!((forward - (-Vec3::new(1.0, 2.0, 3.0)).normalize()).length() < 1e-6);
        assert!((m.inverse().transform_point3(Vec3::ZERO).z + 14f32.sqrt()).abs() < 1e-5);
    }
}

/// What a frame's camera was, for whoever reads the frame as data (`strata render --camera-json`): the image
/// size, the pinhole intrinsics and the pose, in the terms dataset tools use.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraMetadata {
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    /// The frame's time in seconds (the shutter's opening).
    pub time: f32,
    /// The exposure the display image was made with, in stops.
    pub exposure: f32,
}

impl CameraMetadata {
    /// The intrinsics matrix K (pixels; OpenCV's convention: x right, y down, z forward, pixel centres at +½) of a
    /// perspective camera: u = fx·x/z + cx. strata keeps the vertical field of view and fits the horizontal one to
    /// the image, so pixels are square. None for an orthographic camera.
    pub fn intrinsics(&self) -> Option<[[f32; 3]; 3]> {
        let Projection::Perspective { yfov, .. } = self.camera.projection else { return None };
        let f = 0.5 * self.height as f32 / (0.5 * yfov).tan();
        let (cx, cy) = (0.5 * self.width as f32, 0.5 * self.height as f32);
        Some([[f, 0.0, cx], [0.0, f, cy], [0.0, 0.0, 1.0]])
    }

    /// The camera as JSON: `width`, `height`, `K` (rows; null when orthographic), `yfov` (radians, as glTF
    /// has it) or `xmag`/`ymag`, `world_from_camera` (4x4 rows, glTF's camera axes: +X right, +Y up, looking
    /// down −Z), `camera_from_world_opencv` (the same pose for K: +Y down, +Z forward), `near`, `far` (null:
    /// infinite), `time`, `exposure`, `aperture_radius` and `focus_distance`.
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        let rows = |m: Mat4| (0..4).map(|r| m.row(r).to_array()).collect::<Vec<_>>();
        let opencv_from_gltf = Mat4::from_diagonal(Vec4::new(1.0, -1.0, -1.0, 1.0));
        let mut value = json!({
            "width": self.width,
            "height": self.height,
            "K": self.intrinsics(),
            "world_from_camera": rows(self.camera.world_from_camera),
            "camera_from_world_opencv": rows(opencv_from_gltf * self.camera.world_from_camera.inverse()),
            "time": self.time,
            "exposure": self.exposure,
            "aperture_radius": self.camera.lens.aperture_radius,
            "focus_distance": self.camera.lens.focus_distance,
        });
        match self.camera.projection {
            Projection::Perspective { yfov, znear, zfar } => {
                value["projection"] = json!("perspective");
                value["yfov"] = json!(yfov);
                value["near"] = json!(znear);
                value["far"] = json!(zfar);
            }
            Projection::Orthographic { xmag, ymag, znear, zfar } => {
                // The image keeps ymag; its horizontal extent follows its aspect (clip_from_view).
                value["projection"] = json!("orthographic");
                value["xmag"] = json!(ymag * self.width as f32 / self.height as f32);
                value["ymag"] = json!(ymag);
                value["glTF_xmag"] = json!(xmag);
                value["near"] = json!(znear);
                value["far"] = json!(zfar);
            }
        }
        value
    }
}
