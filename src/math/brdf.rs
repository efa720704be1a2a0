//! CPU twin of the GGX pieces of `shaders/include/brdf.glsl` (glTF 2.0 Appendix B: GGX with the height-correlated
//! Smith visibility; Heitz 2018's visible-normal sampling), and the table of the specular lobe's directional
//! albedo the accumulation pass scales the diffuse base by, so that a surface reflects no more than it receives
//! (docs/architecture.md, "Energy: the diffuse base under the specular layer").
use std::f64::consts::PI;

/// alpha = roughness², kept above a floor (as the shader does) so a mirror stays a narrow lobe without NaN.
pub fn ggx_alpha(roughness: f64) -> f64 {
    (roughness * roughness).max(1e-3)
}

pub fn ggx_d(nh: f64, a: f64) -> f64 {
    let a2 = a * a;
    let d = nh * nh * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith G1 for GGX at cosine `c`.
pub fn smith_g1(c: f64, a: f64) -> f64 {
    let a2 = a * a;
    2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt())
}

/// Height-correlated Smith visibility V = G2 / (4 n·l n·v).
pub fn smith_visibility(nl: f64, nv: f64, a: f64) -> f64 {
    let a2 = a * a;
    let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
    let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
    let d = gv + gl;
    if d > 0.0 {
        0.5 / d
    } else {
        0.0
    }
}

/// A GGX visible normal for view `ve` in tangent space (z = normal), from `u` in [0,1)² (Heitz 2018, Listing 1).
pub fn sample_ggx_vndf(ve: [f64; 3], a: f64, u: [f64; 2]) -> [f64; 3] {
    let normalize = |v: [f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    };
    let vh = normalize([a * ve[0], a * ve[1], ve[2]]);
    let lensq = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if lensq > 0.0 { [-vh[1] / lensq.sqrt(), vh[0] / lensq.sqrt(), 0.0] } else { [1.0, 0.0, 0.0] };
    let t2 = [vh[1] * t1[2] - vh[2] * t1[1], vh[2] * t1[0] - vh[0] * t1[2], vh[0] * t1[1] - vh[1] * t1[0]];
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = [0, 1, 2].map(|k| p1 * t1[k] + p2 * t2[k] + p3 * vh[k]);
    normalize([a * nh[0], a * nh[1], nh[2].max(0.0)])
}

/// The GGX lobe's directional albedo at view cosine `mu`, as the two Schlick terms: (E₁, E₅) with
/// E₁ = ∫ D·V·cos dω (a Fresnel of 1) and E₅ = ∫ (1 − v·h)⁵·D·V·cos dω, so that a lobe with Fresnel
/// F₀ + (F₉₀ − F₀)(1 − v·h)⁵ reflects F₀·E₁ + (F₉₀ − F₀)·E₅ of what arrives. Estimated with `n`² stratified
/// visible-normal samples, whose weight G2/G1(v) (sample_specular's) varies little.
pub fn specular_albedo_terms(mu: f64, roughness: f64, n: u32) -> (f64, f64) {
    let mu = mu.clamp(1e-4, 1.0);
    let a = ggx_alpha(roughness);
    let ve = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let (mut e1, mut e5) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let u = [(f64::from(i) + 0.5) / f64::from(n), (f64::from(j) + 0.5) / f64::from(n)];
            let h = sample_ggx_vndf(ve, a, u);
            let vh = ve[0] * h[0] + ve[1] * h[1] + ve[2] * h[2];
            // The mirror direction about h: l = 2 (v·h) h − v.
            let nl = 2.0 * vh * h[2] - ve[2];
            if nl <= 0.0 || vh <= 0.0 {
                continue;
            }
            let weight = 4.0 * nl * mu * smith_visibility(nl, mu, a) / smith_g1(mu, a);
            e1 += weight;
            e5 += weight * (1.0 - vh).powi(5);
        }
    }
    let samples = f64::from(n * n);
    (e1 / samples, e5 / samples)
}

/// The table's size (shared_constants.glsl): view cosines at cell centres (k + ½) / MU_STEPS, roughness at
/// j / (ROUGHNESS_STEPS − 1).
pub const MU_STEPS: usize = crate::shaders::constants::SPECULAR_ALBEDO_MU_STEPS as usize;
pub const ROUGHNESS_STEPS: usize = crate::shaders::constants::SPECULAR_ALBEDO_ROUGHNESS_STEPS as usize;

/// (E₁, E₅) for every (roughness, view cosine) of the table, roughness-major: what the accumulation pass reads
/// (`specular_albedo` in accumulate_bindings.glsl). Made once per process.
pub fn specular_albedo_table() -> &'static [[f32; 2]] {
    static TABLE: std::sync::OnceLock<Vec<[f32; 2]>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut table = Vec::with_capacity(MU_STEPS * ROUGHNESS_STEPS);
        for j in 0..ROUGHNESS_STEPS {
            let roughness = j as f64 / (ROUGHNESS_STEPS - 1) as f64;
            for k in 0..MU_STEPS {
                let mu = (k as f64 + 0.5) / MU_STEPS as f64;
                let (e1, e5) = specular_albedo_terms(mu, roughness, 48);
                table.push([e1 as f32, e5 as f32]);
            }
        }
        table
    })
}

/// The table read as the shader reads it: bilinear in (view cosine, roughness), clamped at the edges.
pub fn lookup(mu: f32, roughness: f32) -> [f32; 2] {
    let table = specular_albedo_table();
    let x = (mu.clamp(0.0, 1.0) * MU_STEPS as f32 - 0.5).clamp(0.0, (MU_STEPS - 1) as f32);
    let y = roughness.clamp(0.0, 1.0) * (ROUGHNESS_STEPS - 1) as f32;
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(MU_STEPS - 1), (y0 + 1).min(ROUGHNESS_STEPS - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let at = |x: usize, y: usize| table[y * MU_STEPS + x];
    std::array::from_fn(|c| {
        let top = at(x0, y0)[c] * (1.0 - fx) + at(x1, y0)[c] * fx;
        let bottom = at(x0, y1)[c] * (1.0 - fx) + at(x1, y1)[c] * fx;
        top * (1.0 - fy) + bottom * fy
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same integral by brute force over the hemisphere of light directions (a midpoint rule in θ, φ), not
    /// through visible normals: the two must agree.
    fn brute_force(mu: f64, roughness: f64) -> (f64, f64) {
        let a = ggx_alpha(roughness);
        let v = [(1.0 - mu * mu).sqrt(), 0.0, mu];
        let (n_theta, n_phi) = (1200, 600);
        let (mut e1, mut e5) = (0.0, 0.0);
        for i in 0..n_theta {
            let theta = (f64::from(i) + 0.5) / f64::from(n_theta) * PI / 2.0;
            for j in 0..n_phi {
                // Symmetric about the plane of v: half the azimuths, twice the weight.
                let phi = (f64::from(j) + 0.5) / f64::from(n_phi) * PI;
                let l = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()];
                let h = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
                let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
                let (vh, nh) = ((h[0] * v[0] + h[2] * v[2]) / len, h[2] / len);
                let d_omega = 2.0 * theta.sin() * (PI / 2.0 / f64::from(n_theta)) * (PI / f64::from(n_phi));
                let f = ggx_d(nh, a) * smith_visibility(l[2], mu, a) * l[2] * d_omega;
                e1 += f;
                e5 += f * (1.0 - vh).powi(5);
            }
        }
        (e1, e5)
    }

    #[test]
    fn visible_normal_quadrature_agrees_with_brute_force_integration() {
        for (mu, roughness) in [(1.0, 0.5), (0.5, 0.5), (0.2, 0.2), (0.1, 0.6), (0.8, 1.0), (0.3, 0.35)] {
            let (e1, e5) = specular_albedo_terms(mu, roughness, 48);
            let (b1, b5) = brute_force(mu, roughness);
            assert!((e1 - b1).abs() < 2e-3, "E1 at mu {mu}, roughness {roughness}: {e1} by VNDF, {b1} brute force");
            assert!((e5 - b5).abs() < 2e-3, "E5 at mu {mu}, roughness {roughness}: {e5} by VNDF, {b5} brute force");
        }
    }

    #[test]
    fn a_white_lobe_reflects_at_most_what_arrives() {
        for &[e1, e5] in specular_albedo_table() {
            assert!(e1 > 0.0 && e1 <= 1.0 + 1e-6 && e5 >= 0.0 && e5 <= e1, "{e1} {e5}");
        }
        // A smooth lobe seen head-on loses nothing. At roughness 1 (α = 1) D = 1/π and V = 1 / (2 (n·l + n·v)),
        // so head-on E₁ = ∫₀¹ c / (c + 1) dc = 1 − ln 2.
        assert!((lookup(1.0, 0.0)[0] - 1.0).abs() < 2e-3, "{:?}", lookup(1.0, 0.0));
        let head_on = specular_albedo_terms(1.0, 1.0, 48).0;
        assert!((head_on - (1.0 - std::f64::consts::LN_2)).abs() < 1e-3, "{head_on}");
    }
}
