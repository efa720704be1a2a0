//! The GGX lobe's pure math, with nothing but `std`: the CPU twin of `shaders/include/brdf.glsl`'s GGX pieces
//! (glTF 2.0 Appendix B: GGX with the height-correlated Smith visibility; Heitz 2018's visible-normal sampling)
//! and the specular albedo table they integrate to. `build.rs` includes this file to bake the table into the
//! binary (`math::brdf::specular_albedo_table`), so every process reads it instead of integrating it again.
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

/// (E₁, E₅) for every (roughness, view cosine) of a `mu_steps` × `roughness_steps` table, roughness-major: view
/// cosines at cell centres (k + ½) / mu_steps, roughness at j / (roughness_steps − 1).
pub fn specular_albedo_table_values(mu_steps: usize, roughness_steps: usize) -> Vec<[f32; 2]> {
    let mut table = Vec::with_capacity(mu_steps * roughness_steps);
    for j in 0..roughness_steps {
        let roughness = j as f64 / (roughness_steps - 1) as f64;
        for k in 0..mu_steps {
            let mu = (k as f64 + 0.5) / mu_steps as f64;
            let (e1, e5) = specular_albedo_terms(mu, roughness, 48);
            table.push([e1 as f32, e5 as f32]);
        }
    }
    table
}
