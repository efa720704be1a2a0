#version 460
// Casts one ray per invocation from a buffer of rays against the TLAS and records the closest hit:
// the ray-query smoke test, and the benchmark's bare ray-query ceiling (also replaying the rays a frame cast).
#extension GL_EXT_ray_query : require
#extension GL_EXT_scalar_block_layout : require

#include "shared_constants.glsl"

layout(local_size_x = PROBE_WORKGROUP_SIZE) in;

struct ProbeRay { vec3 origin; float t_min; vec3 direction; float t_max; uint flags; };  // flags besides opaque
struct ProbeHit { float t; int instance_custom_index; int instance_id; int primitive_id; };

layout(set = 0, binding = RAY_PROBE_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RAY_PROBE_BINDING_RAYS, scalar) readonly buffer Rays { ProbeRay rays[]; };
layout(set = 0, binding = RAY_PROBE_BINDING_HITS, scalar) writeonly buffer Hits { ProbeHit hits[]; };
layout(push_constant) uniform ProbePush { uint ray_count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.ray_count) return;
    ProbeRay r = rays[i];
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, gl_RayFlagsOpaqueEXT | r.flags, 0xFF, r.origin, r.t_min, r.direction, r.t_max);
    while (rayQueryProceedEXT(q)) {}
    ProbeHit h = ProbeHit(-1.0, -1, -1, -1);
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        h.t = rayQueryGetIntersectionTEXT(q, true);
        h.instance_custom_index = rayQueryGetIntersectionInstanceCustomIndexEXT(q, true);
        h.instance_id = rayQueryGetIntersectionInstanceIdEXT(q, true);
        h.primitive_id = rayQueryGetIntersectionPrimitiveIndexEXT(q, true);
    }
    hits[i] = h;
}
