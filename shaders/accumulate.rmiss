#version 460
// The accumulation pipeline's miss shader: the ray met nothing.
#extension GL_EXT_ray_tracing : require
#include "trace.glsl"
#include "trace_payload.glsl"

layout(location = 0) rayPayloadInEXT TracePayload payload;

void main() {
    payload.record = MISS;
}
