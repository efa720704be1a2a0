#version 460
// The resolve pass: the fixed-point sum of N samples (fixed_point.glsl) becomes the pixel estimate R = (1/N) Σ I
// (linear radiance, for EXR), then exposure, a tone map (clamp, or Narkowicz's 2015 fit of the ACES filmic curve)
// and the sRGB encoding (IEC 61966-2-1) into an 8-bit image for PNG.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_scalar_block_layout : require
#include "shared_constants.glsl"
#include "fixed_point.glsl"

layout(local_size_x = RESOLVE_TILE_SIZE, local_size_y = RESOLVE_TILE_SIZE) in;

layout(set = 0, binding = RESOLVE_BINDING_ACCUMULATION, rgba32f) uniform writeonly image2D accumulation;
layout(set = 0, binding = RESOLVE_BINDING_DISPLAY, rgba8) uniform writeonly image2D display;
layout(set = 0, binding = RESOLVE_BINDING_SUMS, std430) readonly buffer Sums { u64vec4 sums[]; };

layout(push_constant, std430) uniform ResolvePush {
    uint width;
    uint height;
    uint samples;      // N, what the sums hold
    float exposure_scale;
    uint tone_map;
    uint transparent;  // 1: keep coverage in alpha, colour unpremultiplied (straight alpha, as PNG stores it)
} pc;

vec3 aces_fit(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 srgb_encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (gl_GlobalInvocationID.x >= pc.width || gl_GlobalInvocationID.y >= pc.height) return;
    vec4 mean = fixed_point_mean(sums[gl_GlobalInvocationID.y * pc.width + gl_GlobalInvocationID.x], pc.samples);
    imageStore(accumulation, p, mean);
    // With a transparent background the accumulated colour is premultiplied by coverage (samples that missed
    // added nothing): the display divides it out, so that compositing the PNG over a background brings it back.
    float alpha = pc.transparent != 0u ? clamp(mean.a, 0.0, 1.0) : 1.0;
    vec3 colour = pc.transparent != 0u ? (mean.a > 0.0 ? mean.rgb / mean.a : vec3(0.0)) : mean.rgb;
    vec3 c = max(colour * pc.exposure_scale, vec3(0.0));
    c = pc.tone_map == 1u ? aces_fit(c) : clamp(c, 0.0, 1.0);
    imageStore(display, p, vec4(srgb_encode(c), alpha));
}
