#version 460
// The first-frame preview: transforms positions to clip space and normals to view space.
#include "preview_layout.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 0) out vec3 out_view_normal;

void main() {
    gl_Position = pc.clip_from_object * vec4(in_position, 1.0);
    out_view_normal = vec3(dot(pc.view_normal_rows[0].xyz, in_normal),
                           dot(pc.view_normal_rows[1].xyz, in_normal),
                           dot(pc.view_normal_rows[2].xyz, in_normal));
}
