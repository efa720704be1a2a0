//! KHR_materials_dispersion's index of refraction by colour channel: the twin of `shaders/include/dispersion.glsl`
//! (which says how the path tracer uses it).

/// The wavelengths (nm) the colour channels refract at: the Fraunhofer C, d and F lines, between which the Abbe
/// number is defined.
pub const CHANNEL_WAVELENGTHS_NM: [f32; 3] = [656.27, 587.56, 486.13];

/// The index of refraction for `channel` (0 red, 1 green, 2 blue) of a material with index `ior` at 587.56 nm and
/// `dispersion` = 20 / V_d: the extension's two-term Cauchy equation, n(λ) = max(n_d + (n_d − 1) / V_d · (523655 /
/// λ² − 1.5168), 1).
pub fn dispersed_ior(ior: f32, dispersion: f32, channel: usize) -> f32 {
    let wavelength = CHANNEL_WAVELENGTHS_NM[channel];
    (ior + (ior - 1.0) * (dispersion / 20.0) * (523_655.0 / (wavelength * wavelength) - 1.5168)).max(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Abbe number is (n_d − 1) / (n_F − n_C): the red and blue channels' indices span exactly that, and green's
    /// is the material's own.
    #[test]
    fn red_and_blue_span_the_abbe_number_and_green_is_the_materials_index() {
        for (ior, dispersion) in [(1.5f32, 0.33f32), (2.4, 0.36), (1.5, 2.0)] {
            let abbe = 20.0 / dispersion;
            let spread = dispersed_ior(ior, dispersion, 2) - dispersed_ior(ior, dispersion, 0);
            assert!((spread - (ior - 1.0) / abbe).abs() < 1e-4 * ior, "{ior}, {dispersion}: spread {spread}");
            assert!((dispersed_ior(ior, dispersion, 1) - ior).abs() < 1e-5, "{ior}, {dispersion}: green");
            assert_eq!(dispersed_ior(ior, 0.0, 0), ior);
        }
        // The index never falls below 1.
        assert_eq!(dispersed_ior(1.01, 200.0, 0), 1.0);
    }
}
