// The payload accumulate.rgen's rays carry to the hit group and the miss shader (trace_pipeline.glsl).
#ifndef TRACE_PAYLOAD_GLSL
#define TRACE_PAYLOAD_GLSL
struct TracePayload {
    // Written by the closest-hit or miss shader.
    int record;  // MISS for a miss
    uint primitive;
    vec2 barycentrics;
    float t;
    mat4x3 world_from_object;
    // Set by the raygen shader for the any-hit shader's alpha test: the ray cone (width at the origin, spread).
    vec2 cone;
};
#endif
