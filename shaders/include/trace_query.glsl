// trace.glsl's two calls with ray queries (GL_EXT_ray_query), for the accumulation pass's compute shader.
#ifndef TRACE_QUERY_GLSL
#define TRACE_QUERY_GLSL
#include "trace.glsl"

// Runs a ray query to its end, confirming the candidate triangles of alpha-tested geometry that cover their point
// (read through the ray's cone, alpha_covers).
void run_query(rayQueryEXT q, vec2 cone) {
    while (rayQueryProceedEXT(q)) {
        if (ALPHA_TESTED != 0u && rayQueryGetIntersectionTypeEXT(q, false) == gl_RayQueryCandidateIntersectionTriangleEXT &&
            alpha_covers(rayQueryGetIntersectionInstanceCustomIndexEXT(q, false) +
                             rayQueryGetIntersectionGeometryIndexEXT(q, false),
                         uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, false)),
                         rayQueryGetIntersectionBarycentricsEXT(q, false), rayQueryGetIntersectionTEXT(q, false),
                         rayQueryGetIntersectionObjectToWorldEXT(q, false), rayQueryGetWorldRayOriginEXT(q),
                         rayQueryGetWorldRayDirectionEXT(q), cone)) {
            rayQueryConfirmIntersectionEXT(q);
        }
    }
}

Hit trace_closest(vec3 origin, vec3 dir, float t_min, float t_max, vec2 cone, uint flags) {
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, TRACE_FLAGS | flags, 0xFF, origin, t_min, dir, t_max);
    run_query(q, cone);
    Hit h;
    h.record = MISS;
    // Committed fields are read only when something was committed (lavapipe dereferences null otherwise).
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        h.record = rayQueryGetIntersectionInstanceCustomIndexEXT(q, true) + rayQueryGetIntersectionGeometryIndexEXT(q, true);
        h.primitive = uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true));
        h.barycentrics = rayQueryGetIntersectionBarycentricsEXT(q, true);
        h.t = rayQueryGetIntersectionTEXT(q, true);
        h.world_from_object = rayQueryGetIntersectionObjectToWorldEXT(q, true);
    }
    return h;
}

bool trace_occluded(vec3 origin, vec3 dir, float t_max) {
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, TRACE_FLAGS | gl_RayFlagsTerminateOnFirstHitEXT, 0xFF, origin, 0.0, dir, t_max);
    run_query(q, vec2(0.0));
    return rayQueryGetIntersectionTypeEXT(q, true) != gl_RayQueryCommittedIntersectionNoneEXT;
}
#endif
