// The accumulation pass's shading body, one for both ways to trace: distributed ray tracing (Cook, Porter and
// Carpenter 1984) on top of one G-buffer sample, or (PRIMARY_RAYS, the reference mode) of a primary ray traced
// per pixel through its own sub-pixel point and lens point. Per pixel: emission, direct light from one light
// sample chosen by power with a shadow ray (soft shadows), then a chain of up to max_depth vertices whose
// directions are perturbed around the ideal reflection or refraction by GGX (gloss, translucency), each with its
// own direct light; with `indirect` on, paths also go on by the diffuse lobe (cosine-weighted), which adds
// diffuse interreflection (Kajiya 1986). It traces only through trace_closest and trace_occluded (trace.glsl),
// which trace_query.glsl (compute, ray queries) or trace_pipeline.glsl (raygen, traceRayEXT) define: the same
// body in accumulate.comp and accumulate.rgen, as Q2RTX builds its path tracer both ways.
#ifndef PATH_TRACER_GLSL
#define PATH_TRACER_GLSL
#include "environment.glsl"
#include "fixed_point.glsl"
#include "ray_log.glsl"
#include "path_vertex.glsl"
#include "direct_light.glsl"
#include "surface.glsl"
#include "path.glsl"
#include "camera_ray.glsl"

// One path's value (its visible surface's light and its chain's) as the camera sample's mean takes it: a path
// that went wrong must not poison the pixel's whole estimate.
vec4 path_value(vec4 value) {
    return any(isnan(value)) || any(isinf(value)) ? vec4(0.0, 0.0, 0.0, value.w == value.w ? value.w : 0.0) : value;
}

// Adds a pixel's camera sample (the sum of its paths' values, `paths` of them) to its sum, as their mean in fixed
// point (the host zeroes the sums before a frame's first sample, or loads them from a checkpoint or a partial
// render). One value per camera sample, whatever pc.shading_samples is: the sums, their bounds and the
// resolve count camera samples.
void accumulate_sample(uvec2 pixel, vec4 paths_sum, uint paths) {
    vec4 value = paths == 1u ? paths_sum : paths_sum / float(paths);
    // For the tests' error estimates: the sample's squared luminance instead of its coverage.
    if (pc.alpha_moment != 0u) value.w = luminance(value.rgb) * luminance(value.rgb);
    uint i = pixel.y * pc.width + pixel.x;
    sums[i] += to_fixed_point(value);
}
#endif
