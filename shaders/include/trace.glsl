// The contract between the shading body (path_tracer.glsl) and the two ways to trace a ray: the body calls only
//   Hit trace_closest(vec3 origin, vec3 dir, float t_min, float t_max, vec2 cone, uint flags)
//   bool trace_occluded(vec3 origin, vec3 dir, float t_max)
// which trace_query.glsl defines with ray queries and trace_pipeline.glsl with traceRayEXT (nvpro-samples
// vk_raytrace: traceray_rq.glsl / traceray_rtx.glsl). Both test alpha cut-outs with alpha_covers (hit_geometry.glsl)
// through the ray's cone, and neither shades: a hit is only where the ray met which triangle. `flags` adds ray flags
// to the ray's own (gl_RayFlagsOpaqueEXT: no alpha test).
#ifndef TRACE_GLSL
#define TRACE_GLSL

// The record a miss carries instead of a primitive record's index.
const int MISS = -1;

struct Hit {
    int record;        // the primitive record (instance custom index + geometry index), or MISS
    uint primitive;    // the triangle within it
    vec2 barycentrics;  // of its second and third vertices
    float t;
    mat4x3 world_from_object;
};
#endif
