// The reference mode's (--primary rays) camera ray per pixel. Part of the accumulation pass's shading body
// (path_tracer.glsl).
#ifndef CAMERA_RAY_GLSL
#define CAMERA_RAY_GLSL

// The reference mode's primary ray for pixel p: through the point p + ½ − jitter of the image (the raster
// pass's jitter convention, camera_sample in src/math/lens.rs) from a point on the thin lens, aimed so that the
// plane at the focus distance stays sharp (docs/architecture.md, "Thin lens"). t_range clips at the near and far depths,
// as the raster pass does.
void camera_ray(GpuCamera c, ivec2 p, vec2 jitter, vec2 lens_uv, out vec3 origin, out vec3 dir, out vec2 t_range) {
    vec2 ndc = (vec2(p) + 0.5 - jitter) / vec2(pc.width, pc.height) * 2.0 - 1.0;
    // View space: x right, y up (the image's y runs down), looking down -z.
    vec2 plane = vec2(ndc.x, -ndc.y) * c.lens.xy;
    vec3 o_view;
    vec3 d_view;
    if (c.range.z != 0.0) {
        o_view = vec3(plane, 0.0);
        d_view = vec3(0.0, 0.0, -1.0);
    } else {
        vec2 offset = c.lens.z > 0.0 ? concentric_disk(lens_uv) * c.lens.z : vec2(0.0);
        o_view = vec3(offset, 0.0);
        d_view = vec3(plane * c.lens.w, -c.lens.w) - o_view;
    }
    origin = (c.world_from_camera * vec4(o_view, 1.0)).xyz;
    vec3 d = mat3(c.world_from_camera) * d_view;
    float len = length(d);
    dir = d / len;
    // Depth along the view axis grows by -d_view.z / len per unit of t.
    float depth_per_t = -d_view.z / len;
    t_range = vec2(c.range.x / depth_per_t, min(c.range.y / depth_per_t, 1e30));
}

#endif
