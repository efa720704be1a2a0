#version 460
// Triangles given directly in clip space with one flat colour: the raster readback test's pass.
layout(push_constant, std430) uniform SolidPush {
    vec4 color;
} pc;
layout(location = 0) in vec2 in_clip_position;

void main() {
    gl_Position = vec4(in_clip_position, 0.0, 1.0);
}
