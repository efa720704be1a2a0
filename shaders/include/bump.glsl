// Blinn bump mapping (Blinn 1978) with a procedural height field; GPU side of src/math/bump.rs.
// N = Q_u x Q_v, n the shading normal, X = n x Q_v, Y = n x Q_u, D = B_u X - B_v Y,
// N' = normalize(n + sigma D / |N|), sigma = sign(n . N) so mirrored UVs keep bumps outward (docs/architecture.md).
#ifndef BUMP_GLSL
#define BUMP_GLSL
#include "noise.glsl"
// Kinds and derivative methods (BUMP_*) are shared constants.
#include "shared_constants.glsl"

// Mirrors `GpuBump` in src/render/gbuffer_layout.rs.
struct Bump {
    int kind;
    float amplitude;
    float frequency;
    uint octaves;
    float lacunarity;
    float gain;
    int derivative;
    float epsilon;
};

// The field at uv before the amplitude: value in w, gradient with respect to (u, v) in xy.
vec4 bump_field(Bump b, vec2 uv) {
    vec3 p = vec3(uv * b.frequency, 0.0);
    vec4 n;
    if (b.kind == BUMP_NOISE) {
        n = noise_with_gradient(p);
    } else if (b.kind == BUMP_FBM) {
        n = fbm_with_gradient(p, b.octaves, b.lacunarity, b.gain);
    } else if (b.kind == BUMP_TURBULENCE) {
        n = turbulence_with_gradient(p, b.octaves, b.lacunarity, b.gain);
    } else {
        const float TAU = 6.28318530717958647692;
        float phase = TAU * p.x;
        n = vec4(TAU * cos(phase), 0.0, 0.0, sin(phase));
    }
    return vec4(n.x * b.frequency, n.y * b.frequency, n.z * b.frequency, n.w);
}

// The field's value alone at uv before the amplitude: bump_field(b, uv).w, without the gradient's work.
float bump_field_value(Bump b, vec2 uv) {
    vec3 p = vec3(uv * b.frequency, 0.0);
    if (b.kind == BUMP_NOISE) return noise_value(p);
    if (b.kind == BUMP_FBM) return fbm_value(p, b.octaves, b.lacunarity, b.gain);
    if (b.kind == BUMP_TURBULENCE) return turbulence_value(p, b.octaves, b.lacunarity, b.gain);
    const float TAU = 6.28318530717958647692;
    return sin(TAU * p.x);
}

float bump_height(Bump b, vec2 uv) {
    return b.amplitude * bump_field_value(b, uv);
}

// (B_u, B_v) by central differences with step epsilon: four evaluations of the field's value.
vec2 bump_central_differences(Bump b, vec2 uv) {
    float e = b.epsilon;
    float du = bump_height(b, uv + vec2(e, 0.0)) - bump_height(b, uv - vec2(e, 0.0));
    float dv = bump_height(b, uv + vec2(0.0, e)) - bump_height(b, uv - vec2(0.0, e));
    return vec2(du, dv) / (2.0 * e);
}

// (B, B_u, B_v): the height and its gradient, by central differences (five field evaluations) or analytically
// (one).
vec3 bump_height_and_gradient(Bump b, vec2 uv) {
    if (b.derivative == BUMP_ANALYTIC) {
        vec4 f = bump_field(b, uv);
        return b.amplitude * vec3(f.w, f.xy);
    }
    return vec3(bump_height(b, uv), bump_central_differences(b, uv));
}

// (B_u, B_v) alone, for shading that never reads the height (ray hits): central differences skip B itself.
vec2 bump_gradient(Bump b, vec2 uv) {
    if (b.derivative == BUMP_ANALYTIC) return b.amplitude * bump_field(b, uv).xy;
    return bump_central_differences(b, uv);
}

// Blinn's perturbed normal; degenerate derivatives or a zero normal give the unperturbed normal, never NaN.
vec3 bump_perturb_normal(vec3 n, vec3 dpdu, vec3 dpdv, vec2 grad) {
    float n_len = length(n);
    if (!(n_len > 0.0)) return vec3(0.0);
    vec3 n_hat = n / n_len;
    vec3 big_n = cross(dpdu, dpdv);
    float len = length(big_n);
    if (isnan(len) || len <= 1e-12 || any(isnan(grad)) || any(isinf(grad))) return n_hat;
    float sigma = dot(n_hat, big_n) < 0.0 ? -1.0 : 1.0;
    vec3 x = cross(n_hat, dpdv);
    vec3 y = cross(n_hat, dpdu);
    vec3 d = x * grad.x - y * grad.y;
    vec3 bumped = n_hat + d * (sigma / len);
    float b_len = length(bumped);
    return b_len > 0.0 ? bumped / b_len : n_hat;
}
#endif
