//! Procedural meshes for the project's own scenes: planes, boxes and UV spheres with normals and UVs
//! (UVs in metres of surface where that is natural, so bump frequencies read in world units).
use super::Primitive;
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// A `size.x` × `size.y` rectangle in the XZ plane at y = 0, facing +Y, split into two triangles.
/// UVs run 0..`uv_scale` across it.
pub fn plane(size: Vec2, uv_scale: Vec2, material: Option<usize>) -> Primitive {
    let (hx, hz) = (size.x * 0.5, size.y * 0.5);
    let positions =
        vec![Vec3::new(-hx, 0.0, hz), Vec3::new(hx, 0.0, hz), Vec3::new(hx, 0.0, -hz), Vec3::new(-hx, 0.0, -hz)];
    let uvs = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(uv_scale.x, 0.0),
        Vec2::new(uv_scale.x, uv_scale.y),
        Vec2::new(0.0, uv_scale.y),
    ];
    Primitive {
        positions,
        normals: vec![Vec3::Y; 4],
        uvs,
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        ..Default::default()
    }
}

/// An axis-aligned box centred at the origin with the given half extents; each face has its own vertices,
/// normal and 0..1 UVs. Triangles wind counter-clockwise seen from outside.
pub fn cuboid(half: Vec3, material: Option<usize>) -> Primitive {
    let mut p = Primitive { material, ..Default::default() };
    // (normal, u axis, v axis): u × v = normal keeps the winding outward.
    let faces = [
        (Vec3::X, Vec3::NEG_Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::X, Vec3::NEG_Z),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
    ];
    for (n, u, v) in faces {
        let base = p.positions.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            p.positions.push((n + u * su + v * sv) * half);
            p.normals.push(n);
            p.uvs.push(Vec2::new((su + 1.0) * 0.5, (sv + 1.0) * 0.5));
        }
        p.indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    p
}

/// A UV sphere: `segments` around the Y axis, `rings` from pole to pole; u = longitude / 2π, v = latitude / π.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32, material: Option<usize>) -> Primitive {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut p = Primitive { material, ..Default::default() };
    for ring in 0..=rings {
        let v = ring as f32 / rings as f32;
        let theta = v * PI;
        for seg in 0..=segments {
            let u = seg as f32 / segments as f32;
            let phi = u * TAU;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin());
            p.positions.push(n * radius);
            p.normals.push(n);
            p.uvs.push(Vec2::new(u, v));
        }
    }
    let row = segments + 1;
    for ring in 0..rings {
        for seg in 0..segments {
            let a = ring * row + seg;
            let b = a + row;
            // Skip the degenerate triangles at the poles.
            if ring != 0 {
                p.indices.extend([a, b, a + 1]);
            }
            if ring != rings - 1 {
                p.indices.extend([a + 1, b, b + 1]);
            }
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outward(p: &Primitive) -> bool {
        p.indices.chunks_exact(3).all(|t| {
            let [a, b, c] = [0, 1, 2].map(|k| p.positions[t[k] as usize]);
            let face = (b - a).cross(c - a);
            let n = p.normals[t[0] as usize] + p.normals[t[1] as usize] + p.normals[t[2] as usize];
            face.dot(n) > 0.0
        })
    }

    #[test]
    fn shapes_wind_counter_clockwise_outwards() {
        assert!(outward(&plane(Vec2::new(2.0, 3.0), Vec2::ONE, None)));
        assert!(outward(&cuboid(Vec3::new(1.0, 2.0, 3.0), None)));
        assert!(outward(&uv_sphere(1.5, 16, 8, None)));
    }

    #[test]
    fn sphere_vertices_lie_on_the_sphere_and_normals_are_radial() {
        let s = uv_sphere(2.0, 12, 6, None);
        for (p, n) in s.positions.iter().zip(&s.normals) {
            assert!((p.length() - 2.0).abs() < 1e-5);
            assert!((*p / 2.0 - *n).length() < 1e-5);
        }
        assert_eq!(s.triangle_count(), 12 * 6 * 2 - 2 * 12);
    }
}
