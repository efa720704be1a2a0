// The one material evaluation: what a glTF metallic-roughness material (glTF 2.0 §3.9, with
// KHR_materials_transmission, _ior, _specular, _unlit, _clearcoat, _sheen and KHR_texture_transform) and its Blinn bump (Blinn 1978) make of a
// surface point. The G-buffer pass (gbuffer.frag) and every ray hit (path_tracer.glsl's hit_surface) call it, so a
// surface looks the same seen directly, in a mirror or through glass.
//
// The two callers read textures differently, so each defines, before including this file,
//   vec4 material_texture(int index, vec2 uv, vec4 rows[2], vec2 footprint_lod);
// the fragment shader by its implicit derivatives (texture), ray hits at the level of detail of the ray's cone
// (textureLod at texture_lod(rows, footprint_lod)). Include after gbuffer_layout.glsl.
#ifndef MATERIAL_GLSL
#define MATERIAL_GLSL
#include "brdf.glsl"

vec4 material_texture(int index, vec2 uv, vec4 rows[2], vec2 footprint_lod);

// The alpha test of glTF's alpha modes: MASK keeps what reaches the cutoff; BLEND keeps a point with probability
// alpha (stochastic transparency, Enderton et al. 2010), `u` uniform in [0, 1) and independent between pixels,
// samples and surfaces, so that the mean over samples is the blend: alpha × this surface + (1 − alpha) × what lies
// behind, for the raster pass, every ray and the shadows alike. Opaque materials pass.
bool alpha_test_passes(GpuMaterial m, float alpha, float u) {
    if (m.alpha_mode == ALPHA_OPAQUE) return true;
    return m.alpha_mode == ALPHA_MASK ? alpha >= m.alpha_cutoff : alpha > u;
}

// A layer texture's texel where the material has that texture (its channel scales a factor), else 1.
vec4 layer_texel(int index, vec4 rows[2], vec2 uv0, vec2 uv1, vec2 footprint_lod) {
    return index >= 0 ? material_texture(index, texture_uv(rows, uv0, uv1), rows, footprint_lod) : vec4(1.0);
}

// KHR_materials_clearcoat's, _sheen's, _iridescence's and _diffuse_transmission's parameters at a point (factors ×
// textures, glTF's channels: the coat's factor in R and roughness in G, the sheen's colour in RGB and roughness in
// A, the film's factor in R and thickness between its bounds in G, the transmitted share in A and its colour in
// RGB), where the material has any of them; none elsewhere. The coat's normal is `n_vertex`, the interpolated
// vertex normal (the base's normal texture and bump lie under the coat), tilted by the coat's own normal texture
// where it has one. `with_layers` false: none anywhere (no material has layers, so clearcoat.w is 0 in all).
void evaluate_layers(GpuMaterial m, vec2 uv0, vec2 uv1, vec3 n_vertex, vec3 dpdu, vec3 dpdv, vec2 footprint_lod,
                     const bool with_layers, inout Shading s) {
    s.clearcoat = 0.0;
    s.clearcoat_roughness = 0.0;
    s.clearcoat_normal = n_vertex;
    s.sheen_color = vec3(0.0);
    s.sheen_roughness = 0.0;
    s.coat_share = 1.0;
    s.sheen_share = 1.0;
    s.diffuse_transmission = 0.0;
    s.diffuse_transmission_color = vec3(1.0);
    s.iridescence = 0.0;
    s.iridescence_ior = 1.0;
    s.iridescence_thickness = 0.0;
    s.film_dielectric = vec3(1.0);
    s.film_metal = vec3(1.0);
    s.anisotropy = 0.0;
    s.anisotropy_direction = vec3(0.0);
    if (!with_layers || m.clearcoat.w == 0.0) return;
    s.iridescence = m.iridescence.x * layer_texel(m.iridescence_texture, m.iridescence_uv_rows, uv0, uv1, footprint_lod).r;
    s.iridescence_ior = m.iridescence.y;
    s.iridescence_thickness = m.iridescence.w;
    if (m.iridescence_thickness_texture >= 0) {
        float g = layer_texel(m.iridescence_thickness_texture, m.iridescence_thickness_uv_rows, uv0, uv1, footprint_lod).g;
        s.iridescence_thickness = mix(m.iridescence.z, m.iridescence.w, g);
    }
    s.anisotropy = m.anisotropy.x;
    if (s.anisotropy > 0.0) {
        // The direction in the tangent frame of TEXCOORD_0 (T along ∂p/∂u, B = ±n × T with the UVs' orientation,
        // as normal textures take it), rotated by the extension's rotation; the texture's RG a direction, its B a
        // factor on the strength.
        vec2 direction = vec2(1.0, 0.0);
        if (m.anisotropy_texture >= 0) {
            vec3 texel = material_texture(m.anisotropy_texture, transform_uv(m.anisotropy_uv_rows, uv0),
                                          m.anisotropy_uv_rows, footprint_lod).rgb;
            direction = texel.rg * 2.0 - 1.0;
            s.anisotropy *= texel.b;
        }
        direction = mat2(m.anisotropy.y, m.anisotropy.z, -m.anisotropy.z, m.anisotropy.y) * direction;
        vec3 t = dpdu - n_vertex * dot(n_vertex, dpdu);
        float t_len = length(t);
        if (t_len > 1e-12) {
            t /= t_len;
            vec3 b = cross(n_vertex, t) * (dot(cross(dpdu, dpdv), n_vertex) < 0.0 ? -1.0 : 1.0);
            s.anisotropy_direction = t * direction.x + b * direction.y;
        } else {
            s.anisotropy = 0.0;  // no tangent frame to stretch along
        }
    }
    s.diffuse_transmission = m.diffuse_transmission.a *
        layer_texel(m.diffuse_transmission_texture, m.diffuse_transmission_uv_rows, uv0, uv1, footprint_lod).a;
    s.diffuse_transmission_color = m.diffuse_transmission.rgb *
        layer_texel(m.diffuse_transmission_color_texture, m.diffuse_transmission_color_uv_rows, uv0, uv1, footprint_lod).rgb;
    s.clearcoat = m.clearcoat.x * layer_texel(m.clearcoat_texture, m.clearcoat_uv_rows, uv0, uv1, footprint_lod).r;
    s.clearcoat_roughness = m.clearcoat.y *
        layer_texel(m.clearcoat_roughness_texture, m.clearcoat_roughness_uv_rows, uv0, uv1, footprint_lod).g;
    if (m.clearcoat_normal_texture >= 0) {
        vec3 texel = material_texture(m.clearcoat_normal_texture, transform_uv(m.clearcoat_normal_uv_rows, uv0),
                                      m.clearcoat_normal_uv_rows, footprint_lod).xyz;
        vec3 map_dpdu = dpdu;
        vec3 map_dpdv = dpdv;
        transform_derivatives(m.clearcoat_normal_uv_rows, map_dpdu, map_dpdv);
        s.clearcoat_normal = normalize(normal_from_texture(n_vertex, map_dpdu, map_dpdv, texel, m.clearcoat.z));
    }
    s.sheen_color = m.sheen.rgb * layer_texel(m.sheen_color_texture, m.sheen_color_uv_rows, uv0, uv1, footprint_lod).rgb;
    s.sheen_roughness = m.sheen.a *
        layer_texel(m.sheen_roughness_texture, m.sheen_roughness_uv_rows, uv0, uv1, footprint_lod).a;
}

// A material at one surface point.
struct MaterialPoint {
    vec4 base;                 // base colour × vertex colour × texture; a: alpha
    vec3 normal;               // after the normal texture and the bump; normalized only where either applied
    float height;              // the bump height B(u, v) (only where asked for: evaluate_material's with_height)
    vec3 emission;             // emissive factor × texture
    vec3 specular_color_texel;  // the specular colour texture's RGB alone (white without one)
    Shading shading;           // what the BRDF reads (brdf.glsl); its specular colour is factor × texel
};

// Evaluates material `m` at a point with vertex colour `vertex_color`, coordinates uv0 (TEXCOORD_0) and uv1,
// normal `n` (world space, on the geometry's own side) and surface derivatives dpdu, dpdv (world space, with
// respect to TEXCOORD_0). Textures scale their factors (glTF 2.0 §3.9.2, §3.9.5); the normal texture tilts n
// in the tangent frame of dpdu, dpdv through its transform, then the bump perturbs it (docs/architecture.md, "Blinn bump
// mapping"). `with_height`: also evaluate the height itself (the G-buffer stores it; ray hits skip it).
// `with_layers`: false where no material has layers (the accumulation pass's LAYERS), so that evaluate_layers's
// reads of up to ten textures, which no material would reach, are not compiled (docs/performance.md, "What LLVM
// spends a cold compile on").
MaterialPoint evaluate_material(GpuMaterial m, vec4 vertex_color, vec2 uv0, vec2 uv1, vec3 n, vec3 dpdu, vec3 dpdv,
                                vec2 footprint_lod, const bool with_height, const bool with_layers) {
    MaterialPoint p;
    vec3 n_vertex = n;
    p.base = m.base_color * vertex_color;
    if (m.base_color_texture >= 0) {
        p.base *= material_texture(m.base_color_texture, texture_uv(m.base_color_uv_rows, uv0, uv1),
                                   m.base_color_uv_rows, footprint_lod);
    }

    if (m.normal_texture >= 0) {
        // Normal textures read TEXCOORD_0 (a warning at load says so of any that name TEXCOORD_1).
        vec3 texel = material_texture(m.normal_texture, transform_uv(m.normal_uv_rows, uv0), m.normal_uv_rows,
                                      footprint_lod).xyz;
        vec3 map_dpdu = dpdu;
        vec3 map_dpdv = dpdv;
        transform_derivatives(m.normal_uv_rows, map_dpdu, map_dpdv);
        n = normal_from_texture(n, map_dpdu, map_dpdv, texel, m.normal_scale);
    }
    p.height = 0.0;
    if (m.bump.kind != BUMP_NONE) {
        vec2 gradient;
        if (with_height) {
            vec3 h = bump_height_and_gradient(m.bump, uv0);
            p.height = h.x;
            gradient = h.yz;
        } else {
            gradient = bump_gradient(m.bump, uv0);
        }
        n = bump_perturb_normal(n, dpdu, dpdv, gradient);
    }
    p.normal = n;

    p.emission = m.emissive.rgb;
    if (m.emissive_texture >= 0) {
        p.emission *= material_texture(m.emissive_texture, texture_uv(m.emissive_uv_rows, uv0, uv1),
                                       m.emissive_uv_rows, footprint_lod).rgb;
    }
    p.shading.albedo = p.base.rgb;
    // Metalness in B, roughness in G (glTF 2.0 §3.9.2).
    vec2 metallic_roughness = vec2(m.metallic, m.roughness);
    if (m.metallic_roughness_texture >= 0) {
        metallic_roughness *= material_texture(m.metallic_roughness_texture,
                                               texture_uv(m.metallic_roughness_uv_rows, uv0, uv1),
                                               m.metallic_roughness_uv_rows, footprint_lod).bg;
    }
    p.shading.metallic = metallic_roughness.x;
    p.shading.roughness = metallic_roughness.y;
    p.shading.transmission = m.transmission;
    if (m.transmission_texture >= 0) {
        p.shading.transmission *= material_texture(m.transmission_texture, texture_uv(m.transmission_uv_rows, uv0, uv1),
                                                   m.transmission_uv_rows, footprint_lod).r;
    }
    p.shading.ior = m.ior;
    p.shading.specular = m.emissive.w;
    if (m.specular_texture >= 0) {
        p.shading.specular *= material_texture(m.specular_texture, texture_uv(m.specular_uv_rows, uv0, uv1),
                                               m.specular_uv_rows, footprint_lod).a;
    }
    p.specular_color_texel = vec3(1.0);
    if (m.specular_color_texture >= 0) {
        p.specular_color_texel = material_texture(m.specular_color_texture,
                                                  texture_uv(m.specular_color_uv_rows, uv0, uv1),
                                                  m.specular_color_uv_rows, footprint_lod).rgb;
    }
    p.shading.specular_color = m.specular_color.rgb * p.specular_color_texel;
    p.shading.diffuse_share = 1.0;
    evaluate_layers(m, uv0, uv1, normalize(n_vertex), dpdu, dpdv, footprint_lod, with_layers, p.shading);
    if (m.unlit != 0) {
        // KHR_materials_unlit: the base colour is what the surface shows, as radiance; it reflects and transmits
        // nothing (specular 0 is F0 = F90 = 0, brdf.glsl). It is no light: light sampling never picks it (its
        // emissive factor is not read), so it reaches other surfaces only through their BSDF samples.
        p.emission = p.base.rgb;
        p.shading.albedo = vec3(0.0);
        p.shading.metallic = 0.0;
        p.shading.transmission = 0.0;
        p.shading.specular = 0.0;
    }
    return p;
}
#endif
