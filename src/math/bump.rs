//! Blinn bump mapping (Blinn 1978, "Simulation of Wrinkled Surfaces") with a procedural Perlin height field.
//! CPU twin of `shaders/include/bump.glsl`. The formula is fixed in docs/architecture.md:
//! N = Q_u × Q_v, n̂ the shading normal, X = n̂ × Q_v, Y = n̂ × Q_u, D = B_u X − B_v Y,
//! N' = normalize(n̂ + σ·D/|N|), with σ = sign(n̂ · N) so mirrored UVs keep bumps outward.
use super::noise::{fbm_with_gradient, noise_with_gradient, turbulence_with_gradient};
use crate::scene::{BumpDerivative, BumpMap, NoiseKind};
use glam::{Vec2, Vec3, Vec4};

/// The height field's noise at UV `uv`: value in `w`, gradient with respect to (u, v, ·) in `xyz`
/// (before the amplitude). Noise is evaluated on the z = 0 slice at frequency × uv.
fn field(bump: &BumpMap, uv: Vec2) -> Vec4 {
    let p = (uv * bump.frequency).extend(0.0);
    let n = match bump.kind {
        NoiseKind::Noise => noise_with_gradient(p),
        NoiseKind::Fbm => fbm_with_gradient(p, bump.octaves, bump.lacunarity, bump.gain),
        NoiseKind::Turbulence => turbulence_with_gradient(p, bump.octaves, bump.lacunarity, bump.gain),
        NoiseKind::Sine => {
            let phase = std::f32::consts::TAU * p.x;
            Vec4::new(std::f32::consts::TAU * phase.cos(), 0.0, 0.0, phase.sin())
        }
    };
    // Chain rule for p = frequency · uv.
    Vec4::new(n.x * bump.frequency, n.y * bump.frequency, n.z * bump.frequency, n.w)
}

/// The height B(u, v) = amplitude · field(u, v).
pub fn height(bump: &BumpMap, uv: Vec2) -> f32 {
    bump.amplitude * field(bump, uv).w
}

/// (B_u, B_v): by central differences with step ε, B_u = (B(u+ε, v) − B(u−ε, v)) / 2ε, or analytically.
pub fn height_gradient(bump: &BumpMap, uv: Vec2) -> Vec2 {
    match bump.derivative {
        BumpDerivative::Analytic => bump.amplitude * field(bump, uv).truncate().truncate(),
        BumpDerivative::CentralDifferences => {
            let e = bump.epsilon;
            let du = height(bump, uv + Vec2::new(e, 0.0)) - height(bump, uv - Vec2::new(e, 0.0));
            let dv = height(bump, uv + Vec2::new(0.0, e)) - height(bump, uv - Vec2::new(0.0, e));
            Vec2::new(du, dv) / (2.0 * e)
        }
    }
}

/// Blinn's perturbed normal from the shading normal `n` (any length), surface derivatives `dpdu`, `dpdv` and
/// the height gradient (B_u, B_v). Degenerate derivatives (zero-area UVs) or a zero normal give the unperturbed
/// normal; the result is never NaN.
pub fn perturb_normal(n: Vec3, dpdu: Vec3, dpdv: Vec3, height_gradient: Vec2) -> Vec3 {
    let n_hat = n.normalize_or_zero();
    let big_n = dpdu.cross(dpdv);
    let length = big_n.length();
    if n_hat == Vec3::ZERO || length.is_nan() || length <= 1e-12 || !height_gradient.is_finite() {
        return n_hat;
    }
    let sigma = if n_hat.dot(big_n) < 0.0 { -1.0 } else { 1.0 };
    let x = n_hat.cross(dpdv);
    let y = n_hat.cross(dpdu);
    let d = x * height_gradient.x - y * height_gradient.y;
    let bumped = (n_hat + d * (sigma / length)).normalize_or_zero();
    if bumped == Vec3::ZERO {
        n_hat
    } else {
        bumped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_normal_is_minus_gradient_over_scale() {
        // Q = (s·u, s·v, 0): N' ∝ (−B_u/s, −B_v/s, 1) (docs/architecture.md), for several UV scales.
        for s in [0.5f32, 1.0, 4.0] {
            let g = Vec2::new(0.3, -0.7);
            let got = perturb_normal(Vec3::Z, Vec3::X * s, Vec3::Y * s, g);
            let want = Vec3::new(-g.x / s, -g.y / s, 1.0).normalize();
            assert!((got - want).length() < 1e-6, "s = {s}: {got} vs {want}");
        }
    }

    #[test]
    fn mirrored_uvs_keep_bumps_outward() {
        // u runs along −x: the surface z = B(−x/s, y/s) has normal ∝ (B_u/s, −B_v/s, 1).
        let (s, g) = (2.0, Vec2::new(0.5, 0.25));
        let got = perturb_normal(Vec3::Z, -Vec3::X * s, Vec3::Y * s, g);
        let want = Vec3::new(g.x / s, -g.y / s, 1.0).normalize();
        assert!((got - want).length() < 1e-6, "{got} vs {want}");
    }

    #[test]
    fn degenerate_input_gives_the_unperturbed_normal() {
        let n = Vec3::new(0.0, 2.0, 0.0);
        assert_eq!(perturb_normal(n, Vec3::ZERO, Vec3::X, Vec2::ONE), Vec3::Y);
        assert_eq!(perturb_normal(n, Vec3::X, Vec3::X * 3.0, Vec2::ONE), Vec3::Y);
        assert_eq!(perturb_normal(Vec3::ZERO, Vec3::X, Vec3::Z, Vec2::ONE), Vec3::ZERO);
        assert_eq!(perturb_normal(n, Vec3::X, Vec3::Z, Vec2::new(f32::NAN, 0.0)), Vec3::Y);
    }

    #[test]
    fn central_differences_approach_the_analytic_gradient() {
        let mut bump = BumpMap { kind: NoiseKind::Fbm, amplitude: 0.05, frequency: 3.0, ..Default::default() };
        let (mut worst, mut mean) = (0.0f32, 0.0f32);
        for i in 0..500 {
            let uv = Vec2::new((i as f32 * 0.618_034).fract() * 4.0, (i as f32 * 0.414_214).fract() * 4.0);
            bump.derivative = BumpDerivative::Analytic;
            let analytic = height_gradient(&bump, uv);
            bump.derivative = BumpDerivative::CentralDifferences;
            bump.epsilon = 1e-3;
            let central = height_gradient(&bump, uv);
            worst = worst.max((analytic - central).length());
            mean += analytic.length() / 500.0;
        }
        // Central differences err by O(ε²·f³): tiny next to the gradient's typical size.
        assert!(worst < 0.01 * mean, "worst difference {worst} vs mean gradient {mean}");
    }
}
