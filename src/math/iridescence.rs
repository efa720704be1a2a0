//! The thin film's Fresnel reflectance, with nothing but `std`: the CPU twin of `shaders/include/layers.glsl`'s
//! `thin_film_fresnel` (KHR_materials_iridescence). Belcour and Barla 2017, "A Practical Extension to Microfacet
//! Theory for the Modeling of Varying Iridescence": the Airy sum of the light reflected between the film's two
//! interfaces, its first two interference terms integrated against the CIE 1931 colour matching functions in
//! Fourier space (the paper's Gaussian fit of them), then XYZ to linear Rec.709, as the extension's sample renderer
//! evaluates it, with two differences that make a film of thickness 0 no film: the film's index fades to the
//! outside's as it thins to nothing (the sample renderer's smoothstep over 0.03 nm), and the outer interface's
//! reflectance is the exact dielectric Fresnel (Schlick's, which the sample renderer uses there, reflects
//! (1 − cos)⁵ between equal indices), so at thickness 0 the Airy sum is the base's Schlick reflectance alone.
//! The shader applies the film as the ratio of its reflectance to the zero-thickness film's at the view angle
//! (`film_ratio`), times the base's own Fresnel per microfacet.
use std::f64::consts::PI;

/// CIE XYZ to linear Rec.709 (sRGB primaries, D65), rows.
const XYZ_TO_REC709: [[f64; 3]; 3] =
    [[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560], [0.0556434, -0.2040259, 1.0572252]];

fn schlick(f0: f64, cos: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - cos).clamp(0.0, 1.0).powi(5)
}

/// The exact unpolarised Fresnel reflectance from index `n1` into `n2` at cosine `cos1` (1 beyond the critical
/// angle).
fn dielectric_fresnel(n1: f64, n2: f64, cos1: f64) -> f64 {
    let sin2_sq = (n1 / n2).powi(2) * (1.0 - cos1 * cos1);
    if sin2_sq >= 1.0 {
        return 1.0;
    }
    let cos2 = (1.0 - sin2_sq).sqrt();
    let rs = (n1 * cos1 - n2 * cos2) / (n1 * cos1 + n2 * cos2);
    let rp = (n2 * cos1 - n1 * cos2) / (n2 * cos1 + n1 * cos2);
    0.5 * (rs * rs + rp * rp)
}

/// The reflectance at normal incidence between media of indices `n1` and `n2`.
fn f0_between(n1: f64, n2: f64) -> f64 {
    ((n1 - n2) / (n1 + n2)).powi(2)
}

/// The index of a medium whose reflectance against air at normal incidence is `f0`.
fn ior_from_f0(f0: f64) -> f64 {
    let s = f0.clamp(0.0, 0.9999).sqrt();
    (1.0 + s) / (1.0 - s)
}

/// The colour matching functions' response to an interference of optical path difference `opd` (nm) and phase
/// `shift` per channel of XYZ, in linear Rec.709: the Fourier transform of the paper's Gaussian fit of x̄, ȳ, z̄
/// (its supplemental material), normalised so that white light sums to 1.
fn sensitivity(opd: f64, shift: [f64; 3]) -> [f64; 3] {
    let phase = 2.0 * PI * opd * 1.0e-9;
    let val = [5.4856e-13, 4.4201e-13, 5.2481e-13];
    let pos = [1.6810e+06, 1.7953e+06, 2.2084e+06];
    let var: [f64; 3] = [4.3278e+09, 9.3046e+09, 6.6121e+09];
    let mut xyz: [f64; 3] = std::array::from_fn(|i| {
        val[i] * (2.0 * PI * var[i]).sqrt() * (pos[i] * phase + shift[i]).cos() * (-phase * phase * var[i]).exp()
    });
    xyz[0] += 9.7470e-14
        * (2.0 * PI * 4.5282e+09f64).sqrt()
        * (2.2399e+06 * phase + shift[0]).cos()
        * (-4.5282e+09 * phase * phase).exp();
    let xyz = xyz.map(|c| c / 1.0685e-7);
    std::array::from_fn(|r| XYZ_TO_REC709[r].iter().zip(xyz).map(|(m, c)| m * c).sum())
}

/// The film's reflectance per linear Rec.709 channel, seen at cosine `cos1` from outside (index 1), for a film of
/// index `film_ior` and `thickness` nanometres over a base whose reflectance at normal incidence is `base_f0`.
pub fn thin_film_fresnel(cos1: f64, film_ior: f64, thickness: f64, base_f0: [f64; 3]) -> [f64; 3] {
    let outside = 1.0;
    // The film fades into the outside medium over its first 0.03 nm (smoothstep), so that no film is no film.
    let t = (thickness / 0.03).clamp(0.0, 1.0);
    let film = outside + (film_ior - outside) * t * t * (3.0 - 2.0 * t);
    let sin2_sq = (outside / film).powi(2) * (1.0 - cos1 * cos1);
    let cos2_sq = 1.0 - sin2_sq;
    if cos2_sq < 0.0 {
        return [1.0; 3]; // total internal reflection at the film
    }
    let cos2 = cos2_sq.sqrt();
    // The outer interface: reflectance, transmittance there and back, the phase of its reflections.
    let r12 = dielectric_fresnel(outside, film, cos1);
    let t121 = 1.0 - r12;
    let phi12 = if film < outside { PI } else { 0.0 };
    let phi21 = PI - phi12;
    // The inner interface, film to base.
    let opd = 2.0 * film * thickness * cos2;
    let mut reflectance = [0.0; 3];
    let (mut r23, mut phi23) = ([0.0; 3], [0.0; 3]);
    for c in 0..3 {
        let base_ior = ior_from_f0(base_f0[c]);
        r23[c] = schlick(f0_between(base_ior, film), cos2);
        phi23[c] = if base_ior < film { PI } else { 0.0 };
    }
    let r123: [f64; 3] = std::array::from_fn(|c| (r12 * r23[c]).clamp(0.0, 0.9999));
    let rs: [f64; 3] = std::array::from_fn(|c| t121 * t121 * r23[c] / (1.0 - r123[c]));
    // The Airy sum: its mean (m = 0), then the first two interference terms.
    let mut cm: [f64; 3] = std::array::from_fn(|c| rs[c] - t121);
    for c in 0..3 {
        reflectance[c] = r12 + rs[c];
    }
    for m in 1..=2 {
        let mf = f64::from(m);
        let shift: [f64; 3] = std::array::from_fn(|c| mf * (phi21 + phi23[c]));
        let s = sensitivity(mf * opd, shift);
        for c in 0..3 {
            cm[c] *= r123[c].sqrt();
            reflectance[c] += cm[c] * 2.0 * s[c];
        }
    }
    reflectance.map(|r| r.max(0.0))
}

/// What the shader multiplies the base's Fresnel by: the film's reflectance over the zero-thickness film's (the
/// base's Schlick reflectance through the same sum) at the view cosine, per channel; 1 where the latter is 0.
pub fn film_ratio(cos1: f64, film_ior: f64, thickness: f64, base_f0: [f64; 3]) -> [f64; 3] {
    let film = thin_film_fresnel(cos1, film_ior, thickness, base_f0);
    let none = thin_film_fresnel(cos1, film_ior, 0.0, base_f0);
    std::array::from_fn(|c| if none[c] > 0.0 { film[c] / none[c] } else { 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No film reflects what the base does; a film's colour swings with its thickness.
    #[test]
    fn no_film_is_the_base_and_a_film_colours_by_thickness() {
        for cos in [1.0, 0.7, 0.3] {
            let none = thin_film_fresnel(cos, 1.3, 0.0, [0.04; 3]);
            let base = schlick(f0_between(ior_from_f0(0.04), 1.0), cos);
            assert!(none.iter().all(|r| (r - base).abs() < 1e-12), "cos {cos}: {none:?} vs {base}");
            assert_eq!(film_ratio(cos, 1.3, 0.0, [0.04; 3]), [1.0; 3]);
        }
        let [r, g, b] = thin_film_fresnel(1.0, 1.3, 300.0, [0.04; 3]);
        let spread = r.max(g).max(b) - r.min(g).min(b);
        assert!(spread > 0.02, "a 300 nm film is coloured: {r} {g} {b}");
    }
}
