// Sample points as pure functions of (seed, pixel, sample index, dimension); GPU side of src/math/sampling.rs
// (tested equal). Cook, Porter and Carpenter (1984) regular / random / jittered, and Kensler's correlated
// multi-jittered sampling (2013), with strata of different dimensions and pixels paired by hash permutations.
#ifndef SAMPLING_GLSL
#define SAMPLING_GLSL
// Sampler kinds (SAMPLER_*) are shared constants.
#include "shared_constants.glsl"

// PCG RXS-M-XS (Jarzynski and Olano 2020).
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

uint sampling_key(uint seed, uint pixel, uint dimension) {
    return pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(dimension + 0x9e3779b9u)));
}

float unit_float(uint h) {
    return float(h >> 8u) * (1.0 / 16777216.0);
}

// Kensler's permutation of [0, l) chosen by p (CMJ, Listing 3).
uint sampling_permute(uint i, uint l, uint p) {
    if (l <= 1u) return 0u;
    uint w = l - 1u;
    w |= w >> 1u;
    w |= w >> 2u;
    w |= w >> 4u;
    w |= w >> 8u;
    w |= w >> 16u;
    for (;;) {
        i ^= p;
        i *= 0xe170893du;
        i ^= p >> 16u;
        i ^= (i & w) >> 4u;
        i ^= p >> 8u;
        i *= 0x0929eb3fu;
        i ^= p >> 23u;
        i ^= (i & w) >> 1u;
        i *= 1u | (p >> 27u);
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11u;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2u;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2u;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5u;
        if (i < l) return (i + p) % l;
    }
}

// Kensler's hash to [0, 1) (CMJ, Listing 4).
float sampling_randfloat(uint i, uint p) {
    i ^= p;
    i ^= i >> 17u;
    i ^= i >> 10u;
    i *= 0xb36534e5u;
    i ^= i >> 12u;
    i ^= i >> 21u;
    i *= 0x93fc4795u;
    i ^= 0xdf6e307fu;
    i ^= i >> 17u;
    i *= 1u | (p >> 18u);
    return min(float(i) * (1.0 / 4294967808.0), 1.0 - 5.96046448e-8);
}

// Owen scrambling by hashing (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)): a
// Laine-Karras-style permutation acts on bit-reversed values, each bit flipping depending only on the bits
// below it; Vegdahl's constants ("Building a Better LK Hash", 2021) randomise the high digits well.
uint laine_karras_permutation(uint x, uint seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16u) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

// The second dimension of Sobol's sequence (the first is the bit-reversed index): direction numbers from
// the primitive polynomial x + 1, v_0 = 1/2 and v_k = v_(k-1) xor v_(k-1)/2.
uint sobol_second_dimension(uint index) {
    uint v = 0x80000000u;
    uint result = 0u;
    for (uint bit = 0u; bit < 32u; bit++) {
        if ((index & (1u << bit)) != 0u) result ^= v;
        v ^= v >> 1u;
    }
    return result;
}

// Seeds of the two coordinates' scrambles, derived from the pair's key.
const uint SOBOL_X_SALT = 0x2545f491u;
const uint SOBOL_Y_SALT = 0x68e31da4u;

// Burley's sampler for one pair of dimensions: the index is shuffled by a nested uniform scramble (which keeps
// every power-of-two prefix a (0,m,2)-net) and each coordinate is Owen-scrambled with its own seed. Pairs of
// different dimensions or pixels get independent keys: that is the padding that decorrelates them.
// sobol_first is also the 1D sampler: an Owen-scrambled van der Corput sequence.
float sobol_first(uint key, uint shuffled) {
    return unit_float(nested_uniform_scramble(bitfieldReverse(shuffled), pcg_hash(key ^ SOBOL_X_SALT)));
}

vec2 sobol_2d(uint key, uint index) {
    uint i = nested_uniform_scramble(index, key);
    uint y = nested_uniform_scramble(sobol_second_dimension(i), pcg_hash(key ^ SOBOL_Y_SALT));
    return vec2(sobol_first(key, i), unit_float(y));
}

uint strata_per_side(uint count) {
    uint c = max(count, 1u);
    uint n = uint(sqrt(float(c)));
    while (n * n < c) n++;
    return max(n, 1u);
}

vec2 sample_2d(uint kind, uint seed, uint pixel, uint index, uint count, uint dimension) {
    count = max(count, 1u);
    uint k = sampling_key(seed, pixel, dimension);
    if (kind == SAMPLER_REGULAR) {
        uint n = strata_per_side(count);
        uint s = index % (n * n);
        return vec2((float(s % n) + 0.5) / float(n), (float(s / n) + 0.5) / float(n));
    }
    if (kind == SAMPLER_RANDOM) {
        uint h = pcg_hash(k ^ pcg_hash(index));
        return vec2(unit_float(h), unit_float(pcg_hash(h)));
    }
    if (kind == SAMPLER_SOBOL) return sobol_2d(k, index);
    if (kind == SAMPLER_JITTERED) {
        uint n = strata_per_side(count);
        uint s = sampling_permute(index % (n * n), n * n, k);
        uint h = pcg_hash(k ^ pcg_hash(index));
        return vec2((float(s % n) + unit_float(h)) / float(n), (float(s / n) + unit_float(pcg_hash(h))) / float(n));
    }
    // Correlated multi-jittered (Kensler 2013, Listing 5).
    uint m = strata_per_side(count);
    uint n = (count + m - 1u) / m;
    uint s = sampling_permute(index % (m * n), m * n, k * 0x51633e2du);
    uint sx = sampling_permute(s % m, m, k * 0xa511e9b3u);
    uint sy = sampling_permute(s / m, n, k * 0x63d83595u);
    float jx = sampling_randfloat(s, k * 0xa399d265u);
    float jy = sampling_randfloat(s, k * 0x711ad6a5u);
    return vec2((float(s % m) + (float(sy) + jx) / float(n)) / float(m),
                (float(s / m) + (float(sx) + jy) / float(m)) / float(n));
}

// Concentric mapping of the unit square onto the unit disk (Shirley and Chiu 1997); GPU side of
// math::lens::concentric_disk.
vec2 concentric_disk(vec2 u) {
    vec2 a = u * 2.0 - 1.0;
    if (a == vec2(0.0)) return vec2(0.0);
    const float QUARTER_PI = 0.78539816339744831;
    float r;
    float theta;
    if (abs(a.x) > abs(a.y)) {
        r = a.x;
        theta = QUARTER_PI * (a.y / a.x);
    } else {
        r = a.y;
        theta = 2.0 * QUARTER_PI - QUARTER_PI * (a.x / a.y);
    }
    return r * vec2(cos(theta), sin(theta));
}

float sample_1d(uint kind, uint seed, uint pixel, uint index, uint count, uint dimension) {
    count = max(count, 1u);
    uint k = sampling_key(seed, pixel, dimension);
    uint h = pcg_hash(k ^ pcg_hash(index));
    if (kind == SAMPLER_REGULAR) return (float(index % count) + 0.5) / float(count);
    if (kind == SAMPLER_RANDOM) return unit_float(h);
    if (kind == SAMPLER_SOBOL) return sobol_first(k, nested_uniform_scramble(index, k));
    return (float(sampling_permute(index % count, count, k)) + unit_float(h)) / float(count);
}
#endif
