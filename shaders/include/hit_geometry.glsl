// What shading reads of the triangle a ray met: its vertex streams through the primitive records, its UVs and
// their footprint under a ray cone, its vertex colour and the alpha cut-out test. Include after
// accumulate_bindings.glsl.
#ifndef HIT_GEOMETRY_GLSL
#define HIT_GEOMETRY_GLSL
#include "material.glsl"
#include "sampling.glsl"
// A triangle a ray met: its primitive record, vertex indices and barycentric weights.
struct TriangleHit {
    GpuPrimitiveRecord r;
    uint i0;
    uint i1;
    uint i2;
    vec3 w;
};

TriangleHit triangle_hit(int record, uint tri, vec2 bc) {
    TriangleHit h;
    h.r = primitives[record];
    UintArray indices = UintArray(h.r.indices);
    h.i0 = indices.v[3u * tri];
    h.i1 = indices.v[3u * tri + 1u];
    h.i2 = indices.v[3u * tri + 2u];
    h.w = vec3(1.0 - bc.x - bc.y, bc.x, bc.y);
    return h;
}

// A hit's coordinates in one UV set (x, y) and twice its triangle's area in that set (z).
vec3 hit_uv_and_area(uint64_t set, TriangleHit h) {
    Vec2Array uvs = Vec2Array(set);
    vec2 a = uvs.v[h.i0];
    vec2 b = uvs.v[h.i1];
    vec2 c = uvs.v[h.i2];
    vec2 e1 = b - a;
    vec2 e2 = c - a;
    return vec3(h.w.x * a + h.w.y * b + h.w.z * c, abs(e1.x * e2.y - e1.y * e2.x));
}

// Ray cones for texture filtering at ray hits (Akenine-Möller et al., "Texture Level of Detail Strategies for
// Real-Time Ray Tracing", Ray Tracing Gems, 2019, ch. 20): a ray carries its pixel's footprint as a width at its
// origin and a spread angle, so a hit reads the mip level a direct view of the same footprint would. Reflection
// and refraction keep the spread (the surface's curvature is not known here; Boksansky et al., "Refraction Ray
// Cones for Texture Level of Detail", Ray Tracing Gems II, 2021, ch. 10, bend it at interfaces), and a rough lobe
// adds nothing: its spread is what the chain's samples integrate.
//
// The camera's pixel cone as (width at the eye, spread): a perspective pixel subtends α = 2·tan(fov_y/2)/height at
// the image's centre (the small-angle form of the chapter's pixel spread angle); an orthographic one keeps its width.
vec2 pixel_cone() {
    GpuCamera c = cameras[pc.counter_slot];
    float pixel = 2.0 * c.lens.y / float(pc.height);
    return c.range.z != 0.0 ? vec2(pixel, 0.0) : vec2(0.0, pixel);
}

// A cone of width `cone_width` meeting a triangle along `dir`, its footprint in a UV set's units as a level of
// detail: log2 of its width along the surface, w / |n·d|, times the UV length per unit of surface length,
// √(A_uv / A_world) (the chapter's triangle LOD term without the texture's own size, which texture_lod adds).
// `world_edges` is the cross product of the triangle's world-space edges (twice its area along its normal);
// `uv_area2` is twice its area in the UV set. The factors of two cancel.
float footprint_lod(float cone_width, vec3 world_edges, vec3 dir, float uv_area2) {
    float world_area2 = length(world_edges);
    float cos_d = abs(dot(world_edges, dir)) / max(world_area2, 1e-30);
    float width_along_surface = cone_width / max(cos_d, 1e-3);
    float uv_per_world = uv_area2 / max(world_area2, 1e-30);
    return 0.5 * log2(max(width_along_surface * width_along_surface * uv_per_world, 1e-30));
}

// Whether any texture the hit shading reads takes TEXCOORD_1 (normal textures read TEXCOORD_0).
bool any_texture_reads_uv1(GpuMaterial m) {
    bool layers = LAYERS != 0u && (reads_uv1(m.clearcoat_uv_rows) || reads_uv1(m.clearcoat_roughness_uv_rows) ||
                                   reads_uv1(m.sheen_color_uv_rows) || reads_uv1(m.sheen_roughness_uv_rows));
    return reads_uv1(m.base_color_uv_rows) || reads_uv1(m.metallic_roughness_uv_rows) ||
           reads_uv1(m.emissive_uv_rows) || reads_uv1(m.transmission_uv_rows) || reads_uv1(m.specular_uv_rows) ||
           reads_uv1(m.specular_color_uv_rows) || layers;
}

vec4 hit_color(TriangleHit h) {
    Vec4Array colors = Vec4Array(h.r.colors);
    return h.w.x * colors.v[h.i0] + h.w.y * colors.v[h.i1] + h.w.z * colors.v[h.i2];
}

// Ray hits read material textures at the level of detail of the ray's cone (material.glsl's contract).
vec4 material_texture(int index, vec2 uv, vec4 rows[2], vec2 footprint_lod) {
    return textureLod(textures[nonuniformEXT(index)], uv, texture_lod(rows, footprint_lod));
}

// Whether an alpha-tested material covers a point with this vertex colour alpha and these UVs: base colour ×
// vertex colour × texture alpha under the one alpha test (alpha_test_passes, as gbuffer.frag discards), the
// texture read at level of detail `lod`; `u`, BLEND's coverage sample.
bool material_covers(GpuMaterial m, float vertex_alpha, vec2 uv0, vec2 uv1, float lod, float u) {
    float alpha = m.base_color.a * vertex_alpha;
    if (m.base_color_texture >= 0) {
        alpha *= textureLod(textures[nonuniformEXT(m.base_color_texture)], texture_uv(m.base_color_uv_rows, uv0, uv1), lod).a;
    }
    return alpha_test_passes(m, alpha, u);
}

// BLEND's coverage sample for a ray's candidate hit: a hash of the sample, the triangle and where along which ray
// it lies (origins too: an orthographic camera's rays share one direction), so that paths, rays and surfaces draw
// independently, and both ways to trace draw alike.
float ray_coverage_sample(int record, uint primitive, vec3 origin, vec3 dir, float t) {
    uint h = pcg_hash(pc.seed ^ pcg_hash(pc.sample_index ^ pcg_hash(uint(record) ^ pcg_hash(primitive))));
    h = pcg_hash(h ^ floatBitsToUint(dir.x)) ^ pcg_hash(floatBitsToUint(dir.y) ^ pcg_hash(floatBitsToUint(dir.z)));
    h = pcg_hash(h ^ floatBitsToUint(origin.x)) ^ pcg_hash(floatBitsToUint(origin.y) ^ pcg_hash(floatBitsToUint(origin.z)));
    return unit_float(pcg_hash(h ^ floatBitsToUint(t)));
}

// Whether a candidate triangle of alpha-tested geometry covers its point, its texture read through the ray's cone
// (width at the origin, spread) as hit_surface reads textures, so a minified cut-out is as covered as the raster
// pass's mip-filtered view of it. Shadow rays carry no pixel footprint: a zero cone reads level 0. The one alpha
// test of both ways to trace: the ray-query loop (trace_query.glsl) and the any-hit shader (accumulate.rahit)
// pass the candidate's record, triangle, barycentrics, distance, transform and the ray's origin and direction.
bool alpha_covers(int record, uint primitive, vec2 barycentrics, float t, mat4x3 world_from_object, vec3 origin,
                  vec3 dir, vec2 cone) {
    TriangleHit h = triangle_hit(record, primitive, barycentrics);
    GpuMaterial m = materials[h.r.material];
    vec3 uv_area = hit_uv_and_area(reads_uv1(m.base_color_uv_rows) ? h.r.uvs1 : h.r.uvs, h);
    float lod = 0.0;
    if (m.base_color_texture >= 0 && cone != vec2(0.0)) {
        Vec3Array positions = Vec3Array(h.r.positions);
        vec3 p0 = positions.v[h.i0];
        mat3 m3 = mat3(world_from_object);
        vec3 world_edges = cross(m3 * (positions.v[h.i1] - p0), m3 * (positions.v[h.i2] - p0));
        float width = cone.x + cone.y * t;
        float footprint = footprint_lod(width, world_edges, dir, uv_area.z);
        lod = texture_lod(m.base_color_uv_rows, vec2(footprint));
    }
    // Only BLEND draws a coverage sample.
    float u = m.alpha_mode == ALPHA_BLEND ? ray_coverage_sample(record, primitive, origin, dir, t) : 0.0;
    return material_covers(m, hit_color(h).a, uv_area.xy, uv_area.xy, lod, u);
}
#endif
