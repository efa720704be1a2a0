#version 460
// G-buffer pass: one camera sample (lens point, time, jitter) in pc.clip_from_world; instance transforms for
// this sample's time in draws[pc.draw], the draw pushed before each draw.
#extension GL_EXT_scalar_block_layout : require
#include "gbuffer_layout.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_color;
layout(location = 4) in vec3 in_dpdu;
layout(location = 5) in vec3 in_dpdv;
layout(location = 6) in vec2 in_uv1;

layout(location = 0) out vec3 out_world_position;
layout(location = 1) out vec3 out_world_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) out vec4 out_color;
layout(location = 4) out vec3 out_dpdu;
layout(location = 5) out vec3 out_dpdv;
layout(location = 7) out vec2 out_uv1;

void main() {
    GBufferDraw d = draws[pc.draw];
    vec4 world = d.world_from_object * vec4(in_position, 1.0);
    gl_Position = pc.clip_from_world * world;
    out_world_position = world.xyz;
    out_world_normal = vec3(dot(d.normal_rows[0].xyz, in_normal), dot(d.normal_rows[1].xyz, in_normal),
                            dot(d.normal_rows[2].xyz, in_normal));
    // Surface derivatives are tangent vectors: they transform with the object matrix, not the normal matrix.
    out_dpdu = mat3(d.world_from_object) * in_dpdu;
    out_dpdv = mat3(d.world_from_object) * in_dpdv;
    out_uv = in_uv;
    out_uv1 = in_uv1;
    out_color = in_color;
}
