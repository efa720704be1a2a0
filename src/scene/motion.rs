//! Rigid motion over the shutter that glTF cannot say: a constant linear and angular velocity, for nodes
//! (in their parent's frame, the world for top-level nodes) and for the camera (in the world).
use glam::{Mat4, Quat, Vec3};

#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RigidMotion {
    /// Metres per second.
    pub velocity: Vec3,
    /// Radians per second about each axis (the rotation vector ω; |ω| is the angular speed).
    pub angular_velocity: Vec3,
}

impl RigidMotion {
    pub fn is_still(&self) -> bool {
        self.velocity == Vec3::ZERO && self.angular_velocity == Vec3::ZERO
    }

    /// The motion from time 0 to `t`, applied to a frame `m` (in the same parent space): spin about the frame's
    /// own origin by ω·t, then translate by v·t.
    pub fn apply(&self, m: Mat4, t: f32) -> Mat4 {
        if self.is_still() {
            return m;
        }
        let origin = m.w_axis.truncate();
        let spin = Quat::from_scaled_axis(self.angular_velocity * t);
        Mat4::from_translation(origin + self.velocity * t) * Mat4::from_quat(spin) * Mat4::from_translation(-origin) * m
    }
}

/// A node's extra motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeMotion {
    pub node: usize,
    pub motion: RigidMotion,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spin_is_about_the_frames_own_origin_and_translation_is_linear() {
        let m = Mat4::from_translation(Vec3::new(2.0, 0.0, 0.0));
        let motion = RigidMotion {
            velocity: Vec3::new(0.0, 1.0, 0.0),
            angular_velocity: Vec3::new(0.0, std::f32::consts::PI, 0.0),
        };
        let moved = motion.apply(m, 0.5);
        // Origin moves by v·t only.
        assert!((moved.w_axis.truncate() - Vec3::new(2.0, 0.5, 0.0)).length() < 1e-6);
        // A point 1 m along +X from the origin turns by 90° about +Y: to −Z.
        let p = moved.transform_point3(Vec3::X);
        assert!((p - Vec3::new(2.0, 0.5, -1.0)).length() < 1e-5, "{p}");
        assert_eq!(RigidMotion::default().apply(m, 3.0), m);
    }
}
