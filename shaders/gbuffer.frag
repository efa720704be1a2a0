#version 460
// G-buffer pass: material evaluation and Blinn bump mapping (Blinn 1978) of the shading normal with a Perlin
// height field (Perlin 1985, 2002), evaluated procedurally here.
#extension GL_EXT_nonuniform_qualifier : require
#extension GL_EXT_scalar_block_layout : require
#include "gbuffer_layout.glsl"

layout(set = 0, binding = 2) uniform sampler2D textures[];

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

void main() {
    GBufferDraw d = draws[in_draw];
    GpuMaterial m = materials[d.material];

    vec4 base = m.base_color * in_color;
    if (m.base_color_texture >= 0) {
        base *= texture(textures[nonuniformEXT(m.base_color_texture)], texture_uv(m.base_color_uv_rows, in_uv, in_uv1));
    }
    // MASK discards below the cutoff; BLEND is drawn as coverage at 0.5 (no order-independent transparency).
    if ((m.alpha_mode == 1 && base.a < m.alpha_cutoff) || (m.alpha_mode == 2 && base.a < 0.5)) discard;

    // The face normal from screen-space derivatives, turned to the interpolated normal's side.
    vec3 face = cross(dFdx(in_world_position), dFdy(in_world_position));
    float face_len = length(face);
    vec3 n = in_world_normal;
    float n_len = length(n);
    vec3 geometric = face_len > 0.0 ? face / face_len : (n_len > 0.0 ? n / n_len : vec3(0.0, 0.0, 1.0));
    if (n_len > 0.0 && dot(geometric, n) < 0.0) geometric = -geometric;
    if (!(n_len > 0.0)) n = geometric;

    if (m.normal_texture >= 0) {
        vec3 texel = texture(textures[nonuniformEXT(m.normal_texture)], transform_uv(m.normal_uv_rows, in_uv)).xyz;
        vec3 dpdu = in_dpdu;
        vec3 dpdv = in_dpdv;
        transform_derivatives(m.normal_uv_rows, dpdu, dpdv);
        n = normal_from_texture(n, dpdu, dpdv, texel, m.normal_scale);
    }
    float height = 0.0;
    vec3 shading = normalize(n);
    if (m.bump.kind != BUMP_NONE) {
        vec3 h = bump_height_and_gradient(m.bump, in_uv);
        height = h.x;
        shading = bump_perturb_normal(n, in_dpdu, in_dpdv, h.yz);
    }
    // Double-sided faces seen from behind: the same surface, so its normals flip toward the viewer.
    if (!gl_FrontFacing && m.double_sided != 0) {
        shading = -shading;
        geometric = -geometric;
    }

    out_position = vec4(in_world_position, -dot(pc.view_z_row, vec4(in_world_position, 1.0)));
    out_shading_normal = vec4(shading, height);
    // The specular factor rides in the geometric normal's spare channel (16-bit float).
    float specular = m.emissive.w;
    if (m.specular_texture >= 0) {
        specular *= texture(textures[nonuniformEXT(m.specular_texture)], texture_uv(m.specular_uv_rows, in_uv, in_uv1)).a;
    }
    out_geometric_normal = vec4(geometric, specular);
    out_albedo = base;
    // Textures scale their factors (glTF 2.0 §3.9.2, §3.9.5); ray hits do the same (accumulate.comp).
    vec2 metallic_roughness = vec2(m.metallic, m.roughness);  // metalness in B, roughness in G
    if (m.metallic_roughness_texture >= 0) {
        metallic_roughness *= texture(textures[nonuniformEXT(m.metallic_roughness_texture)],
                                      texture_uv(m.metallic_roughness_uv_rows, in_uv, in_uv1)).bg;
    }
    vec3 emission = m.emissive.rgb;
    if (m.emissive_texture >= 0) {
        emission *= texture(textures[nonuniformEXT(m.emissive_texture)], texture_uv(m.emissive_uv_rows, in_uv, in_uv1)).rgb;
    }
    float transmission = m.transmission;
    if (m.transmission_texture >= 0) {
        transmission *=
            texture(textures[nonuniformEXT(m.transmission_texture)], texture_uv(m.transmission_uv_rows, in_uv, in_uv1)).r;
    }
    out_material = vec4(metallic_roughness, transmission, pack_ior(m.ior));
    out_emission = vec4(emission, 0.0);
    // The texel alone: the factor may exceed 1, beyond what this 8-bit sRGB attachment holds.
    out_specular_color = vec4(1.0);
    if (m.specular_color_texture >= 0) {
        out_specular_color.rgb = texture(textures[nonuniformEXT(m.specular_color_texture)],
                                         texture_uv(m.specular_color_uv_rows, in_uv, in_uv1)).rgb;
    }
    out_ids = uvec2(d.instance + 1u, d.material);
}
