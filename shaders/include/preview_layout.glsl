// Push constants of the preview pass; mirrored by `PreviewPush` in src/render/preview.rs (size test there).
#ifndef PREVIEW_LAYOUT_GLSL
#define PREVIEW_LAYOUT_GLSL
layout(push_constant, std430) uniform PreviewPush {
    mat4 clip_from_object;
    // Rows of the 3x3 matrix taking object normals to view space (inverse transpose), padded to vec4.
    vec4 view_normal_rows[3];
    vec4 base_color;
} pc;
#endif
