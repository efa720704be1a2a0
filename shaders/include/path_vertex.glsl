// What every vertex of a path uses: its sampler dimensions, the Surface it shades, and its shadow rays. Part of
// the accumulation pass's shading body (path_tracer.glsl).
#ifndef PATH_VERTEX_GLSL
#define PATH_VERTEX_GLSL
#include "ray_log.glsl"
#include "shared_constants.glsl"

// Sampler dimensions: the camera's (DIM_PIXEL, DIM_TIME, DIM_LENS) and DIM_FIRST_VERTEX are shared constants.
// Each vertex of a path draws from its own four, from DIM_FIRST_VERTEX + DIMS_PER_VERTEX · depth on:
const uint VERTEX_LIGHT = 0u;            // which light (by power) and where on it (2D; direct_light.glsl)
const uint VERTEX_ROULETTE = 1u;         // whether a weak path goes on (Russian roulette)
const uint VERTEX_LOBE_CHOICE = 2u;      // diffuse or specular lobe, reflection or refraction
const uint VERTEX_LOBE_DIRECTION = 3u;   // the direction within the lobe (2D)
const uint DIMS_PER_VERTEX = 4u;

struct Surface {
    float emitter_density;  // π · luminance · sides of an emitter that light sampling covers, else 0
    vec3 position;
    vec3 normal;     // shading normal, on the side of the incoming ray
    vec3 geometric;  // face normal, same side
    vec3 emission;
    bool inside;     // the incoming ray travels inside the material
    vec3 absorption; // σ per metre inside the material (KHR_materials_volume)
    float dispersion; // 20 / V_d (KHR_materials_dispersion; dispersion.glsl), 0: none
    Shading m;
};

// Which of the frame's paths this invocation shades: camera sample pc.sample_index traces pc.shading_samples paths
// from its visible surface, path k being number sample_index · shading_samples + k of sample_count ·
// shading_samples. The path's own dimensions (lights, lobes, roulette) are stratified over all of them; the
// camera's (pixel jitter, lens) over the camera samples, as the host draws them for the G-buffer. Set by
// begin_path before each path.
uint path_index = 0u;
uint path_count = 1u;

void begin_path(uint k) {
    path_index = pc.sample_index * pc.shading_samples + k;
    path_count = pc.sample_count * pc.shading_samples;
}

vec2 sample2(uint pixel, uint dim) {
    return sample_2d(pc.sampler_kind, pc.seed, pixel, path_index, path_count, dim);
}

float sample1(uint pixel, uint dim) {
    return sample_1d(pc.sampler_kind, pc.seed, pixel, path_index, path_count, dim);
}

// The camera's dimensions (DIM_PIXEL, DIM_LENS): one point per camera sample, shared by its paths.
vec2 camera_sample2(uint pixel, uint dim) {
    return sample_2d(pc.sampler_kind, pc.seed, pixel, pc.sample_index, pc.sample_count, dim);
}

// A ray origin just off the surface on the side the ray leaves towards (scaled to the position's magnitude).
vec3 offset_origin(vec3 p, vec3 ng, vec3 dir) {
    float eps = 1e-4 * (1.0 + max(max(abs(p.x), abs(p.y)), abs(p.z)));
    return p + ng * (dot(ng, dir) >= 0.0 ? eps : -eps);
}

bool occluded(vec3 o, vec3 d, float t_max) {
    if (t_max <= 0.0 || (pc.sabotage & SABOTAGE_NO_SHADOW_RAYS) != 0u) return false;
    log_ray(gl_RayFlagsTerminateOnFirstHitEXT, o, 0.0, d, t_max);
    return trace_occluded(o, d, t_max);
}

#endif
