//! The table of the GGX specular lobe's directional albedo that the accumulation pass scales the diffuse base by,
//! so that a surface reflects no more than it receives (docs/architecture.md, "Energy: the diffuse base under the
//! specular layer"), and its lookup as the shader reads it. The GGX pieces themselves, the CPU twin of
//! `shaders/include/brdf.glsl`'s, are `math::ggx`, which build.rs integrates the table with; they stay reachable
//! here, where the library's users found them before the table moved to build time.
pub use super::ggx::{ggx_alpha, ggx_d, sample_ggx_vndf, smith_g1, smith_visibility, specular_albedo_terms};

/// The table's size (shared_constants.glsl): view cosines at cell centres (k + ½) / MU_STEPS, roughness at
/// j / (ROUGHNESS_STEPS − 1).
pub const MU_STEPS: usize = crate::shaders::constants::SPECULAR_ALBEDO_MU_STEPS as usize;
pub const ROUGHNESS_STEPS: usize = crate::shaders::constants::SPECULAR_ALBEDO_ROUGHNESS_STEPS as usize;

/// (E₁, E₅) for every (roughness, view cosine) of the table, roughness-major: what the accumulation pass reads
/// (`specular_albedo` in accumulate_bindings.glsl). Integrated once, by build.rs (`ggx::specular_albedo_table_values`),
/// and carried in the binary: integrating it took 0.8 s of every process's start-up.
pub fn specular_albedo_table() -> &'static [[f32; 2]] {
    &SPECULAR_ALBEDO_TABLE
}

include!(concat!(env!("OUT_DIR"), "/specular_albedo_table.rs"));

/// The white sheen lobe's directional albedo E for every (roughness, view cosine) of the same grid, roughness-major
/// (`sheen::sheen_albedo_table_values`, baked by build.rs): what the layers under a sheen are scaled by.
pub fn sheen_albedo_table() -> &'static [f32] {
    &SHEEN_ALBEDO_TABLE
}

/// What the accumulation pass's albedo buffer holds (`albedo_tables` in accumulate_bindings.glsl): the specular
/// table's (E₁, E₅), then the sheen table's (E, 0), each on the same grid.
pub fn albedo_tables() -> Vec<[f32; 2]> {
    specular_albedo_table().iter().copied().chain(sheen_albedo_table().iter().map(|&e| [e, 0.0])).collect()
}

/// The specular table read as the shader reads it: bilinear in (view cosine, roughness), clamped at the edges.
pub fn lookup(mu: f32, roughness: f32) -> [f32; 2] {
    let table = specular_albedo_table();
    lookup_in(|i| table[i], mu, roughness)
}

/// The sheen table read as the shader reads it.
pub fn sheen_lookup(mu: f32, roughness: f32) -> f32 {
    let table = sheen_albedo_table();
    lookup_in(|i| [table[i]], mu, roughness)[0]
}

/// A table whose entry `i` is `at(i)`, read bilinearly.
fn lookup_in<const N: usize>(at: impl Fn(usize) -> [f32; N], mu: f32, roughness: f32) -> [f32; N] {
    let x = (mu.clamp(0.0, 1.0) * MU_STEPS as f32 - 0.5).clamp(0.0, (MU_STEPS - 1) as f32);
    let y = roughness.clamp(0.0, 1.0) * (ROUGHNESS_STEPS - 1) as f32;
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(MU_STEPS - 1), (y0 + 1).min(ROUGHNESS_STEPS - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let at = |x: usize, y: usize| at(y * MU_STEPS + x);
    std::array::from_fn(|c| {
        let top = at(x0, y0)[c] * (1.0 - fx) + at(x1, y0)[c] * fx;
        let bottom = at(x0, y1)[c] * (1.0 - fx) + at(x1, y1)[c] * fx;
        top * (1.0 - fy) + bottom * fy
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

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

    /// The table build.rs baked is the one these functions integrate, bit for bit.
    #[test]
    fn the_baked_table_is_the_integrated_one() {
        let integrated = super::super::ggx::specular_albedo_table_values(MU_STEPS, ROUGHNESS_STEPS);
        let bits = |t: &[[f32; 2]]| t.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(specular_albedo_table()), bits(&integrated));
    }

    /// The sheen table: baked as integrated, and its quadrature within 2e-3 of a grid eight times finer each way
    /// (the Charlie lobe narrows towards the horizon as its roughness falls). The lobe reflects more than arrives
    /// where a smooth sheen is seen at grazing (1.51 at view cosine 0.01, roughness 0.03), which is why the shader
    /// divides it by max(1, E) (layers.glsl); seen head-on a smooth sheen reflects nothing.
    #[test]
    fn the_sheen_table_is_the_integrated_one_and_its_quadrature_converged() {
        use super::super::sheen::{sheen_albedo, sheen_albedo_table_values};
        let integrated = sheen_albedo_table_values(MU_STEPS, ROUGHNESS_STEPS);
        let bits = |t: &[f32]| t.iter().map(|e| e.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(sheen_albedo_table()), bits(&integrated));
        assert!(sheen_albedo_table().iter().all(|&e| (0.0..2.0).contains(&e)));
        assert!(sheen_albedo(0.01, 0.03, 96, 48) > 1.5 && sheen_albedo(1.0, 0.03, 96, 48) < 1e-6);
        for (mu, roughness) in [(1.0, 0.5), (0.5, 0.3), (0.1, 0.1), (0.05, 0.9), (0.8, 1.0), (0.05, 0.03), (0.01, 0.1)]
        {
            let (coarse, fine) = (sheen_albedo(mu, roughness, 96, 48), sheen_albedo(mu, roughness, 768, 384));
            assert!((coarse - fine).abs() < 2e-3, "mu {mu}, roughness {roughness}: {coarse} against {fine}");
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
