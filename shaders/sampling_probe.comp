#version 460
// Evaluates sample_2d (dimensions 0 and 1) and sample_1d (dimension 2) for every (pixel, sample index):
// the GPU side of the sampler twin test (src/math/sampling.rs).
#extension GL_EXT_scalar_block_layout : require
#include "sampling.glsl"
#include "shared_constants.glsl"

layout(local_size_x = PROBE_WORKGROUP_SIZE) in;
layout(set = 0, binding = SAMPLING_PROBE_BINDING_RESULTS, scalar) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform SamplingProbePush {
    uint kind;
    uint seed;
    uint count;
    uint pixels;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count * pc.pixels) return;
    uint pixel = i / pc.count, index = i % pc.count;
    vec2 a = sample_2d(pc.kind, pc.seed, pixel, index, pc.count, 0u);
    vec2 b = sample_2d(pc.kind, pc.seed, pixel, index, pc.count, 1u);
    float t = sample_1d(pc.kind, pc.seed, pixel, index, pc.count, 2u);
    results[2u * i] = vec4(a, b);
    results[2u * i + 1u] = vec4(t, 0.0, 0.0, 0.0);
}
