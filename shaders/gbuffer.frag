#version 460
// G-buffer pass: the material and the Blinn bump-mapped shading normal (Blinn 1978) with a Perlin height field
// (Perlin 1985, 2002), evaluated procedurally by material.glsl, the evaluation ray hits share; then packed into
// the attachments (gbuffer_layout.glsl).
#extension GL_EXT_nonuniform_qualifier : require
#extension GL_EXT_scalar_block_layout : require
#include "gbuffer_layout.glsl"
#include "material.glsl"

layout(set = 0, binding = GBUFFER_BINDING_TEXTURES) uniform sampler2D textures[];

layout(location = 0) in vec3 in_world_position;
layout(location = 1) in vec3 in_world_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_color;
layout(location = 4) in vec3 in_dpdu;
layout(location = 5) in vec3 in_dpdv;
layout(location = 6) flat in uint in_draw;
layout(location = 7) in vec2 in_uv1;

layout(location = GBUFFER_POSITION) out vec4 out_position;
layout(location = GBUFFER_SHADING_NORMAL) out vec4 out_shading_normal;
layout(location = GBUFFER_GEOMETRIC_NORMAL) out vec4 out_geometric_normal;
layout(location = GBUFFER_ALBEDO) out vec4 out_albedo;
layout(location = GBUFFER_MATERIAL) out vec4 out_material;
layout(location = GBUFFER_EMISSION) out vec4 out_emission;
layout(location = GBUFFER_SPECULAR_COLOR) out vec4 out_specular_color;
layout(location = GBUFFER_IDS) out uvec2 out_ids;

// The fragment reads material textures by its implicit derivatives (material.glsl's contract).
vec4 material_texture(int index, vec2 uv, vec4 rows[2], vec2 footprint_lod) {
    return texture(textures[nonuniformEXT(index)], uv);
}

void main() {
    GBufferDraw d = draws[in_draw];
    GpuMaterial m = materials[d.material];

    // The face normal from screen-space derivatives, turned to the interpolated normal's side.
    vec3 face = cross(dFdx(in_world_position), dFdy(in_world_position));
    float face_len = length(face);
    vec3 n = in_world_normal;
    float n_len = length(n);
    vec3 geometric = face_len > 0.0 ? face / face_len : (n_len > 0.0 ? n / n_len : vec3(0.0, 0.0, 1.0));
    if (n_len > 0.0 && dot(geometric, n) < 0.0) geometric = -geometric;
    if (!(n_len > 0.0)) n = geometric;

    MaterialPoint p = evaluate_material(m, in_color, in_uv, in_uv1, n, in_dpdu, in_dpdv, vec2(0.0), true);
    if (!alpha_test_passes(m, p.base.a)) discard;
    // Without a bump the normal (interpolated, or tilted by a normal texture) still needs its unit length.
    vec3 shading = m.bump.kind != BUMP_NONE ? p.normal : normalize(p.normal);
    // Double-sided faces seen from behind: the same surface, so its normals flip toward the viewer.
    if (!gl_FrontFacing && m.double_sided != 0) {
        shading = -shading;
        geometric = -geometric;
    }

    out_position = vec4(in_world_position, -dot(pc.view_z_row, vec4(in_world_position, 1.0)));
    out_shading_normal = vec4(shading, p.height);
    // The specular factor rides in the geometric normal's spare channel (16-bit float).
    out_geometric_normal = vec4(geometric, p.shading.specular);
    out_albedo = p.base;
    out_material = vec4(p.shading.metallic, p.shading.roughness, p.shading.transmission, pack_ior(p.shading.ior));
    out_emission = vec4(p.emission, 0.0);
    // The texel alone: the factor may exceed 1, beyond what this 8-bit sRGB attachment holds.
    out_specular_color = vec4(p.specular_color_texel, 1.0);
    out_ids = uvec2(d.instance + 1u, d.material);
}
