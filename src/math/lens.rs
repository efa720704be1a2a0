//! The thin-lens camera for raster (docs/architecture.md, "Thin lens"): the eye moves to the lens point l on the aperture
//! disk and the frustum is sheared so the plane at the focus distance f keeps its place on the image. A point at
//! depth d then shifts on the image by l·(1/d − 1/f)·(focal length in pixels): its circle of confusion.
//! Sub-pixel jitter shifts the whole image by a fraction of a pixel.
use crate::scene::camera::{perspective, Lens};
use crate::scene::{Camera, Projection};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// One camera sample's matrices: `clip_from_world = clip_from_view · view_from_world`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraSample {
    pub view_from_world: Mat4,
    pub clip_from_view: Mat4,
    /// The eye (lens point) in world space.
    pub eye: Vec3,
}

impl CameraSample {
    pub fn clip_from_world(&self) -> Mat4 {
        self.clip_from_view * self.view_from_world
    }
}

/// Concentric mapping of the unit square onto the unit disk (Shirley and Chiu 1997): keeps strata compact.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let a = u * 2.0 - Vec2::ONE;
    if a == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, theta) = if a.x.abs() > a.y.abs() {
        (a.x, std::f32::consts::FRAC_PI_4 * (a.y / a.x))
    } else {
        (a.y, std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a.x / a.y))
    };
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// The matrices for lens point `lens_uv` (in `[0,1]²`, mapped to the aperture disk) and sub-pixel `jitter` (in
/// pixels, e.g. in [−½, ½]²), for an image of `width` × `height`. Aperture 0 and zero jitter give exactly the
/// camera's own projection.
pub fn camera_sample(camera: &Camera, width: u32, height: u32, lens_uv: Vec2, jitter: Vec2) -> CameraSample {
    let aspect = width as f32 / height as f32;
    let view_from_world = camera.view_from_world();
    let lens: Lens = camera.lens;
    let offset = if lens.aperture_radius > 0.0 { concentric_disk(lens_uv) * lens.aperture_radius } else { Vec2::ZERO };
    // Jitter in NDC: one pixel is 2/width wide.
    let delta = Vec2::new(2.0 * jitter.x / width as f32, 2.0 * jitter.y / height as f32);
    let mut clip_from_view = camera.clip_from_view(aspect);
    if offset == Vec2::ZERO && delta == Vec2::ZERO {
        return CameraSample { view_from_world, clip_from_view, eye: camera.world_from_camera.w_axis.truncate() };
    }
    match camera.projection {
        Projection::Perspective { yfov, znear, zfar } => {
            // x_c = x/(t·a) − (lx/W)·z − δx·z, y_c = −y/t + (ly/H)·z − δy·z with W = f·t·a, H = f·t, w_c = −z.
            let t = (yfov * 0.5).tan();
            let (w_half, h_half) = (lens.focus_distance * t * aspect, lens.focus_distance * t);
            clip_from_view = perspective(yfov, aspect, znear, zfar);
            clip_from_view.z_axis += Vec4::new(-offset.x / w_half - delta.x, offset.y / h_half - delta.y, 0.0, 0.0);
        }
        Projection::Orthographic { .. } => {
            // An orthographic camera has no lens; jitter is a plain shift of the image.
            clip_from_view = Mat4::from_translation(delta.extend(0.0)) * clip_from_view;
            return CameraSample { view_from_world, clip_from_view, eye: camera.world_from_camera.w_axis.truncate() };
        }
    }
    let shifted = Mat4::from_translation(-offset.extend(0.0)) * view_from_world;
    let eye = camera.world_from_camera.transform_point3(offset.extend(0.0));
    CameraSample { view_from_world: shifted, clip_from_view, eye }
}

/// Pixel coordinates (x right, y down, pixel centres at +½) of a world point under `sample`.
pub fn project_to_pixel(sample: &CameraSample, world: Vec3, width: u32, height: u32) -> Vec2 {
    let clip = sample.clip_from_world() * world.extend(1.0);
    let ndc = Vec2::new(clip.x, clip.y) / clip.w;
    (ndc + Vec2::ONE) * 0.5 * Vec2::new(width as f32, height as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::look_at;

    fn camera(aperture: f32, focus: f32) -> Camera {
        Camera {
            name: "test".into(),
            world_from_camera: look_at(Vec3::new(0.3, 1.0, 4.0), Vec3::new(0.0, 0.5, 0.0), Vec3::Y),
            projection: Projection::Perspective { yfov: 0.7, znear: 0.1, zfar: Some(50.0) },
            lens: Lens { aperture_radius: aperture, focus_distance: focus },
        }
    }

    #[test]
    fn pinhole_without_jitter_is_exactly_the_camera_projection() {
        let c = camera(0.0, 3.0);
        let s = camera_sample(&c, 640, 480, Vec2::new(0.9, 0.1), Vec2::ZERO);
        assert_eq!(s.clip_from_view, c.clip_from_view(640.0 / 480.0));
        assert_eq!(s.view_from_world, c.view_from_world());
    }

    #[test]
    fn focus_plane_points_stay_put_and_others_move_by_the_circle_of_confusion() {
        let (w, h, f) = (640u32, 480u32, 3.0f32);
        let c = camera(0.1, f);
        let pinhole = camera_sample(&c, w, h, Vec2::splat(0.5), Vec2::ZERO);
        // The lens point at the disk's +x rim: (1, ½) maps to (A, 0).
        let shifted = camera_sample(&c, w, h, Vec2::new(1.0, 0.5), Vec2::ZERO);
        assert!((shifted.eye - c.world_from_camera.transform_point3(Vec3::new(0.1, 0.0, 0.0))).length() < 1e-6);
        let focal_px = h as f32 * 0.5 / (0.35f32).tan();
        for (x, y) in [(0.0, 0.0), (0.5, -0.3), (-1.0, 0.4)] {
            let on_plane = c.world_from_camera.transform_point3(Vec3::new(x, y, -f));
            let a = project_to_pixel(&pinhole, on_plane, w, h);
            let b = project_to_pixel(&shifted, on_plane, w, h);
            assert!((a - b).length() < 1e-3, "focus-plane point moved {} px", (a - b).length());
            // A point at depth d moves by A·(1/d − 1/f)·focal_px, opposite to the lens offset when nearer.
            let d = 1.5;
            let near = c.world_from_camera.transform_point3(Vec3::new(x * d / f, y * d / f, -d));
            let moved = project_to_pixel(&shifted, near, w, h) - project_to_pixel(&pinhole, near, w, h);
            let predicted = -0.1 * (1.0 / d - 1.0 / f) * focal_px;
            assert!((moved.x - predicted).abs() < 1e-2 && moved.y.abs() < 1e-2, "moved {moved}, predicted {predicted}");
        }
    }

    #[test]
    fn jitter_shifts_the_image_by_that_many_pixels() {
        let c = camera(0.0, 3.0);
        let base = camera_sample(&c, 200, 100, Vec2::ZERO, Vec2::ZERO);
        let jittered = camera_sample(&c, 200, 100, Vec2::ZERO, Vec2::new(0.25, -0.5));
        let p = Vec3::new(0.2, 0.7, 0.1);
        let d = project_to_pixel(&jittered, p, 200, 100) - project_to_pixel(&base, p, 200, 100);
        assert!((d - Vec2::new(0.25, -0.5)).length() < 1e-4, "{d}");
    }

    #[test]
    fn concentric_mapping_lands_in_the_disk_and_keeps_the_rim() {
        for i in 0..=10 {
            for j in 0..=10 {
                let d = concentric_disk(Vec2::new(i as f32 / 10.0, j as f32 / 10.0));
                assert!(d.length() <= 1.0 + 1e-6);
            }
        }
        assert!((concentric_disk(Vec2::new(1.0, 0.5)) - Vec2::X).length() < 1e-6);
        assert!((concentric_disk(Vec2::new(0.5, 1.0)) - Vec2::Y).length() < 1e-6);
    }
}
