#version 460
// G-buffer pass: the material and the Blinn bump-mapped shading normal (Blinn 1978) with a Perlin height field
// (Perlin 1985, 2002), evaluated procedurally by material.glsl, the evaluation ray hits share; then packed into
// the attachments (gbuffer_encoding.glsl).
#extension GL_EXT_nonuniform_qualifier : require
#extension GL_EXT_scalar_block_layout : require
#include "gbuffer_layout.glsl"
#include "material.glsl"
#include "sampling.glsl"
#define GBUFFER_ENCODE
#include "gbuffer_encoding.glsl"

layout(set = 0, binding = GBUFFER_BINDING_TEXTURES) uniform sampler2D textures[];

layout(location = 0) in vec3 in_world_position;
layout(location = 1) in vec3 in_world_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_color;
layout(location = 4) in vec3 in_dpdu;
layout(location = 5) in vec3 in_dpdv;
layout(location = 7) in vec2 in_uv1;

// The fragment reads material textures by its implicit derivatives (material.glsl's contract).
vec4 material_texture(int index, vec2 uv, vec4 rows[2], vec2 footprint_lod) {
    return texture(textures[nonuniformEXT(index)], uv);
}

void main() {
    GBufferDraw d = draws[pc.draw];
    GpuMaterial m = materials[pc.material];

    // The face normal from screen-space derivatives, turned to the interpolated normal's side.
    vec3 face = cross(dFdx(in_world_position), dFdy(in_world_position));
    float face_len = length(face);
    vec3 n = in_world_normal;
    float n_len = length(n);
    vec3 geometric = face_len > 0.0 ? face / face_len : (n_len > 0.0 ? n / n_len : vec3(0.0, 0.0, 1.0));
    if (n_len > 0.0 && dot(geometric, n) < 0.0) geometric = -geometric;
    if (!(n_len > 0.0)) n = geometric;

    MaterialPoint p = evaluate_material(m, in_color, in_uv, in_uv1, n, in_dpdu, in_dpdv, vec2(0.0), true, true);
    // BLEND's coverage sample: independent per pixel, surface point and sample (the draw record's per-sample key;
    // the point's position tells layers apart without gl_PrimitiveID, which a fragment shader may read only
    // with geometry shaders enabled).
    float coverage_u = 0.0;
    if (m.alpha_mode == ALPHA_BLEND) {
        uint pixel = uint(gl_FragCoord.x) | (uint(gl_FragCoord.y) << 16u);
        uvec3 at = floatBitsToUint(in_world_position);
        uint h = pcg_hash(d.coverage_key ^ pcg_hash(pixel ^ pcg_hash(d.instance)));
        coverage_u = unit_float(pcg_hash(h ^ pcg_hash(at.x ^ pcg_hash(at.y ^ pcg_hash(at.z)))));
    }
    if (!alpha_test_passes(m, p.base.a, coverage_u)) discard;
    // Without a bump the normal (interpolated, or tilted by a normal texture) still needs its unit length.
    vec3 shading = m.bump.kind != BUMP_NONE ? p.normal : normalize(p.normal);
    // Double-sided faces seen from behind: the same surface, so its normals flip toward the viewer.
    if (!gl_FrontFacing && m.double_sided != 0) {
        shading = -shading;
        geometric = -geometric;
    }

    GBufferTexel t;
    t.position = in_world_position;
    t.view_depth = -dot(pc.view_z_row, vec4(in_world_position, 1.0));
    // What the BRDF reads: the base colour, or nothing for an unlit material (its colour is its emission).
    t.albedo = vec4(p.shading.albedo, p.base.a);
    t.metallic = p.shading.metallic;
    t.roughness = p.shading.roughness;
    t.transmission = p.shading.transmission;
    t.ior = p.shading.ior;
    t.emission = p.emission;
    t.height = p.height;
    // The texel alone: the factor may exceed 1, beyond what an 8-bit sRGB channel holds.
    t.specular_color_texel = p.specular_color_texel;
    t.specular = p.shading.specular;
    t.instance_plus_one = d.instance + 1u;
    t.material = pc.material;
    t.shading_normal = shading;
    t.geometric_normal = geometric;
    write_gbuffer(t);
}
