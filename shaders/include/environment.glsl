// Environment lighting: radiance from infinitely far away as an equirectangular image (src/scene/environment.rs
// for the mapping of directions), importance-sampled by a 2D piecewise-constant distribution proportional to
// luminance × sin θ: a row by the marginal CDF, then a column by the row's conditional CDF (Pharr, Jakob and
// Humphreys, Physically Based Rendering, 4th ed., §A.5.3, §12.5.2). The CPU twin is src/math/environment.rs;
// src/render/environment.rs lays the buffer out. Include after accumulate_bindings.glsl.
#ifndef ENVIRONMENT_GLSL
#define ENVIRONMENT_GLSL

const uint ENV_HEADER = 0u;  // env_data starts after the header

bool environment_present() {
    return HAS_ENVIRONMENT != 0u && env_present != 0u;
}

uint env_texel_offset(uint column, uint row) {
    return 4u * (row * env_width + column);
}

uint env_marginal_offset() {
    return 4u * env_width * env_height;
}

uint env_conditional_offset(uint row) {
    return env_marginal_offset() + env_height + 1u + row * (env_width + 1u);
}

// A world direction in the image's frame: the rotation about +Y undone (params.x = cos, .y = sin).
vec3 env_to_local(vec3 d) {
    float c = env_params.x;
    float s = -env_params.y;
    return vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

vec3 env_to_world(vec3 d) {
    float c = env_params.x;
    float s = env_params.y;
    return vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

vec2 env_direction_to_uv(vec3 d) {
    float theta = acos(clamp(d.y, -1.0, 1.0));
    float phi = atan(d.x, -d.z);
    float u = 0.5 + phi / (2.0 * PI);
    return vec2(u - floor(u), theta / PI);
}

vec3 env_uv_to_direction(vec2 uv) {
    float phi = 2.0 * PI * (uv.x - 0.5);
    float theta = PI * uv.y;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

uvec2 env_texel_of(vec2 uv) {
    return uvec2(min(uint(uv.x * float(env_width)), env_width - 1u), min(uint(uv.y * float(env_height)), env_height - 1u));
}

// The radiance arriving from world direction d: the texel it falls in, times the intensity.
vec3 environment_radiance(vec3 d) {
    uvec2 t = env_texel_of(env_direction_to_uv(env_to_local(d)));
    uint o = env_texel_offset(t.x, t.y);
    return vec3(env_data[o], env_data[o + 1u], env_data[o + 2u]) * env_params.z;
}

// The largest i in 0..n with cdf[offset + i] <= u, moved past empty intervals (find_interval in the twin).
uint env_find_interval(uint offset, uint n, float u) {
    uint lo = 0u;
    uint hi = n;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) / 2u;
        if (env_data[offset + mid] <= u) lo = mid; else hi = mid;
    }
    while (lo + 1u < n && env_data[offset + lo + 1u] - env_data[offset + lo] <= 0.0) lo++;
    return lo;
}

// The density in solid angle with which environment_sample picks world direction d.
float environment_pdf(vec3 d) {
    if (env_uniform != 0u) return 1.0 / (4.0 * PI);
    vec2 uv = env_direction_to_uv(env_to_local(d));
    float sin_theta = sin(PI * uv.y);
    if (sin_theta <= 0.0) return 0.0;
    uvec2 t = env_texel_of(uv);
    uint m = env_marginal_offset();
    uint c = env_conditional_offset(t.y);
    float p = (env_data[m + t.y + 1u] - env_data[m + t.y]) * (env_data[c + t.x + 1u] - env_data[c + t.x]);
    return p * float(env_width * env_height) / (2.0 * PI * PI * sin_theta);
}

// A world direction drawn from the distribution with uniform numbers xi, and its solid-angle density.
vec3 environment_sample(vec2 xi, out float pdf) {
    if (env_uniform != 0u) {
        float z = 1.0 - 2.0 * xi.x;
        float r = sqrt(max(0.0, 1.0 - z * z));
        float phi = 2.0 * PI * xi.y;
        pdf = 1.0 / (4.0 * PI);
        return vec3(r * cos(phi), r * sin(phi), z);
    }
    uint m = env_marginal_offset();
    uint row = env_find_interval(m, env_height, xi.y);
    float p_row = env_data[m + row + 1u] - env_data[m + row];
    float dv = p_row > 0.0 ? clamp((xi.y - env_data[m + row]) / p_row, 0.0, 1.0) : 0.5;
    uint c = env_conditional_offset(row);
    uint column = env_find_interval(c, env_width, xi.x);
    float p_column = env_data[c + column + 1u] - env_data[c + column];
    float du = p_column > 0.0 ? clamp((xi.x - env_data[c + column]) / p_column, 0.0, 1.0) : 0.5;
    vec2 uv = vec2((float(column) + du) / float(env_width), (float(row) + dv) / float(env_height));
    float sin_theta = sin(PI * uv.y);
    pdf = sin_theta > 0.0 ? p_row * p_column * float(env_width * env_height) / (2.0 * PI * PI * sin_theta) : 0.0;
    return env_to_world(env_uv_to_direction(uv));
}
#endif
