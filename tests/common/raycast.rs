//! A CPU ray caster over a scene's triangles (Möller–Trumbore), for tests that compare GPU images with a CPU
//! twin: it returns where a ray hits, and interpolates any per-vertex attribute there.
use glam::{Mat4, Vec2, Vec3};
use strata::scene::{Primitive, Scene};

pub struct Hit<'a> {
    pub t: f32,
    pub world_from_object: Mat4,
    pub primitive: &'a Primitive,
    /// The triangle's three vertex indices.
    pub vertices: [usize; 3],
    /// Barycentric weights of the three vertices.
    pub weights: [f32; 3],
}

impl Hit<'_> {
    /// Interpolates a per-vertex attribute (which must not be empty).
    pub fn lerp<T>(&self, values: &[T]) -> T
    where
        T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        let [a, b, c] = self.vertices;
        values[a] * self.weights[0] + values[b] * self.weights[1] + values[c] * self.weights[2]
    }
}

/// The nearest hit of the ray `origin + t·direction`, t > 1e-4, with any instance of `scene` placed by
/// `transforms` (one per instance).
pub fn cast<'a>(scene: &'a Scene, transforms: &[Mat4], origin: Vec3, direction: Vec3) -> Option<Hit<'a>> {
    let mut best: Option<Hit<'a>> = None;
    for (instance, m) in scene.instances.iter().zip(transforms) {
        for p in &scene.meshes[instance.mesh].primitives {
            for tri in p.indices.chunks_exact(3) {
                let vertices = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
                let [a, b, c] = vertices.map(|i| m.transform_point3(p.positions[i]));
                let (e1, e2) = (b - a, c - a);
                let pv = direction.cross(e2);
                let det = e1.dot(pv);
                if det.abs() < 1e-12 {
                    continue;
                }
                let s = origin - a;
                let u = s.dot(pv) / det;
                let q = s.cross(e1);
                let v = direction.dot(q) / det;
                let t = e2.dot(q) / det;
                if u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 1e-4 || best.as_ref().is_some_and(|h| h.t <= t) {
                    continue;
                }
                best = Some(Hit { t, world_from_object: *m, primitive: p, vertices, weights: [1.0 - u - v, u, v] });
            }
        }
    }
    best
}

/// The world-space ray through the centre of pixel (x, y) for `clip_from_world` on a `width`×`height` image.
pub fn pixel_ray(clip_from_world: Mat4, x: u32, y: u32, width: u32, height: u32) -> (Vec3, Vec3) {
    point_ray(clip_from_world, Vec2::new(x as f32 + 0.5, y as f32 + 0.5), width, height)
}

/// The ray through a point of the image, in pixels from its top-left corner (pixel centres at +0.5).
pub fn point_ray(clip_from_world: Mat4, point: Vec2, width: u32, height: u32) -> (Vec3, Vec3) {
    let world_from_clip = clip_from_world.inverse();
    let ndc = point / Vec2::new(width as f32, height as f32) * 2.0 - Vec2::ONE;
    let near = world_from_clip.project_point3(ndc.extend(0.0));
    let far = world_from_clip.project_point3(ndc.extend(0.5));
    (near, (far - near).normalize())
}
