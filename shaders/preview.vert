#version 460
// The first-frame preview: transforms positions to clip space and normals to view space, and passes
// texture coordinates and vertex colours on.
#include "preview_layout.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_color;
layout(location = 0) out vec3 out_view_normal;
layout(location = 1) out vec2 out_uv;
layout(location = 2) out vec4 out_color;
layout(location = 3) flat out int out_draw;

void main() {
    PreviewDraw d = draws[gl_InstanceIndex];
    gl_Position = d.clip_from_object * vec4(in_position, 1.0);
    out_view_normal = vec3(dot(d.view_normal_rows[0].xyz, in_normal),
                           dot(d.view_normal_rows[1].xyz, in_normal),
                           dot(d.view_normal_rows[2].xyz, in_normal));
    out_uv = in_uv;
    out_color = in_color;
    out_draw = gl_InstanceIndex;
}
