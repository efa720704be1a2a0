//! Surface derivatives for bump mapping: Q_u = ∂P/∂u and Q_v = ∂P/∂v per vertex from positions and UVs.
//! Blinn (1978) perturbs the normal by D/|N| with N = Q_u × Q_v, so these stay unnormalized.
use super::Primitive;
use glam::Vec3;

/// Fills `dpdu`/`dpdv` from TEXCOORD_0. For each triangle with edges e1 = P1 − P0, e2 = P2 − P0 and UV edges
/// Δ1, Δ2, solving e1 = Q_u Δ1.u + Q_v Δ1.v and e2 = Q_u Δ2.u + Q_v Δ2.v gives
/// Q_u = (e1 Δ2.v − e2 Δ1.v)/det, Q_v = (e2 Δ1.u − e1 Δ2.u)/det, det = Δ1.u Δ2.v − Δ1.v Δ2.u.
/// A vertex averages the triangles around it; triangles with zero UV area or zero 3D area contribute nothing,
/// so a vertex touched only by those keeps zero derivatives (bump mapping is then off there, never NaN).
pub fn compute_surface_derivatives(primitive: &mut Primitive) {
    let n = primitive.positions.len();
    primitive.dpdu.clear();
    primitive.dpdv.clear();
    if primitive.uvs.len() != n {
        return;
    }
    let mut sum_u = vec![Vec3::ZERO; n];
    let mut sum_v = vec![Vec3::ZERO; n];
    let mut count = vec![0u32; n];
    for tri in primitive.indices.chunks_exact(3) {
        let [i0, i1, i2] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        let (p0, p1, p2) = (primitive.positions[i0], primitive.positions[i1], primitive.positions[i2]);
        let (t0, t1, t2) = (primitive.uvs[i0], primitive.uvs[i1], primitive.uvs[i2]);
        let (e1, e2) = (p1 - p0, p2 - p0);
        let (d1, d2) = (t1 - t0, t2 - t0);
        let det = d1.x * d2.y - d1.y * d2.x;
        let area = e1.cross(e2).length();
        // Relative thresholds: the scale of UVs and positions is arbitrary.
        let uv_scale = d1.length_squared().max(d2.length_squared());
        if area <= f32::EPSILON * (e1.length_squared() + e2.length_squared()) || det.abs() <= 1e-7 * uv_scale {
            continue;
        }
        let qu = (e1 * d2.y - e2 * d1.y) / det;
        let qv = (e2 * d1.x - e1 * d2.x) / det;
        if !qu.is_finite() || !qv.is_finite() {
            continue;
        }
        for i in [i0, i1, i2] {
            sum_u[i] += qu;
            sum_v[i] += qv;
            count[i] += 1;
        }
    }
    primitive.dpdu = sum_u.iter().zip(&count).map(|(s, &c)| if c > 0 { *s / c as f32 } else { Vec3::ZERO }).collect();
    primitive.dpdv = sum_v.iter().zip(&count).map(|(s, &c)| if c > 0 { *s / c as f32 } else { Vec3::ZERO }).collect();
}

/// Without NORMAL, glTF asks for flat normals (§3.7.2.1): give every triangle its own three vertices.
pub fn flatten_with_face_normals(p: &mut Primitive) {
    fn gather<T: Copy>(values: &[T], indices: &[u32]) -> Vec<T> {
        if values.is_empty() {
            Vec::new()
        } else {
            indices.iter().map(|&i| values[i as usize]).collect()
        }
    }
    let normals = p
        .indices
        .chunks_exact(3)
        .flat_map(|tri| {
            let [a, b, c] = [0, 1, 2].map(|k| p.positions[tri[k] as usize]);
            // Zero-area triangles get a zero normal rather than NaN.
            let n = (b - a).cross(c - a).normalize_or_zero();
            [n, n, n]
        })
        .collect();
    p.positions = gather(&p.positions, &p.indices);
    p.tangents = gather(&p.tangents, &p.indices);
    p.uvs = gather(&p.uvs, &p.indices);
    p.uvs1 = gather(&p.uvs1, &p.indices);
    p.colors = gather(&p.colors, &p.indices);
    for set in &mut p.skin_influences {
        set.joints = gather(&set.joints, &p.indices);
        set.weights = gather(&set.weights, &p.indices);
    }
    p.normals = normals;
    p.indices = (0..p.positions.len() as u32).collect();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes::{plane, uv_sphere};
    use glam::Vec2;

    #[test]
    fn plane_with_uv_scale_has_derivatives_of_length_size_over_scale() {
        // A 4 m × 2 m plane with UVs 0..2 × 0..8: Q_u = 2 m per UV unit along +X, Q_v = 0.25 m along −Z.
        let mut p = plane(Vec2::new(4.0, 2.0), Vec2::new(2.0, 8.0), None);
        compute_surface_derivatives(&mut p);
        for (qu, qv) in p.dpdu.iter().zip(&p.dpdv) {
            assert!((*qu - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6, "{qu}");
            assert!((*qv - Vec3::new(0.0, 0.0, -0.25)).length() < 1e-6, "{qv}");
            // Q_u × Q_v points along the normal.
            assert!(qu.cross(*qv).normalize().dot(Vec3::Y) > 0.999);
        }
    }

    #[test]
    fn mirrored_uvs_flip_the_sign_of_q_u_cross_q_v() {
        let mut p = plane(Vec2::new(1.0, 1.0), Vec2::ONE, None);
        for uv in &mut p.uvs {
            uv.x = 1.0 - uv.x;
        }
        compute_surface_derivatives(&mut p);
        for (qu, qv) in p.dpdu.iter().zip(&p.dpdv) {
            assert!(qu.cross(*qv).normalize().dot(Vec3::Y) < -0.999);
        }
    }

    #[test]
    fn sphere_derivatives_match_the_parametrisation() {
        // u = φ/2π, v = θ/π: |Q_u| = 2π r sin θ, |Q_v| = π r, orthogonal.
        let r = 1.5;
        let mut s = uv_sphere(r, 64, 32, None);
        compute_surface_derivatives(&mut s);
        for i in 0..s.positions.len() {
            let theta = s.uvs[i].y * std::f32::consts::PI;
            // Near the poles the averaged fan is not the analytic limit, and seam vertices (u = 0 or 1) see
            // triangles on one side only, so their average is biased by the ring spacing.
            if !(0.3..=std::f32::consts::PI - 0.3).contains(&theta) || s.uvs[i].x == 0.0 || s.uvs[i].x == 1.0 {
                continue;
            }
            let (qu, qv) = (s.dpdu[i], s.dpdv[i]);
            let want_u = std::f32::consts::TAU * r * theta.sin();
            let want_v = std::f32::consts::PI * r;
            assert!((qu.length() / want_u - 1.0).abs() < 0.01, "vertex {i}: |Q_u| {} want {want_u}", qu.length());
            assert!((qv.length() / want_v - 1.0).abs() < 0.01, "vertex {i}: |Q_v| {} want {want_v}", qv.length());
            assert!(qu.normalize().dot(qv.normalize()).abs() < 0.02);
        }
    }

    #[test]
    fn degenerate_uvs_and_zero_area_triangles_give_zero_not_nan() {
        let mut p = plane(Vec2::ONE, Vec2::ONE, None);
        p.uvs = vec![Vec2::ZERO; 4];
        compute_surface_derivatives(&mut p);
        assert!(p.dpdu.iter().chain(&p.dpdv).all(|v| *v == Vec3::ZERO));
        let mut q = plane(Vec2::ONE, Vec2::ONE, None);
        q.positions = vec![Vec3::ONE; 4];
        compute_surface_derivatives(&mut q);
        assert!(q.dpdu.iter().chain(&q.dpdv).all(|v| v.is_finite() && *v == Vec3::ZERO));
    }
}
