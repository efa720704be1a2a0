//! The sheen lobe's pure math, with nothing but `std`: the CPU twin of `shaders/include/layers.glsl`'s sheen
//! (KHR_materials_sheen: the "Charlie" distribution and its visibility, Estevez and Kulla 2017, "Production
//! Friendly Microfacet Sheen BRDF") and its directional albedo table, which the accumulation pass scales the
//! layers under the sheen by (docs/architecture.md, "Layered materials"). `build.rs` includes this file to bake
//! the table into the binary.
use std::f64::consts::PI;

/// The sheen roughness the lobe is evaluated at: the extension's roughness, kept off 0 (the distribution's
/// exponent is 1 / roughness²).
pub fn sheen_alpha(roughness: f64) -> f64 {
    let r = roughness.max(1e-3);
    r * r
}

/// The Charlie distribution D(h) = (2 + 1/α) sin^(1/α)(θ_h) / (2π) (Estevez and Kulla 2017, eq. 2).
pub fn charlie_d(nh: f64, alpha: f64) -> f64 {
    let sin2 = (1.0 - nh * nh).max(0.0);
    (2.0 + 1.0 / alpha) * sin2.powf(0.5 / alpha) / (2.0 * PI)
}

/// The paper's fit of the Charlie masking exponent's logarithm (its Table 1 and eq. 3), interpolated between the
/// fits at roughness 0 and 1 by (1 − α)², as the extension's sample renderer does.
fn lambda_fit(x: f64, alpha: f64) -> f64 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f64, b: f64| a + (b - a) * t;
    let (a, b, c) = (mix(21.5473, 25.3245), mix(3.82987, 3.32435), mix(0.19823, 0.16801));
    let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Λ(cos θ) of the Charlie distribution: the fit below 60° from grazing, mirrored about cos θ = ½ above it.
fn lambda(cos_theta: f64, alpha: f64) -> f64 {
    if cos_theta.abs() < 0.5 {
        lambda_fit(cos_theta, alpha).exp()
    } else {
        (2.0 * lambda_fit(0.5, alpha) - lambda_fit(1.0 - cos_theta, alpha)).exp()
    }
}

/// The sheen's visibility V = G2 / (4 n·l n·v) with G2 = 1 / (1 + Λ(v) + Λ(l)), kept within [0, 1] as the
/// extension's sample renderer keeps it.
pub fn sheen_visibility(nl: f64, nv: f64, alpha: f64) -> f64 {
    let v = 1.0 / ((1.0 + lambda(nv, alpha) + lambda(nl, alpha)) * (4.0 * nv * nl));
    v.clamp(0.0, 1.0)
}

/// The white sheen lobe's D·V·cos for light from `l` seen from `v` about the normal z (tangent space).
pub fn sheen_cos(v: [f64; 3], l: [f64; 3], alpha: f64) -> f64 {
    if l[2] <= 0.0 || v[2] <= 0.0 {
        return 0.0;
    }
    let h = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
    let nh = h[2] / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    charlie_d(nh, alpha) * sheen_visibility(l[2], v[2], alpha) * l[2]
}

/// The white sheen lobe's directional albedo E(μ) = ∫ D·V·cos dω at view cosine `mu`: a midpoint rule over the
/// hemisphere of light directions, `n_theta` polar steps and `2·n_phi` azimuths (symmetric about the view's plane,
/// so half of them counted twice). The polar steps crowd towards the horizon (θ = π/2 · (1 − (1 − t)²) for t
/// uniform), where a smooth sheen's lobe lies.
pub fn sheen_albedo(mu: f64, roughness: f64, n_theta: u32, n_phi: u32) -> f64 {
    let alpha = sheen_alpha(roughness);
    let v = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let dt = 1.0 / f64::from(n_theta);
    let d_phi = PI / f64::from(n_phi);
    let mut e = 0.0;
    for i in 0..n_theta {
        let t = (f64::from(i) + 0.5) * dt;
        let theta = PI / 2.0 * (1.0 - (1.0 - t) * (1.0 - t));
        let d_theta = PI * (1.0 - t) * dt;
        let (sin_t, cos_t) = theta.sin_cos();
        for j in 0..n_phi {
            let phi = (f64::from(j) + 0.5) * d_phi;
            let l = [sin_t * phi.cos(), sin_t * phi.sin(), cos_t];
            e += sheen_cos(v, l, alpha) * 2.0 * sin_t * d_theta * d_phi;
        }
    }
    e
}

/// E(μ) for every (roughness, view cosine) of a `mu_steps` × `roughness_steps` table, roughness-major, on the
/// specular albedo table's grid (`ggx::specular_albedo_table_values`).
pub fn sheen_albedo_table_values(mu_steps: usize, roughness_steps: usize) -> Vec<f32> {
    let mut table = Vec::with_capacity(mu_steps * roughness_steps);
    for j in 0..roughness_steps {
        let roughness = j as f64 / (roughness_steps - 1) as f64;
        for k in 0..mu_steps {
            let mu = (k as f64 + 0.5) / mu_steps as f64;
            table.push(sheen_albedo(mu, roughness, 96, 48) as f32);
        }
    }
    table
}
