// Perlin's improved gradient noise (Perlin 2002) with its analytic gradient, fBm and turbulence (Perlin 1985).
// GPU side of src/math/noise.rs: same permutation, gradients and operation order (tested equal within 1e-5).
#ifndef NOISE_GLSL
#define NOISE_GLSL

const int NOISE_PERMUTATION[256] = int[256](
    151,160,137,91,90,15,131,13,201,95,96,53,194,233,7,225,140,36,103,30,69,142,8,99,37,240,21,10,23,190,6,148,
    247,120,234,75,0,26,197,62,94,252,219,203,117,35,11,32,57,177,33,88,237,149,56,87,174,20,125,136,171,168,68,175,
    74,165,71,134,139,48,27,166,77,146,158,231,83,111,229,122,60,211,133,230,220,105,92,41,55,46,245,40,244,102,143,54,
    65,25,63,161,1,216,80,73,209,76,132,187,208,89,18,169,200,196,135,130,116,188,159,86,164,100,109,198,173,186,3,64,
    52,217,226,250,124,123,5,202,38,147,118,126,255,82,85,212,207,206,59,227,47,16,58,17,182,189,28,42,223,183,170,213,
    119,248,152,2,44,154,163,70,221,153,101,155,167,43,172,9,129,22,39,253,19,98,108,110,79,113,224,232,178,185,112,104,
    218,246,97,228,251,34,242,193,238,210,144,12,191,179,162,241,81,51,145,235,249,14,239,107,49,192,214,31,181,199,106,157,
    184,84,204,176,115,121,50,45,127,4,150,254,138,236,205,93,222,114,67,29,24,72,243,141,128,195,78,66,215,61,156,180
);

int noise_perm(int i) { return NOISE_PERMUTATION[i & 255]; }

// The 12 cube-edge gradients, picked by the low 4 bits of the hash (16 cases, four repeated).
const vec3 NOISE_GRADIENTS[16] = vec3[16](
    vec3(1, 1, 0), vec3(-1, 1, 0), vec3(1, -1, 0), vec3(-1, -1, 0),
    vec3(1, 0, 1), vec3(-1, 0, 1), vec3(1, 0, -1), vec3(-1, 0, -1),
    vec3(0, 1, 1), vec3(0, -1, 1), vec3(0, 1, -1), vec3(0, -1, -1),
    vec3(1, 1, 0), vec3(0, -1, 1), vec3(-1, 1, 0), vec3(0, -1, -1));

vec3 noise_gradient_at(int hash) { return NOISE_GRADIENTS[hash & 15]; }

// Quintic fade 6t^5 - 15t^4 + 10t^3 and its derivative 30t^4 - 60t^3 + 30t^2.
vec2 noise_fade(float t) {
    return vec2(t * t * t * (t * (t * 6.0 - 15.0) + 10.0), 30.0 * t * t * (t * (t - 2.0) + 1.0));
}

// Noise value in w, gradient in xyz. Zero at every integer lattice point.
vec4 noise_with_gradient(vec3 p) {
    vec3 cell = floor(p);
    int xi = int(cell.x), yi = int(cell.y), zi = int(cell.z);
    vec3 f = p - cell;
    vec2 fu = noise_fade(f.x), fv = noise_fade(f.y), fw = noise_fade(f.z);
    float u = fu.x, du = fu.y, v = fv.x, dv = fv.y, w = fw.x, dw = fw.y;
    int a = noise_perm(xi) + yi;
    int aa = noise_perm(a) + zi, ab = noise_perm(a + 1) + zi;
    int b = noise_perm(xi + 1) + yi;
    int ba = noise_perm(b) + zi, bb = noise_perm(b + 1) + zi;
    vec3 g0 = noise_gradient_at(noise_perm(aa)),     d0 = f;
    vec3 g1 = noise_gradient_at(noise_perm(ba)),     d1 = f - vec3(1, 0, 0);
    vec3 g2 = noise_gradient_at(noise_perm(ab)),     d2 = f - vec3(0, 1, 0);
    vec3 g3 = noise_gradient_at(noise_perm(bb)),     d3 = f - vec3(1, 1, 0);
    vec3 g4 = noise_gradient_at(noise_perm(aa + 1)), d4 = f - vec3(0, 0, 1);
    vec3 g5 = noise_gradient_at(noise_perm(ba + 1)), d5 = f - vec3(1, 0, 1);
    vec3 g6 = noise_gradient_at(noise_perm(ab + 1)), d6 = f - vec3(0, 1, 1);
    vec3 g7 = noise_gradient_at(noise_perm(bb + 1)), d7 = f - vec3(1, 1, 1);
    float n0 = dot(g0, d0), n1 = dot(g1, d1), n2 = dot(g2, d2), n3 = dot(g3, d3);
    float n4 = dot(g4, d4), n5 = dot(g5, d5), n6 = dot(g6, d6), n7 = dot(g7, d7);
    // Trilinear blend as polynomial coefficients, so the gradient is exact.
    float k0 = n0;
    float k1 = n1 - n0;
    float k2 = n2 - n0;
    float k3 = n4 - n0;
    float k4 = n0 - n1 - n2 + n3;
    float k5 = n0 - n2 - n4 + n6;
    float k6 = n0 - n1 - n4 + n5;
    float k7 = -n0 + n1 + n2 - n3 + n4 - n5 - n6 + n7;
    float value = k0 + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w;
    vec3 blended = g0
        + (g1 - g0) * u
        + (g2 - g0) * v
        + (g4 - g0) * w
        + (g0 - g1 - g2 + g3) * (u * v)
        + (g0 - g2 - g4 + g6) * (v * w)
        + (g0 - g1 - g4 + g5) * (w * u)
        + (-g0 + g1 + g2 - g3 + g4 - g5 - g6 + g7) * (u * v * w);
    vec3 weights = vec3(
        du * (k1 + k4 * v + k6 * w + k7 * v * w),
        dv * (k2 + k4 * u + k5 * w + k7 * u * w),
        dw * (k3 + k5 * v + k6 * u + k7 * u * v));
    return vec4(blended + weights, value);
}

// fBm: sum of gain^i * noise(lacunarity^i * p), value in w, gradient in xyz.
vec4 fbm_with_gradient(vec3 p, uint octaves, float lacunarity, float gain) {
    vec4 sum = vec4(0.0);
    float amplitude = 1.0, frequency = 1.0;
    for (uint i = 0u; i < octaves; ++i) {
        vec4 n = noise_with_gradient(p * frequency);
        sum += vec4(n.x * frequency, n.y * frequency, n.z * frequency, n.w) * amplitude;
        amplitude *= gain;
        frequency *= lacunarity;
    }
    return sum;
}

// Turbulence: sum of gain^i * |noise(lacunarity^i * p)| (Perlin 1985), value in w, gradient in xyz.
vec4 turbulence_with_gradient(vec3 p, uint octaves, float lacunarity, float gain) {
    vec4 sum = vec4(0.0);
    float amplitude = 1.0, frequency = 1.0;
    for (uint i = 0u; i < octaves; ++i) {
        vec4 n = noise_with_gradient(p * frequency);
        float s = n.w < 0.0 ? -1.0 : 1.0;
        sum += vec4(s * n.x * frequency, s * n.y * frequency, s * n.z * frequency, abs(n.w)) * amplitude;
        amplitude *= gain;
        frequency *= lacunarity;
    }
    return sum;
}

#endif
