// KHR_materials_dispersion: a transmissive material's index of refraction by wavelength, by the extension's two
// terms of Cauchy's equation through the material's IOR at λ_d = 587.56 nm: n(λ) = max(n_d + (n_d − 1) / V_d ·
// (523655 / λ² − 1.5168), 1), V_d = 20 / dispersion. The colour channels take the Fraunhofer lines the Abbe
// number is defined by: C (656.27 nm) for red, d for green, F (486.13 nm) for blue, so n_F − n_C = (n_d − 1) / V_d.
// A path that meets a dispersive transmissive surface picks one channel for the rest of its way, uniformly, and
// carries 3 on that channel and 0 on the others (an unbiased estimate of each channel's own path, as spectral
// renderers' hero wavelengths); every dispersive surface it meets then refracts by that channel's index.
// The CPU twin is math::dispersion.
#ifndef DISPERSION_GLSL
#define DISPERSION_GLSL

// A path's channel before it has met a dispersive surface: all three travel together.
const uint ALL_CHANNELS = 3u;

float dispersed_ior(float ior, float dispersion, uint channel) {
    float wavelength = channel == 0u ? 656.27 : (channel == 1u ? 587.56 : 486.13);
    return max(ior + (ior - 1.0) * (dispersion / 20.0) * (523655.0 / (wavelength * wavelength) - 1.5168), 1.0);
}

#endif
