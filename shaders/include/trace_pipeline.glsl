// trace.glsl's two calls through a ray-tracing pipeline (GL_EXT_ray_tracing), for accumulate.rgen. The hit
// group's shaders only record: accumulate.rchit writes the hit into the payload, accumulate.rahit runs the alpha
// test, accumulate.rmiss marks a miss. The pipeline's recursion depth is 1: paths stay loops in the raygen shader.
#ifndef TRACE_PIPELINE_GLSL
#define TRACE_PIPELINE_GLSL
#include "trace.glsl"
#include "trace_payload.glsl"

layout(location = 0) rayPayloadEXT TracePayload payload;

Hit trace_closest(vec3 origin, vec3 dir, float t_min, float t_max, vec2 cone, uint flags) {
    payload.cone = cone;
    traceRayEXT(tlas, TRACE_FLAGS | flags, 0xFF, 0, 0, 0, origin, t_min, dir, t_max, 0);
    Hit h;
    h.record = payload.record;
    h.primitive = payload.primitive;
    h.barycentrics = payload.barycentrics;
    h.t = payload.t;
    h.world_from_object = payload.world_from_object;
    return h;
}

bool trace_occluded(vec3 origin, vec3 dir, float t_max) {
    // Any hit ends the ray, and the closest-hit shader is skipped: only the miss shader changes the record.
    payload.record = 0;
    payload.cone = vec2(0.0);
    traceRayEXT(tlas, TRACE_FLAGS | gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT, 0xFF, 0,
                0, 0, origin, 0.0, dir, t_max, 0);
    return payload.record != MISS;
}
#endif
