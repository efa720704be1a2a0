#version 460
// Forward flow in pixels: where the surface point is one frame later minus where it is now, both projected
// (math::lens::project_to_pixel's convention: NDC (−1, −1) is the image's top-left corner). Clip positions are
// interpolated perspective-correctly, so for a point of the triangle this is the projection of the same
// barycentric point of the triangle one frame later.
layout(push_constant, std430) uniform MotionPush { mat4 clip_from_world; vec2 image_size; } pc;

layout(location = 0) in vec4 in_clip_now;
layout(location = 1) in vec4 in_clip_next;
layout(location = 2) flat in uint in_instance_plus_one;

layout(location = 0) out vec4 out_flow;

vec2 to_pixel(vec4 clip) {
    return (clip.xy / clip.w + 1.0) * 0.5 * pc.image_size;
}

void main() {
    out_flow = vec4(to_pixel(in_clip_next) - to_pixel(in_clip_now), float(in_instance_plus_one), 1.0);
}
