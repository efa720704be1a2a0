#version 460
// The motion pass (render::motion): the deformed (skinned or morphing) instances drawn at the frame's time, each
// vertex carrying where it is one frame later. Positions now are placed exactly as gbuffer.vert places them
// (world_from_object, then the camera), so the two passes cover the same pixels.
#extension GL_EXT_scalar_block_layout : require

struct MotionDraw {
    mat4 world_from_object_now;
    mat4 clip_from_object_next;  // the next frame's camera times the instance's transform then
    uint instance_plus_one;
    uint pad[3];
};

layout(set = 0, binding = 0, scalar) readonly buffer MotionDraws { MotionDraw draws[]; };
layout(push_constant, std430) uniform MotionPush { mat4 clip_from_world; vec2 image_size; } pc;

layout(location = 0) in vec3 in_position_now;
layout(location = 1) in vec3 in_position_next;

layout(location = 0) out vec4 out_clip_now;
layout(location = 1) out vec4 out_clip_next;
layout(location = 2) flat out uint out_instance_plus_one;

void main() {
    MotionDraw d = draws[gl_InstanceIndex];
    vec4 world = d.world_from_object_now * vec4(in_position_now, 1.0);
    gl_Position = pc.clip_from_world * world;
    out_clip_now = gl_Position;
    out_clip_next = d.clip_from_object_next * vec4(in_position_next, 1.0);
    out_instance_plus_one = d.instance_plus_one;
}
