// The G-buffer's one encoding: what gbuffer.frag packs into the attachments and the accumulation pass unpacks
// (Rust's twin, for read-backs and AOVs: src/render/gbuffer_encoding.rs). Locations are GBUFFER_ATTACHMENT_* in
// shared_constants.glsl; formats are render::gbuffer_layout::ATTACHMENTS.
//   position         RGBA32F     world xyz (full precision: rays start there), w = view depth of this sample's eye
//   albedo           RGBA8 sRGB  base colour x texture x vertex colour, a = alpha
//   material         RGBA8       metallic, roughness, transmission, pack_ior(ior)
//   emission         RGBA16F     emitted radiance rgb, a = bump height B(u, v)
//   specular         RGBA8 sRGB  KHR_materials_specular's colour texel (white without one), a = specular factor
//   surface ids      RGBA32UI    instance index + 1 (0: nothing), material index, shading normal, geometric normal
// Normals are octahedral (Cigolle et al. 2014, "A Survey of Efficient Representations for Independent Unit
// Vectors", JCGT 3(2)) in two 16-bit snorms: under 1e-4 rad off, in a third of the bytes of three floats.
#ifndef GBUFFER_ENCODING_GLSL
#define GBUFFER_ENCODING_GLSL
#include "shared_constants.glsl"

// The index of refraction in an 8-bit unorm channel: 1 to 4 mapped onto 0 to 1.
float pack_ior(float ior) { return clamp((ior - 1.0) / 3.0, 0.0, 1.0); }
float unpack_ior(float packed) { return 1.0 + 3.0 * packed; }

vec2 sign_not_zero(vec2 v) { return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }

// A unit vector onto the octahedron |x| + |y| + |z| = 1, its lower half folded over the upper, as two snorm16s.
uint encode_unit_vector(vec3 n) {
    float l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if (!(l1 > 0.0)) return packSnorm2x16(vec2(0.0));  // decodes to +z: nothing better exists for a zero vector
    vec3 o = n / l1;
    vec2 folded = o.z >= 0.0 ? o.xy : (1.0 - abs(o.yx)) * sign_not_zero(o.xy);
    return packSnorm2x16(folded);
}

vec3 decode_unit_vector(uint packed) {
    vec2 f = unpackSnorm2x16(packed);
    vec3 n = vec3(f, 1.0 - abs(f.x) - abs(f.y));
    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * sign_not_zero(n.xy);
    return normalize(n);
}

// One G-buffer texel, decoded.
struct GBufferTexel {
    vec3 position;
    float view_depth;
    vec4 albedo;
    float metallic;
    float roughness;
    float transmission;
    float ior;
    vec3 emission;
    float height;
    vec3 specular_color_texel;
    float specular;
    uint instance_plus_one;
    uint material;
    vec3 shading_normal;
    vec3 geometric_normal;
};

#ifdef GBUFFER_ENCODE
layout(location = GBUFFER_ATTACHMENT_POSITION) out vec4 out_position;
layout(location = GBUFFER_ATTACHMENT_ALBEDO) out vec4 out_albedo;
layout(location = GBUFFER_ATTACHMENT_MATERIAL) out vec4 out_material;
layout(location = GBUFFER_ATTACHMENT_EMISSION) out vec4 out_emission;
layout(location = GBUFFER_ATTACHMENT_SPECULAR) out vec4 out_specular;
layout(location = GBUFFER_ATTACHMENT_SURFACE_IDS) out uvec4 out_surface_ids;

void write_gbuffer(GBufferTexel t) {
    out_position = vec4(t.position, t.view_depth);
    out_albedo = t.albedo;
    out_material = vec4(t.metallic, t.roughness, t.transmission, pack_ior(t.ior));
    out_emission = vec4(t.emission, t.height);
    out_specular = vec4(t.specular_color_texel, t.specular);
    out_surface_ids = uvec4(t.instance_plus_one, t.material, encode_unit_vector(t.shading_normal),
                            encode_unit_vector(t.geometric_normal));
}
#endif

#ifdef GBUFFER_DECODE
// The accumulation pass's view: the float attachments as one sampler array (at their GBUFFER_ATTACHMENT_*
// indices, the surface ids last and apart), read texel by texel.
layout(set = 0, binding = ACCUMULATE_BINDING_GBUFFER) uniform sampler2D gbuffer[GBUFFER_ATTACHMENT_SURFACE_IDS];
layout(set = 0, binding = ACCUMULATE_BINDING_GBUFFER_IDS) uniform usampler2D gbuffer_surface_ids;

uvec4 read_gbuffer_surface_ids(ivec2 p) { return texelFetch(gbuffer_surface_ids, p, 0); }

vec3 read_gbuffer_position(ivec2 p) { return texelFetch(gbuffer[GBUFFER_ATTACHMENT_POSITION], p, 0).xyz; }

// What shading reads of a covered pixel whose surface ids are `ids` (the view depth and height are the AOVs').
GBufferTexel read_gbuffer(ivec2 p, uvec4 ids) {
    GBufferTexel t;
    vec4 pos = texelFetch(gbuffer[GBUFFER_ATTACHMENT_POSITION], p, 0);
    vec4 mat = texelFetch(gbuffer[GBUFFER_ATTACHMENT_MATERIAL], p, 0);
    vec4 specular = texelFetch(gbuffer[GBUFFER_ATTACHMENT_SPECULAR], p, 0);
    vec4 emission = texelFetch(gbuffer[GBUFFER_ATTACHMENT_EMISSION], p, 0);
    t.position = pos.xyz;
    t.view_depth = pos.w;
    t.albedo = texelFetch(gbuffer[GBUFFER_ATTACHMENT_ALBEDO], p, 0);
    t.metallic = mat.x;
    t.roughness = mat.y;
    t.transmission = mat.z;
    t.ior = unpack_ior(mat.w);
    t.emission = emission.rgb;
    t.height = emission.a;
    t.specular_color_texel = specular.rgb;
    t.specular = specular.a;
    t.instance_plus_one = ids.x;
    t.material = ids.y;
    t.shading_normal = decode_unit_vector(ids.z);
    t.geometric_normal = decode_unit_vector(ids.w);
    return t;
}
#endif
#endif
