#version 460
// The accumulation pipeline's closest-hit shader: it records where the ray met which triangle, and shades nothing
// (path_tracer.glsl shades, in the raygen shader).
#extension GL_EXT_ray_tracing : require
#include "trace.glsl"
#include "trace_payload.glsl"

layout(location = 0) rayPayloadInEXT TracePayload payload;
hitAttributeEXT vec2 barycentrics;

void main() {
    payload.record = gl_InstanceCustomIndexEXT + gl_GeometryIndexEXT;
    payload.primitive = uint(gl_PrimitiveID);
    payload.barycentrics = barycentrics;
    payload.t = gl_HitTEXT;
    payload.world_from_object = gl_ObjectToWorldEXT;
}
