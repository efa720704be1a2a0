// Perlin's improved gradient noise (Perlin 2002) with its analytic gradient, fBm and turbulence (Perlin 1985).
// GPU side of src/math/noise.rs: same lattice hash, gradients and operation order (tested equal within 1e-5).
#ifndef NOISE_GLSL
#define NOISE_GLSL

// Integer hash of a lattice cell in place of Perlin's permutation table (tables indexed per pixel are slow on
// SIMD CPU rasterizers such as lavapipe): lowbias32 (Wellons 2018), nested per axis. Mirrors lattice_hash().
uint noise_lowbias32(uint v) {
    v ^= v >> 16;
    v *= 0x7feb352du;
    v ^= v >> 15;
    v *= 0x846ca68bu;
    v ^= v >> 16;
    return v;
}

uint noise_lattice_hash(ivec3 c) {
    return noise_lowbias32(uint(c.x) + noise_lowbias32(uint(c.y) + noise_lowbias32(uint(c.z))));
}

// Perlin's 2002 grad() as a vector, with selects rather than a table: 12 cube edges, four repeated.
vec3 noise_gradient_at(uint hash) {
    uint h = hash & 15u;
    float su = (h & 1u) != 0u ? -1.0 : 1.0;
    float sv = (h & 2u) != 0u ? -1.0 : 1.0;
    bool v_is_x = h == 12u || h == 14u;
    return vec3(h < 8u ? su : (v_is_x ? sv : 0.0),
                h < 8u ? (h < 4u ? sv : 0.0) : su,
                h < 8u ? (h < 4u ? 0.0 : sv) : (v_is_x ? 0.0 : sv));
}

// Quintic fade 6t^5 - 15t^4 + 10t^3 and its derivative 30t^4 - 60t^3 + 30t^2.
vec2 noise_fade(float t) {
    return vec2(t * t * t * (t * (t * 6.0 - 15.0) + 10.0), 30.0 * t * t * (t * (t - 2.0) + 1.0));
}

// The trilinear blend of the corner values n0..n7 (corner i has offset bits x = i&1, y = i&2, z = i&4) as
// polynomial coefficients, so the gradient is exact; noise_with_gradient and noise_value share them, and so
// give the same value bits.
struct NoiseBlend {
    float k0, k1, k2, k3, k4, k5, k6, k7;
};

NoiseBlend noise_blend(float n0, float n1, float n2, float n3, float n4, float n5, float n6, float n7) {
    return NoiseBlend(n0, n1 - n0, n2 - n0, n4 - n0, n0 - n1 - n2 + n3, n0 - n2 - n4 + n6, n0 - n1 - n4 + n5,
                      -n0 + n1 + n2 - n3 + n4 - n5 - n6 + n7);
}

// The blend's value at the faded cell coordinates (u, v, w).
float noise_blend_value(NoiseBlend b, float u, float v, float w) {
    return b.k0 + b.k1 * u + b.k2 * v + b.k3 * w + b.k4 * u * v + b.k5 * v * w + b.k6 * w * u + b.k7 * u * v * w;
}

// Noise value in w, gradient in xyz. Zero at every integer lattice point.
vec4 noise_with_gradient(vec3 p) {
    vec3 cell = floor(p);
    ivec3 c = ivec3(cell);
    vec3 f = p - cell;
    vec2 fu = noise_fade(f.x), fv = noise_fade(f.y), fw = noise_fade(f.z);
    float u = fu.x, du = fu.y, v = fv.x, dv = fv.y, w = fw.x, dw = fw.y;
    // Corner i has offset bits x = i&1, y = i&2, z = i&4.
    vec3 g0 = noise_gradient_at(noise_lattice_hash(c + ivec3(0, 0, 0))), d0 = f;
    vec3 g1 = noise_gradient_at(noise_lattice_hash(c + ivec3(1, 0, 0))), d1 = f - vec3(1, 0, 0);
    vec3 g2 = noise_gradient_at(noise_lattice_hash(c + ivec3(0, 1, 0))), d2 = f - vec3(0, 1, 0);
    vec3 g3 = noise_gradient_at(noise_lattice_hash(c + ivec3(1, 1, 0))), d3 = f - vec3(1, 1, 0);
    vec3 g4 = noise_gradient_at(noise_lattice_hash(c + ivec3(0, 0, 1))), d4 = f - vec3(0, 0, 1);
    vec3 g5 = noise_gradient_at(noise_lattice_hash(c + ivec3(1, 0, 1))), d5 = f - vec3(1, 0, 1);
    vec3 g6 = noise_gradient_at(noise_lattice_hash(c + ivec3(0, 1, 1))), d6 = f - vec3(0, 1, 1);
    vec3 g7 = noise_gradient_at(noise_lattice_hash(c + ivec3(1, 1, 1))), d7 = f - vec3(1, 1, 1);
    float n0 = dot(g0, d0), n1 = dot(g1, d1), n2 = dot(g2, d2), n3 = dot(g3, d3);
    float n4 = dot(g4, d4), n5 = dot(g5, d5), n6 = dot(g6, d6), n7 = dot(g7, d7);
    NoiseBlend b = noise_blend(n0, n1, n2, n3, n4, n5, n6, n7);
    float value = noise_blend_value(b, u, v, w);
    vec3 blended = g0
        + (g1 - g0) * u
        + (g2 - g0) * v
        + (g4 - g0) * w
        + (g0 - g1 - g2 + g3) * (u * v)
        + (g0 - g2 - g4 + g6) * (v * w)
        + (g0 - g1 - g4 + g5) * (w * u)
        + (-g0 + g1 + g2 - g3 + g4 - g5 - g6 + g7) * (u * v * w);
    vec3 weights = vec3(
        du * (b.k1 + b.k4 * v + b.k6 * w + b.k7 * v * w),
        dv * (b.k2 + b.k4 * u + b.k5 * w + b.k7 * u * w),
        dw * (b.k3 + b.k5 * v + b.k6 * u + b.k7 * u * v));
    return vec4(blended + weights, value);
}

// The noise value alone: noise_with_gradient's value by the same operations (so the same bits), without the
// gradient's blends, for callers that difference values (central-difference bump mapping evaluates four).
float noise_value(vec3 p) {
    vec3 cell = floor(p);
    ivec3 c = ivec3(cell);
    vec3 f = p - cell;
    float u = noise_fade(f.x).x, v = noise_fade(f.y).x, w = noise_fade(f.z).x;
    float n0 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(0, 0, 0))), f);
    float n1 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(1, 0, 0))), f - vec3(1, 0, 0));
    float n2 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(0, 1, 0))), f - vec3(0, 1, 0));
    float n3 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(1, 1, 0))), f - vec3(1, 1, 0));
    float n4 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(0, 0, 1))), f - vec3(0, 0, 1));
    float n5 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(1, 0, 1))), f - vec3(1, 0, 1));
    float n6 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(0, 1, 1))), f - vec3(0, 1, 1));
    float n7 = dot(noise_gradient_at(noise_lattice_hash(c + ivec3(1, 1, 1))), f - vec3(1, 1, 1));
    return noise_blend_value(noise_blend(n0, n1, n2, n3, n4, n5, n6, n7), u, v, w);
}

// The sum of gain^i * noise(lacunarity^i * p), each octave's noise taken as |noise| when `absolute`, added to
// `start`: the values of fbm_with_gradient and turbulence_with_gradient by the same operations, and from a start of
// -0.0 with one octave noise_value itself, bit for bit (-0.0 + x is x for every x; 0.0 + -0.0 is +0.0).
float octave_sum_value(vec3 p, uint octaves, float lacunarity, float gain, bool absolute, float start) {
    float sum = start;
    float amplitude = 1.0, frequency = 1.0;
    for (uint i = 0u; i < octaves; ++i) {
        float n = noise_value(p * frequency);
        sum += (absolute ? abs(n) : n) * amplitude;
        amplitude *= gain;
        frequency *= lacunarity;
    }
    return sum;
}

float fbm_value(vec3 p, uint octaves, float lacunarity, float gain) {
    return octave_sum_value(p, octaves, lacunarity, gain, false, 0.0);
}

float turbulence_value(vec3 p, uint octaves, float lacunarity, float gain) {
    return octave_sum_value(p, octaves, lacunarity, gain, true, 0.0);
}

// The octave sum with its gradient (value in w, gradient in xyz): each octave's noise and gradient turned by the
// noise's sign when `absolute` (|noise| has gradient sign(noise) * gradient), added to `start`. From a start of
// -0.0 with one octave it is noise_with_gradient itself, bit for bit (as octave_sum_value). Callers that choose
// among plain noise, fBm and turbulence at run time call this once: a driver inlines every call site, and three
// copies of the noise made most of the shading code (docs/performance.md, "One noise call site").
vec4 octave_sum_with_gradient(vec3 p, uint octaves, float lacunarity, float gain, bool absolute, vec4 start) {
    vec4 sum = start;
    float amplitude = 1.0, frequency = 1.0;
    for (uint i = 0u; i < octaves; ++i) {
        vec4 n = noise_with_gradient(p * frequency);
        float s = absolute && n.w < 0.0 ? -1.0 : 1.0;
        sum += vec4(s * n.x * frequency, s * n.y * frequency, s * n.z * frequency, absolute ? abs(n.w) : n.w)
            * amplitude;
        amplitude *= gain;
        frequency *= lacunarity;
    }
    return sum;
}

// fBm: sum of gain^i * noise(lacunarity^i * p), value in w, gradient in xyz.
vec4 fbm_with_gradient(vec3 p, uint octaves, float lacunarity, float gain) {
    return octave_sum_with_gradient(p, octaves, lacunarity, gain, false, vec4(0.0));
}

// Turbulence: sum of gain^i * |noise(lacunarity^i * p)| (Perlin 1985), value in w, gradient in xyz.
vec4 turbulence_with_gradient(vec3 p, uint octaves, float lacunarity, float gain) {
    return octave_sum_with_gradient(p, octaves, lacunarity, gain, true, vec4(0.0));
}

#endif
