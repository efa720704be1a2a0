// What a ray finds: the background where it escapes, or a surface, its normals turned to the viewer, its
// material evaluated and its emission. Part of the accumulation pass's shading body (path_tracer.glsl).
#ifndef SURFACE_GLSL
#define SURFACE_GLSL
#include "path_vertex.glsl"
#include "layers.glsl"

// What a pixel shows where no surface is, along its primary ray's direction: the background colour, the
// environment, or nothing (a transparent background: alpha 0 and no radiance).
vec3 background_seen(vec3 dir) {
    if (pc.background.w == float(BACKGROUND_ENVIRONMENT) && environment_present()) return environment_radiance(dir);
    if (pc.background.w == float(BACKGROUND_TRANSPARENT)) return vec3(0.0);
    return pc.background.rgb;
}


// Turns the normals to the side the ray arrives from; arriving from behind means travelling inside. Then the
// one rule of emission, for every way a surface is seen (the G-buffer's visible surface, primary rays, gloss,
// translucency and diffuse rays): a surface emits towards a side only where light sampling could choose it
// (render/lights.rs), so a one-sided emitter is dark from behind, and light sampling and BSDF sampling agree
// on where light comes from. `emitter_density` is π · luminance · sides of the emissive factor on an emitting
// side (the density behind the lights' selection by power), else 0.
void face_viewer(inout Surface s, vec3 v, GpuMaterial m) {
    s.inside = dot(s.geometric, v) < 0.0;
    if (s.inside) {
        s.normal = -s.normal;
        s.geometric = -s.geometric;
        s.m.clearcoat_normal = -s.m.clearcoat_normal;
    }
    if (LAYERS != 0u) set_film(s.m, dot(s.normal, v));
    // brdf.glsl cannot see LAYERS: without layers the lobe is isotropic as a constant, so none of its anisotropic
    // code is compiled.
    if (LAYERS == 0u) s.m.anisotropy = 0.0;
    s.m.diffuse_share = diffuse_share_from(s.m, specular_albedo_terms(dot(s.normal, v), s.m.roughness));
    if (LAYERS != 0u) set_layer_shares(s.m, s.normal, v);
    s.absorption = m.absorption.rgb;
    s.dispersion = m.absorption.w;
    bool emits = m.double_sided != 0 || !s.inside;
    if (!emits) s.emission = vec3(0.0);
    float factor = luminance(m.emissive.rgb);
    s.emitter_density = emits && factor > 0.0 ? PI * factor * (m.double_sided != 0 ? 2.0 : 1.0) : 0.0;
}

// The visible surface the G-buffer holds at pixel `p` (covered: its surface ids `ids` name an instance).
Surface gbuffer_surface(ivec2 p, uvec4 ids, vec3 v) {
    GBufferTexel t = read_gbuffer(p, ids);
    Surface s;
    s.position = t.position;
    s.normal = t.shading_normal;
    s.geometric = t.geometric_normal;
    s.emission = t.emission;
    s.m.albedo = t.albedo.rgb;
    s.m.metallic = t.metallic;
    s.m.roughness = t.roughness;
    s.m.transmission = t.transmission;
    // The material's own index, not the G-buffer's 8-bit copy (glTF gives IOR no texture): at 1.5 the copy is
    // 1.494, and a glass slab entered at 45° by it and left by the exact index bent rays by 0.23° (1.2 cm over 3 m).
    s.m.ior = materials[t.material].ior;
    s.m.specular = t.specular;
    s.m.specular_color = materials[t.material].specular_color.rgb * t.specular_color_texel;
    // No layers: a layered material's visible surface is evaluated at a ray hit instead (gbuffer_vertex).
    s.m.clearcoat = 0.0;
    s.m.clearcoat_roughness = 0.0;
    s.m.clearcoat_normal = s.normal;
    s.m.sheen_color = vec3(0.0);
    s.m.sheen_roughness = 0.0;
    s.m.diffuse_transmission = 0.0;
    s.m.diffuse_transmission_color = vec3(1.0);
    s.m.iridescence = 0.0;
    s.m.film_dielectric = vec3(1.0);
    s.m.film_metal = vec3(1.0);
    s.m.anisotropy = 0.0;
    face_viewer(s, v, materials[t.material]);
    return s;
}

// The surface a ray hit, from the primitive's vertex streams, its material evaluated by the one evaluation the
// G-buffer pass uses too (material.glsl), so a surface looks the same seen directly, in a mirror or through glass. `visible` (a primary ray of the reference mode) also turns double-sided faces to the
// viewer, as the raster pass does; deeper hits keep their side, so a ray inside a double-sided transmissive mesh
// still knows it is inside.
Surface hit_surface(Hit hit, vec3 v, float cone_width, const bool visible) {
    TriangleHit h = triangle_hit(hit.record, hit.primitive, hit.barycentrics);
    mat4x3 world_from_object = hit.world_from_object;
    Vec3Array positions = Vec3Array(h.r.positions);
    vec3 p0 = positions.v[h.i0];
    vec3 p1 = positions.v[h.i1];
    vec3 p2 = positions.v[h.i2];
    Vec3Array normals = Vec3Array(h.r.normals);
    vec3 n_object = h.w.x * normals.v[h.i0] + h.w.y * normals.v[h.i1] + h.w.z * normals.v[h.i2];
    vec3 uv_area = hit_uv_and_area(h.r.uvs, h);
    vec2 uv = uv_area.xy;

    mat3 m3 = mat3(world_from_object);
    // Normals transform by the cofactor matrix (det · inverse transpose); the sign keeps mirrored instances right.
    mat3 cofactor = mat3(cross(m3[1], m3[2]), cross(m3[2], m3[0]), cross(m3[0], m3[1]));
    float det_sign = dot(m3[0], cross(m3[1], m3[2])) < 0.0 ? -1.0 : 1.0;
    Surface s;
    s.position = world_from_object * vec4(h.w.x * p0 + h.w.y * p1 + h.w.z * p2, 1.0);
    vec3 ng = det_sign * (cofactor * cross(p1 - p0, p2 - p0));  // ±(M·e1) × (M·e2): footprint_lod's world_edges
    s.geometric = normalize(ng);
    vec3 ns = det_sign * (cofactor * n_object);
    s.normal = dot(ns, ns) > 0.0 ? normalize(ns) : s.geometric;
    if (dot(s.normal, s.geometric) < 0.0) s.geometric = -s.geometric;

    GpuMaterial m = materials[h.r.material];
    vec3 uv1_area = any_texture_reads_uv1(m) ? hit_uv_and_area(h.r.uvs1, h) : uv_area;
    // The cone's footprint in each UV set; texture_lod adds each texture's own density.
    vec2 lod = vec2(footprint_lod(cone_width, ng, v, uv_area.z), footprint_lod(cone_width, ng, v, uv1_area.z));
    vec3 dpdu = vec3(0.0);
    vec3 dpdv = vec3(0.0);
    bool layer_frame = LAYERS != 0u && (m.clearcoat_normal_texture >= 0 || m.anisotropy.x > 0.0);
    if (m.normal_texture >= 0 || m.bump.kind != BUMP_NONE || layer_frame) {
        // Tangent vectors transform with the object matrix (gbuffer.vert).
        Vec3Array dpdus = Vec3Array(h.r.dpdu);
        Vec3Array dpdvs = Vec3Array(h.r.dpdv);
        dpdu = m3 * (h.w.x * dpdus.v[h.i0] + h.w.y * dpdus.v[h.i1] + h.w.z * dpdus.v[h.i2]);
        dpdv = m3 * (h.w.x * dpdvs.v[h.i0] + h.w.y * dpdvs.v[h.i1] + h.w.z * dpdvs.v[h.i2]);
    }
    MaterialPoint mp = evaluate_material(m, hit_color(h), uv, uv1_area.xy, s.normal, dpdu, dpdv, lod, false, LAYERS != 0u);
    s.normal = mp.normal;
    s.emission = mp.emission;
    s.m = mp.shading;
    // The raster pass turns double-sided faces seen from behind to the viewer: the same surface.
    if (visible && m.double_sided != 0 && dot(s.geometric, v) < 0.0) {
        s.normal = -s.normal;
        s.geometric = -s.geometric;
        s.m.clearcoat_normal = -s.m.clearcoat_normal;
    }
    face_viewer(s, v, m);
    return s;
}

#endif
