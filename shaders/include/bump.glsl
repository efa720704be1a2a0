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

// Whether the field is an octave sum of noise (plain noise is one octave); otherwise it is the sine.
bool bump_is_noise(Bump b) {
    return b.kind == BUMP_NOISE || b.kind == BUMP_FBM || b.kind == BUMP_TURBULENCE;
}

// The field at uv before the amplitude: value in w, gradient with respect to (u, v) in xy. Plain noise, fBm and
// turbulence go through one octave sum (plain noise: one octave from -0.0, the noise's own bits), so the noise is
// inlined once.
vec4 bump_field(Bump b, vec2 uv) {
    vec3 p = vec3(uv * b.frequency, 0.0);
    vec4 n;
    if (bump_is_noise(b)) {
        bool plain = b.kind == BUMP_NOISE;
        n = octave_sum_with_gradient(p, plain ? 1u : b.octaves, b.lacunarity, b.gain, b.kind == BUMP_TURBULENCE,
                                     vec4(plain ? -0.0 : 0.0));
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
    if (bump_is_noise(b)) {
        bool plain = b.kind == BUMP_NOISE;
        return octave_sum_value(p, plain ? 1u : b.octaves, b.lacunarity, b.gain, b.kind == BUMP_TURBULENCE,
                                plain ? -0.0 : 0.0);
    }
    const float TAU = 6.28318530717958647692;
    return sin(TAU * p.x);
}

// The field's values before the amplitude at uv (k = 0) and around it for central differences with step epsilon:
// uv + (e, 0), uv - (e, 0), uv + (0, e), uv - (0, e) (k = 1..4, in `around`), from k = `first`. One loop rather
// than five calls, so the field's code is inlined once (docs/performance.md, "One noise call site").
void bump_field_values(Bump b, vec2 uv, uint first, out float at_uv, out vec4 around) {
    float e = b.epsilon;
    at_uv = 0.0;
    around = vec4(0.0);
    for (uint k = first; k < 5u; k++) {
        vec2 d = k < 3u ? vec2(e, 0.0) : vec2(0.0, e);
        float f = bump_field_value(b, k == 0u ? uv : ((k & 1u) == 1u ? uv + d : uv - d));
        at_uv = k == 0u ? f : at_uv;
        around = vec4(k == 1u ? f : around.x, k == 2u ? f : around.y, k == 3u ? f : around.z,
                      k == 4u ? f : around.w);
    }
}

// (B_u, B_v) by central differences with step epsilon from the field's values around the point.
vec2 bump_central_differences(Bump b, vec4 around) {
    float du = b.amplitude * around.x - b.amplitude * around.y;
    float dv = b.amplitude * around.z - b.amplitude * around.w;
    return vec2(du, dv) / (2.0 * b.epsilon);
}

// (B, B_u, B_v): the height and its gradient, by central differences (five field evaluations) or analytically
// (one).
vec3 bump_height_and_gradient(Bump b, vec2 uv) {
    if (b.derivative == BUMP_ANALYTIC) {
        vec4 f = bump_field(b, uv);
        return b.amplitude * vec3(f.w, f.xy);
    }
    float at_uv;
    vec4 around;
    bump_field_values(b, uv, 0u, at_uv, around);
    return vec3(b.amplitude * at_uv, bump_central_differences(b, around));
}

// (B_u, B_v) alone, for shading that never reads the height (ray hits): central differences skip B itself.
vec2 bump_gradient(Bump b, vec2 uv) {
    if (b.derivative == BUMP_ANALYTIC) return b.amplitude * bump_field(b, uv).xy;
    float at_uv;
    vec4 around;
    bump_field_values(b, uv, 1u, at_uv, around);
    return bump_central_differences(b, around);
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
