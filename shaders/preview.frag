#version 460
// Simple shading for the preview: a key light from over the viewer's shoulder plus a little ambient, in view
// space, so any scene is readable without lights of its own. The surface colour is the glTF base colour:
// factor × vertex colour × base-colour texture (glTF 2.0 §3.9.2). Linear radiance out.
#extension GL_EXT_nonuniform_qualifier : require
#include "preview_layout.glsl"

layout(set = 0, binding = PREVIEW_BINDING_TEXTURES) uniform sampler2D textures[];

layout(location = 0) in vec3 in_view_normal;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec4 in_color;
layout(location = 3) flat in int in_draw;
layout(location = 0) out vec4 out_color;

const vec3 KEY_DIRECTION = vec3(0.3333333, 0.6666667, 0.6666667); // unit vector towards the light
const float AMBIENT = 0.15;

void main() {
    PreviewDraw d = draws[in_draw];
    vec4 base = d.base_color * in_color;
    if (d.base_color_texture >= 0) {
        vec3 uv1 = vec3(in_uv, 1.0);
        vec2 uv = vec2(dot(d.uv_transform_rows[0].xyz, uv1), dot(d.uv_transform_rows[1].xyz, uv1));
        base *= texture(textures[nonuniformEXT(d.base_color_texture)], uv);
    }
    float len = length(in_view_normal);
    vec3 n = len > 0.0 ? in_view_normal / len : vec3(0.0, 0.0, 1.0);
    // Double-sided preview: shade back faces as seen.
    if (!gl_FrontFacing) n = -n;
    float lambert = max(dot(n, KEY_DIRECTION), 0.0);
    out_color = vec4(base.rgb * (AMBIENT + (1.0 - AMBIENT) * lambert), 1.0);
}
