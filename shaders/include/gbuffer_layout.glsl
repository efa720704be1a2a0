// The G-buffer pass's data; mirrored by src/render/gbuffer_layout.rs (size/offset tests there).
#ifndef GBUFFER_LAYOUT_GLSL
#define GBUFFER_LAYOUT_GLSL
#include "bump.glsl"
#include "shared_constants.glsl"

// What each attachment holds and how: gbuffer_encoding.glsl.

struct GBufferDraw {
    mat4 world_from_object;
    // Rows of the world-normal matrix (inverse transpose), padded to vec4.
    vec4 normal_rows[3];
    // The draw's material index is pushed (pc.material), not read from here.
    uint instance;
    uint coverage_key;  // this sample's key for BLEND's stochastic coverage (alpha_test_passes)
    uint pad1;
};

struct GpuMaterial {
    vec4 base_color;
    vec4 emissive;           // rgb emitted radiance, w specular factor (KHR_materials_specular)
    float metallic;
    float roughness;
    float transmission;
    float ior;
    float normal_scale;
    float alpha_cutoff;
    int alpha_mode;          // ALPHA_OPAQUE, ALPHA_MASK or ALPHA_BLEND (shared_constants.glsl)
    int double_sided;
    int base_color_texture;  // -1: none
    int transmission_texture;  // R scales the transmission factor (KHR_materials_transmission); -1: none
    int normal_texture;
    int emissive_texture;
    vec4 base_color_uv_rows[2];
    Bump bump;               // kind BUMP_NONE: no bump
    int metallic_roughness_texture;  // roughness in G, metalness in B (glTF 2.0 §3.9.2); -1: none
    int specular_texture;    // A scales the specular factor (KHR_materials_specular); -1: none
    int specular_color_texture;  // RGB scales the specular colour (KHR_materials_specular); -1: none
    int unlit;               // 1: KHR_materials_unlit (material.glsl)
    // Each texture's KHR_texture_transform (transform_uv), identity without one; the spare w of the first row
    // names the UV set (reads_uv1), of the second the texture's level-of-detail offset (texture_lod).
    vec4 metallic_roughness_uv_rows[2];
    vec4 normal_uv_rows[2];
    vec4 emissive_uv_rows[2];
    vec4 transmission_uv_rows[2];
    vec4 specular_color;     // rgb KHR_materials_specular colour (tints the dielectric F0)
    vec4 specular_uv_rows[2];
    vec4 specular_color_uv_rows[2];
    vec4 absorption;         // rgb σ per metre inside the material (KHR_materials_volume); 0: none
    // KHR_materials_clearcoat: x factor (0: no coat), y roughness, z the coat normal texture's scale, w 1 where the
    // material has any layer or diffuse transmission (docs/architecture.md, "Layered materials").
    vec4 clearcoat;
    vec4 sheen;              // KHR_materials_sheen: rgb colour (black: no sheen), a roughness
    int clearcoat_texture;   // R scales the coat's factor; -1: none (and likewise below)
    int clearcoat_roughness_texture;  // G scales the coat's roughness
    int clearcoat_normal_texture;
    int sheen_color_texture;          // RGB scales the sheen colour
    int sheen_roughness_texture;      // A scales the sheen roughness
    int diffuse_transmission_texture;        // A scales the diffuse transmission factor
    int diffuse_transmission_color_texture;  // RGB scales the diffuse transmission colour
    int pad;
    vec4 clearcoat_uv_rows[2];
    vec4 clearcoat_roughness_uv_rows[2];
    vec4 clearcoat_normal_uv_rows[2];
    vec4 sheen_color_uv_rows[2];
    vec4 sheen_roughness_uv_rows[2];
    vec4 diffuse_transmission;  // KHR_materials_diffuse_transmission: rgb colour, a factor (0: none)
    vec4 diffuse_transmission_uv_rows[2];
    vec4 diffuse_transmission_color_uv_rows[2];
    vec4 iridescence;  // KHR_materials_iridescence: x factor (0: no film), y the film's index, z, w thickness range (nm)
    int iridescence_texture;            // R scales the factor
    int iridescence_thickness_texture;  // G places the thickness within the range (without one: its maximum)
    int pad1[2];
    vec4 iridescence_uv_rows[2];
    vec4 iridescence_thickness_uv_rows[2];
    vec4 anisotropy;         // KHR_materials_anisotropy: x strength (0: isotropic), y, z the rotation's cos and sin
    int anisotropy_texture;  // RG a tangent-space direction, B scales the strength
    int pad2[3];
    vec4 anisotropy_uv_rows[2];
};

// A material's KHR_texture_transform, stored as the first two rows of a 3x3 matrix, applied to a UV.
vec2 transform_uv(vec4 rows[2], vec2 uv) {
    vec3 h = vec3(uv, 1.0);
    return vec2(dot(rows[0].xyz, h), dot(rows[1].xyz, h));
}

// Whether a texture reads TEXCOORD_1 (its rows' spare channel; GpuMaterial::new), not TEXCOORD_0.
bool reads_uv1(vec4 rows[2]) {
    return rows[0].w != 0.0;
}

// The level of detail for reading a texture over a footprint whose level in its UV set's units is `footprint_lod`
// (x: TEXCOORD_0, y: TEXCOORD_1): the rows' spare w adds the texture's texels per unit of UV length
// (texel_lod_offset in gbuffer_layout.rs).
float texture_lod(vec4 rows[2], vec2 footprint_lod) {
    return (reads_uv1(rows) ? footprint_lod.y : footprint_lod.x) + rows[1].w;
}

// A texture's coordinates: its set's UV through its transform.
vec2 texture_uv(vec4 rows[2], vec2 uv0, vec2 uv1) {
    return transform_uv(rows, reads_uv1(rows) ? uv1 : uv0);
}

// The surface derivatives with respect to a texture's transformed coordinates uv' = A·uv + t: [∂p/∂u' ∂p/∂v'] =
// [∂p/∂u ∂p/∂v]·A⁻¹, so a rotated or scaled normal texture keeps its tangent frame on the surface.
void transform_derivatives(vec4 rows[2], inout vec3 dpdu, inout vec3 dpdv) {
    // A = [a b; c d] (rows[0] = (a, b, tx), rows[1] = (c, d, ty)); A⁻¹ = [d −b; −c a] / det.
    float det = rows[0].x * rows[1].y - rows[0].y * rows[1].x;
    if (!(abs(det) > 0.0)) return;
    vec3 u = (dpdu * rows[1].y - dpdv * rows[1].x) / det;
    vec3 v = (dpdv * rows[0].x - dpdu * rows[0].y) / det;
    dpdu = u;
    dpdv = v;
}

// A glTF normal texture (tangent space, glTF 2.0 §3.9.3) tilts the normal n by the texel `texel` (as stored, in
// [0, 1]); the tangent frame comes from the surface derivatives (T along Q_u, B = ±n x T with the sign of the UV
// orientation). Degenerate derivatives leave n as it was.
vec3 normal_from_texture(vec3 n, vec3 dpdu, vec3 dpdv, vec3 texel, float scale) {
    vec3 nn = normalize(n);
    vec3 t = dpdu - nn * dot(nn, dpdu);
    float t_len = length(t);
    if (!(t_len > 1e-12)) return n;
    t /= t_len;
    vec3 b = cross(nn, t) * (dot(cross(dpdu, dpdv), nn) < 0.0 ? -1.0 : 1.0);
    vec3 tex = texel * 2.0 - 1.0;
    tex.xy *= scale;
    vec3 mapped = t * tex.x + b * tex.y + nn * tex.z;
    float mapped_len = length(mapped);
    return mapped_len > 0.0 ? mapped / mapped_len : n;
}

#ifndef GBUFFER_LAYOUT_STRUCTS_ONLY
layout(set = 0, binding = GBUFFER_BINDING_DRAWS, std430) readonly buffer GBufferDraws { GBufferDraw draws[]; };
layout(set = 0, binding = GBUFFER_BINDING_MATERIALS, std430) readonly buffer GBufferMaterials { GpuMaterial materials[]; };

layout(push_constant, std430) uniform GBufferPush {
    mat4 clip_from_world;
    // Third row of view_from_world: view depth = -dot(view_z_row, vec4(p, 1)).
    vec4 view_z_row;
    // The draw record this draw reads (draws[draw]), pushed before each draw: a push constant is uniform over
    // the draw, so llvmpipe branches on its material's fields instead of running every branch under a mask, as it
    // did for a flat varying.
    uint draw;
    // Its material's index (materials[material]), pushed too: indexed by a field of the draw record, the material's
    // fields were gathered lane by lane (render/gbuffer_layout.rs, GBufferDrawPush).
    uint material;
} pc;
#endif
#endif
