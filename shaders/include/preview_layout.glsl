// Per-draw data of the preview pass; mirrored by `PreviewDraw` in src/render/preview.rs (size test there).
// Draw i reads draws[i], selected through firstInstance = i (gl_InstanceIndex).
#ifndef PREVIEW_LAYOUT_GLSL
#define PREVIEW_LAYOUT_GLSL
#include "shared_constants.glsl"
struct PreviewDraw {
    mat4 clip_from_object;
    // Rows of the 3x3 matrix taking object normals to view space (inverse transpose), padded to vec4.
    vec4 view_normal_rows[3];
    vec4 base_color;
    // KHR_texture_transform as two rows of a 2x3 matrix: uv' = (dot(row0.xyz, (u, v, 1)), dot(row1.xyz, ...)).
    vec4 uv_transform_rows[2];
    // Index into `textures`, or -1 for none.
    int base_color_texture;
    int pad0;
    int pad1;
    int pad2;
};

layout(set = 0, binding = PREVIEW_BINDING_DRAWS, std430) readonly buffer PreviewDraws { PreviewDraw draws[]; };
#endif
