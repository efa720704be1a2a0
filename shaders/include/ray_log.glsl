// The rays a sample casts, logged for the benchmark's probe (render::ray_log). Part of the accumulation pass's
// shading body (path_tracer.glsl), which includes it.
#ifndef RAY_LOG_GLSL
#define RAY_LOG_GLSL

// As cast, for the benchmark's probe to replay without shading; ProbeRay's layout (ray_probe.comp).
struct LoggedRay {
    vec3 origin;
    float t_min;
    vec3 dir;
    float t_max;
    uint flags;  // besides gl_RayFlagsOpaqueEXT
};
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer RayLog {
    uint count;  // rays cast, even beyond capacity
    uint capacity;
    uint pad0;
    uint pad1;
    LoggedRay rays[];
};

void log_ray(uint flags, vec3 origin, float t_min, vec3 dir, float t_max) {
    if (pc.ray_log == 0ul) return;
    RayLog log = RayLog(pc.ray_log);
    uint i = atomicAdd(log.count, 1u);
    if (i < log.capacity) log.rays[i] = LoggedRay(origin, t_min, dir, t_max, flags);
}

#endif
