#version 460
// Simple shading for the preview: a key light from over the viewer's shoulder plus a little ambient, in view
// space, so any scene is readable without lights of its own. Linear radiance out.
#include "preview_layout.glsl"

layout(location = 0) in vec3 in_view_normal;
layout(location = 0) out vec4 out_color;

const vec3 KEY_DIRECTION = vec3(0.3333333, 0.6666667, 0.6666667); // unit vector towards the light
const float AMBIENT = 0.15;

void main() {
    float len = length(in_view_normal);
    vec3 n = len > 0.0 ? in_view_normal / len : vec3(0.0, 0.0, 1.0);
    // Double-sided preview: shade back faces as seen.
    if (!gl_FrontFacing) n = -n;
    float lambert = max(dot(n, KEY_DIRECTION), 0.0);
    out_color = vec4(pc.base_color.rgb * (AMBIENT + (1.0 - AMBIENT) * lambert), 1.0);
}
