#version 460
// Evaluates noise, fBm and turbulence with gradients, and their value-only forms, at points from a buffer: the
// GPU side of the noise twin test (src/math/noise.rs).
#extension GL_EXT_scalar_block_layout : require
#include "noise.glsl"
#include "shared_constants.glsl"

layout(local_size_x = PROBE_WORKGROUP_SIZE) in;

layout(set = 0, binding = NOISE_PROBE_BINDING_POINTS, scalar) readonly buffer Points { vec4 points[]; };
// Four results per point: noise, fBm, turbulence (value in w, gradient in xyz), then the three value-only
// functions' results in xyz.
layout(set = 0, binding = NOISE_PROBE_BINDING_RESULTS, scalar) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform NoiseProbePush {
    uint count;
    uint octaves;
    float lacunarity;
    float gain;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    vec3 p = points[i].xyz;
    results[4 * i + 0] = noise_with_gradient(p);
    results[4 * i + 1] = fbm_with_gradient(p, pc.octaves, pc.lacunarity, pc.gain);
    results[4 * i + 2] = turbulence_with_gradient(p, pc.octaves, pc.lacunarity, pc.gain);
    results[4 * i + 3] = vec4(noise_value(p), fbm_value(p, pc.octaves, pc.lacunarity, pc.gain),
                              turbulence_value(p, pc.octaves, pc.lacunarity, pc.gain), 0.0);
}
