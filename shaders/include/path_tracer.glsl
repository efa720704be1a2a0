// The accumulation pass's shading body, one for both ways to trace: distributed ray tracing (Cook, Porter and
// Carpenter 1984) on top of one G-buffer sample, or (PRIMARY_RAYS, the reference mode) of a primary ray traced
// per pixel through its own sub-pixel point and lens point. Per pixel: emission, direct light from one light
// sample chosen by power with a shadow ray (soft shadows), then a chain of up to max_depth vertices whose
// directions are perturbed around the ideal reflection or refraction by GGX (gloss, translucency), each with its
// own direct light; with `indirect` on, paths also go on by the diffuse lobe (cosine-weighted), which adds
// diffuse interreflection (Kajiya 1986). It traces only through trace_closest and trace_occluded (trace.glsl),
// which trace_query.glsl (compute, ray queries) or trace_pipeline.glsl (raygen, traceRayEXT) define: the same
// body in accumulate.comp and accumulate.rgen, as Q2RTX builds its path tracer both ways.
#ifndef PATH_TRACER_GLSL
#define PATH_TRACER_GLSL
#include "environment.glsl"
#include "fixed_point.glsl"
// The rays a sample casts, as cast, for the benchmark's probe to replay without shading (render::ray_log);
// ProbeRay's layout (ray_probe.comp).
struct LoggedRay {
    vec3 origin;
    float t_min;
    vec3 dir;
    float t_max;
    uint flags;  // besides gl_RayFlagsOpaqueEXT
};
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer RayLog {
    uint count;  // rays cast, even beyond capacity
    uint capacity;
    uint pad0;
    uint pad1;
    LoggedRay rays[];
};

void log_ray(uint flags, vec3 origin, float t_min, vec3 dir, float t_max) {
    if (pc.ray_log == 0ul) return;
    RayLog log = RayLog(pc.ray_log);
    uint i = atomicAdd(log.count, 1u);
    if (i < log.capacity) log.rays[i] = LoggedRay(origin, t_min, dir, t_max, flags);
}

// Sampler dimensions (docs/architecture.md: pixel, time, lens, light, then bounces). The camera's (0-2) are drawn on the
// host for the whole image, except pixel and lens in the reference mode (per pixel, here).
const uint DIM_PIXEL = 0u;
const uint DIM_LENS = 2u;
const uint DIM_FIRST_VERTEX = 3u;
const uint DIMS_PER_VERTEX = 5u;  // light pick, light point (2D), lobe choice, lobe direction (2D)

struct Surface {
    float emitter_density;  // π · luminance · sides of an emitter that light sampling covers, else 0
    vec3 position;
    vec3 normal;     // shading normal, on the side of the incoming ray
    vec3 geometric;  // face normal, same side
    vec3 emission;
    bool inside;     // the incoming ray travels inside the material
    Shading m;
};

vec2 sample2(uint pixel, uint dim) {
    return sample_2d(pc.sampler_kind, pc.seed, pixel, pc.sample_index, pc.sample_count, dim);
}

float sample1(uint pixel, uint dim) {
    return sample_1d(pc.sampler_kind, pc.seed, pixel, pc.sample_index, pc.sample_count, dim);
}

// A ray origin just off the surface on the side the ray leaves towards (scaled to the position's magnitude).
vec3 offset_origin(vec3 p, vec3 ng, vec3 dir) {
    float eps = 1e-4 * (1.0 + max(max(abs(p.x), abs(p.y)), abs(p.z)));
    return p + ng * (dot(ng, dir) >= 0.0 ? eps : -eps);
}

bool occluded(vec3 o, vec3 d, float t_max) {
    if (t_max <= 0.0 || (pc.sabotage & SABOTAGE_NO_SHADOW_RAYS) != 0u) return false;
    log_ray(gl_RayFlagsTerminateOnFirstHitEXT, o, 0.0, d, t_max);
    return trace_occluded(o, d, t_max);
}

uint pick_light(float u) {
    uint lo = 0u;
    uint hi = pc.light_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u < lights[pc.light_offset + mid].emission.w) hi = mid; else lo = mid + 1u;
    }
    return pc.light_offset + lo;
}

// A direction towards the environment drawn by its distribution (environment.glsl): infinitely far, like a
// directional light, but with an area's density.
LightSample sample_environment_light(vec2 u) {
    LightSample s;
    s.dir = environment_sample(u, s.pdf);
    s.dist = 1e30;
    s.delta = false;
    s.bary = vec2(0.0);
    s.value = s.pdf > 0.0 ? environment_radiance(s.dir) / s.pdf : vec3(0.0);
    return s;
}

// Whether a light that is not geometry (a quad, disk or sphere light) lies on the shadow ray before t_max, other
// than the light sampled: paths end at such lights (lights_along), so a shadow ray must not see past them either,
// or light sampling would count light that BSDF sampling finds blocked. Asked only of shadow rays towards the
// environment, which every analytic light in the sky hides a part of: the test costs every shadow ray it is
// asked of (13% of the showcase's accumulation when asked of all), and between the other lights such overlap
// is rare (the one inconsistency left: a quad light in front of another light still lets its shadow rays by).
bool behind_analytic_light(vec3 o, vec3 d, float t_max, uint sampled) {
    for (uint i = 0u; i < pc.analytic_light_count; i++) {
        uint index = pc.light_offset + i;
        if (index != sampled && light_blocks(lights[index], o, d, t_max)) return true;
    }
    return false;
}

// Marks a ray that left by the diffuse lobe: light sampling at its vertex took every light whole (the diffuse
// lobe has no MIS), so the lights and emitters such a ray reaches add nothing, or they would count twice.
const float DIFFUSE_BOUNCE = -1.0;

// The probability that a path goes on by the diffuse lobe: 0 without diffuse interreflection, where light
// sampling takes that lobe whole, except when BSDF sampling alone estimates direct light.
float diffuse_probability(Shading m) {
    return pc.indirect != 0u || pc.direct_light == DIRECT_BSDF_SAMPLING ? diffuse_choice(m) : 0.0;
}

// Whether a path may go on from vertex `depth` (--bounces): the MIS weights of that vertex's light sample
// count on it.
bool room_to_bounce(uint depth) {
    return depth + 1u < pc.max_depth;
}

// The probability that it goes on by the specular lobe: what scales the gloss rays' density for MIS.
float specular_share(Shading m) {
    return 1.0 - diffuse_probability(m);
}

// One light sample: the light picked by power, a point on it, its shadow ray. With MIS the diffuse lobe takes it
// whole and the specular lobe shares it with the gloss rays by the power heuristic, when a gloss ray follows
// from this vertex (`bsdf_follows`); where the path ends here no BSDF sample covers the specular lobe, so the
// light sample takes it whole as well. Light sampling alone takes every lobe whole; BSDF sampling alone leaves
// the lights to the rays, except delta lights, which no ray can hit.
vec3 direct_light(Surface s, vec3 v, uint pixel, uint dim, bool bsdf_follows, inout uint shadow_rays) {
    if (pc.light_count == 0u) return vec3(0.0);
    uint picked = pick_light(sample1(pixel, dim));
    GpuLight l = lights[picked];
    float p = l.cone.w;
    if (!(p > 0.0)) return vec3(0.0);
    bool environment = HAS_ENVIRONMENT != 0u && l.position_kind.w == LIGHT_ENVIRONMENT;
    LightSample ls = environment ? sample_environment_light(sample2(pixel, dim + 1u))
                                 : sample_light(l, s.position, sample2(pixel, dim + 1u));
    if (pc.direct_light == DIRECT_BSDF_SAMPLING && !ls.delta) return vec3(0.0);
    if (l.position_kind.w == LIGHT_TRIANGLE && l.uv2_material.z >= 0.0) {
        // The emitter's material where the sample landed, as a ray hit there would see it (hit_surface): its
        // emissive texture scales the radiance, and where alpha-masking cuts the surface out nothing emits.
        GpuMaterial m = materials[int(l.uv2_material.z)];
        vec3 w = vec3(1.0 - ls.bary.x - ls.bary.y, ls.bary);
        vec2 uv0 = w.x * l.uv01.xy + w.y * l.uv01.zw + w.z * l.uv2_material.xy;
        vec2 uv1 = w.x * l.uv1_01.xy + w.y * l.uv1_01.zw + w.z * l.uv1_2.xy;
        if (ALPHA_TESTED != 0u && m.alpha_mode != 0 && !material_covers(m, dot(w, l.corner_alpha.xyz), uv0, uv1, 0.0)) {
            return vec3(0.0);
        }
        if (m.emissive_texture >= 0) {
            ls.value *= textureLod(textures[nonuniformEXT(m.emissive_texture)], texture_uv(m.emissive_uv_rows, uv0, uv1), 0.0).rgb;
        }
    }
    if (ls.value == vec3(0.0) || dot(s.geometric, ls.dir) <= 0.0) return vec3(0.0);
    vec3 diffuse;
    vec3 specular;
    brdf_cos(s.m, s.normal, v, ls.dir, diffuse, specular);
    if (!ls.delta && pc.direct_light == DIRECT_MIS && bsdf_follows) {
        specular *= power_heuristic(p * ls.pdf, specular_share(s.m) * specular_pdf(s.m, s.normal, v, ls.dir));
    }
    vec3 f = diffuse + specular;
    if (f == vec3(0.0)) return vec3(0.0);
    shadow_rays++;
    vec3 o = offset_origin(s.position, s.geometric, ls.dir);
    vec3 shadow_dir = ls.dir;
    float t_max = 1e30;
    if (ls.dist < 1e30) {
        // Aim from the offset origin at the sampled point itself and stop just short of it: emissive triangles
        // are geometry and must not shadow themselves. Measured from the surface point instead, the offset
        // (towards the light's plane, for a floor under a ceiling light) brought the light's plane nearer than
        // the margin where the light is seen at a grazing angle, and shadowed the light by itself.
        vec3 to_light = s.position + ls.dir * ls.dist - o;
        float dist = length(to_light);
        shadow_dir = to_light / dist;
        t_max = dist * (1.0 - 1e-4) - 1e-4 * (1.0 + dist);
    }
    if (occluded(o, shadow_dir, t_max)) return vec3(0.0);
    if (environment && behind_analytic_light(o, shadow_dir, t_max, picked)) return vec3(0.0);
    return f * ls.value / p;
}

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
    }
    bool emits = m.double_sided != 0 || !s.inside;
    if (!emits) s.emission = vec3(0.0);
    float factor = luminance(m.emissive.rgb);
    s.emitter_density = emits && factor > 0.0 ? PI * factor * (m.double_sided != 0 ? 2.0 : 1.0) : 0.0;
}

Surface gbuffer_surface(ivec2 p, uint material, vec3 v) {
    Surface s;
    vec4 pos = texelFetch(gbuffer[GBUFFER_POSITION], p, 0);
    vec4 mat = texelFetch(gbuffer[GBUFFER_MATERIAL], p, 0);
    s.position = pos.xyz;
    s.normal = normalize(texelFetch(gbuffer[GBUFFER_SHADING_NORMAL], p, 0).xyz);
    vec4 geometric = texelFetch(gbuffer[GBUFFER_GEOMETRIC_NORMAL], p, 0);
    s.geometric = normalize(geometric.xyz);
    s.emission = texelFetch(gbuffer[GBUFFER_EMISSION], p, 0).rgb;
    s.m.albedo = texelFetch(gbuffer[GBUFFER_ALBEDO], p, 0).rgb;
    s.m.metallic = mat.x;
    s.m.roughness = mat.y;
    s.m.transmission = mat.z;
    s.m.ior = unpack_ior(mat.w);
    s.m.specular = geometric.w;  // factor × texture, in the geometric normal's spare channel (gbuffer.frag)
    s.m.specular_color = materials[material].specular_color.rgb * texelFetch(gbuffer[GBUFFER_SPECULAR_COLOR], p, 0).rgb;
    face_viewer(s, v, materials[material]);
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
    if (m.normal_texture >= 0 || m.bump.kind != BUMP_NONE) {
        // Tangent vectors transform with the object matrix (gbuffer.vert).
        Vec3Array dpdus = Vec3Array(h.r.dpdu);
        Vec3Array dpdvs = Vec3Array(h.r.dpdv);
        dpdu = m3 * (h.w.x * dpdus.v[h.i0] + h.w.y * dpdus.v[h.i1] + h.w.z * dpdus.v[h.i2]);
        dpdv = m3 * (h.w.x * dpdvs.v[h.i0] + h.w.y * dpdvs.v[h.i1] + h.w.z * dpdvs.v[h.i2]);
    }
    MaterialPoint mp = evaluate_material(m, hit_color(h), uv, uv1_area.xy, s.normal, dpdu, dpdv, lod, false);
    s.normal = mp.normal;
    // The raster pass turns double-sided faces seen from behind to the viewer: the same surface.
    if (visible && m.double_sided != 0 && dot(s.geometric, v) < 0.0) {
        s.normal = -s.normal;
        s.geometric = -s.geometric;
    }
    s.emission = mp.emission;
    s.m = mp.shading;
    face_viewer(s, v, m);
    return s;
}

// The nearest non-geometry light along a ray, if nearer than t_max: its radiance, and in `density` the
// solid-angle density with which light sampling would have chosen that direction.
vec3 lights_along(vec3 o, vec3 d, float t_max, out float density) {
    vec3 result = vec3(0.0);
    density = 0.0;
    float nearest = t_max;
    for (uint i = 0u; i < pc.analytic_light_count; i++) {
        vec3 radiance;
        GpuLight l = lights[pc.light_offset + i];
        float t = intersect_light(l, o, d, nearest, radiance);
        if (t > 0.0) {
            nearest = t;
            result = radiance;
            density = l.cone.w * light_pdf(l, o, d, t);
        }
    }
    return result;
}

// Where a path goes on from one vertex: the next ray and what it carries.
struct ChainRay {
    vec3 origin;
    // Solid-angle density of a reflection (for MIS), 0 for a refraction, DIFFUSE_BOUNCE for a diffuse bounce.
    float pdf;
    vec3 dir;
    uint pixel;
    vec3 throughput;
    uint lane;  // the invocation whose pixel it belongs to
    vec2 cone;  // the ray cone: width at the origin, spread angle (pixel_cone)
    // 1: the ray only gathers the light it reaches (lights and emitters, not the background) and the path
    // ends at its hit: BSDF sampling's estimate of the direct light at the vertex it left (a path's last
    // vertex, or the diffuse lobe without diffuse interreflection).
    uint gather_only;
};

// A cosine-weighted direction about n (Malley's method: the concentric disk projected up onto the hemisphere).
vec3 sample_cosine(vec3 n, vec2 u) {
    vec2 d = concentric_disk(u);
    vec3 t;
    vec3 b;
    make_basis(n, t, b);
    return normalize(t * d.x + b * d.y + n * sqrt(max(0.0, 1.0 - dot(d, d))));
}

// The next direction of the path from vertex `depth`: with diffuse interreflection on, by the diffuse lobe
// (cosine-weighted) with probability diffuse_probability; otherwise GGX around the mirror or refracted direction.
// Then Russian roulette on weak paths (most of a dielectric's Fresnel reflection): unbiased, and cheap.
// Survival is 4x the weight: weak reflections still end most paths, at a quarter of the variance.
// Past the last vertex --bounces allows, BSDF sampling alone still casts one ray that only gathers light.
bool next_chain_ray(Surface s, vec3 v, uint depth, inout ChainRay r) {
    bool bsdf_only = pc.direct_light == DIRECT_BSDF_SAMPLING;
    if (!room_to_bounce(depth) && !bsdf_only) return false;
    r.gather_only = room_to_bounce(depth) ? 0u : 1u;
    uint dim = DIM_FIRST_VERTEX + DIMS_PER_VERTEX * depth;
    vec3 weight;
    float u_lobe = sample1(r.pixel, dim + 3u);
    float p_diffuse = diffuse_probability(s.m);
    if (u_lobe < p_diffuse) {
        r.dir = sample_cosine(s.normal, sample2(r.pixel, dim + 4u));
        float nl = dot(s.normal, r.dir);
        if (nl <= 0.0 || dot(s.geometric, r.dir) <= 0.0) return false;
        vec3 diffuse;
        vec3 specular;
        brdf_cos(s.m, s.normal, v, r.dir, diffuse, specular);
        // f·cos / (p_diffuse · cos/π).
        weight = diffuse * (PI / (nl * p_diffuse));
        r.pdf = DIFFUSE_BOUNCE;
        if (pc.indirect == 0u) r.gather_only = 1u;
    } else {
        // The rest of u_lobe chooses between reflection and refraction.
        u_lobe = (u_lobe - p_diffuse) / (1.0 - p_diffuse);
        if (!sample_specular(s.m, s.normal, v, s.inside, sample2(r.pixel, dim + 4u), u_lobe, r.dir, weight, r.pdf)) {
            return false;
        }
        // A reflection below the face, as light sampling sees it (direct_light), reflects nothing.
        if (r.pdf > 0.0 && dot(s.geometric, r.dir) <= 0.0) return false;
        weight /= 1.0 - p_diffuse;
        r.pdf *= 1.0 - p_diffuse;
    }
    r.throughput *= weight;
    float survive = min(1.0, 4.0 * max(r.throughput.x, max(r.throughput.y, r.throughput.z)));
    if (survive < 1.0) {
        float u = unit_float(pcg_hash(sampling_key(pc.seed, r.pixel, dim + 2u) ^ pcg_hash(pc.sample_index)));
        if (u >= survive) return false;
        r.throughput /= survive;
    }
    r.origin = offset_origin(s.position, s.geometric, r.dir);
    return true;
}

// The visible vertex: emission and one light sample. Returns whether a chain ray goes on from it.
vec3 shade_visible(Surface s, vec3 v, inout ChainRay r, out bool chain, inout uint shadow_rays) {
    if ((pc.sabotage & SABOTAGE_FLIPPED_NORMALS) != 0u) s.normal = -s.normal;
    vec3 radiance = s.emission + direct_light(s, v, r.pixel, DIM_FIRST_VERTEX, room_to_bounce(0u), shadow_rays);
    r.throughput = vec3(1.0);
    chain = next_chain_ray(s, v, 0u, r);
    return radiance;
}

// The weight of light a chain ray reaches, which light sampling chooses with solid-angle density
// `light_density` (0: never, as for a refraction, which light sampling never covers: the ray has it alone).
// With MIS a reflection (pdf > 0) shares it by the power heuristic and a diffuse bounce leaves it to light
// sampling, which took that lobe whole; light sampling alone leaves rays nothing it covers, BSDF sampling alone
// gives them everything.
float reached_light_weight(float pdf, float light_density) {
    if (!(light_density > 0.0) || pdf == 0.0 || pc.direct_light == DIRECT_BSDF_SAMPLING) return 1.0;
    if (pc.direct_light == DIRECT_LIGHT_SAMPLING || pdf == DIFFUSE_BOUNCE) return 0.0;
    return power_heuristic(pdf, light_density);
}

// The light an escaping ray finds: the environment, a light like any other (MIS against light sampling; a
// gather-only ray gathers it), or without one the background colour (not a light: gather-only rays skip it).
vec3 escaped(ChainRay r) {
    if (environment_present()) {
        float density = lights[pc.light_offset].cone.w * environment_pdf(r.dir);
        return environment_radiance(r.dir) * reached_light_weight(r.pdf, density);
    }
    return r.gather_only == 0u ? pc.background.rgb : vec3(0.0);
}

// The chain from vertex 1 on: each ray finds a light (MIS against light sampling; nothing for a diffuse
// bounce), the background, or a surface whose emission and one light sample it adds before going on.
vec3 follow_chain(ChainRay r, inout uint shadow_rays, inout uint secondary_rays) {
    vec3 radiance = vec3(0.0);
    for (uint depth = 1u; depth <= pc.max_depth; depth++) {
        secondary_rays++;
        log_ray(0u, r.origin, 0.0, r.dir, 1e30);
        Hit h = trace_closest(r.origin, r.dir, 0.0, 1e30, r.cone);
        bool hit = h.record != MISS;
        float t_hit = hit ? h.t : 1e30;
        float light_density;
        vec3 light = lights_along(r.origin, r.dir, t_hit, light_density);
        if (light != vec3(0.0)) {
            radiance += r.throughput * light * reached_light_weight(r.pdf, light_density);
            break;
        }
        if (!hit) {
            radiance += r.throughput * escaped(r);
            break;
        }
        vec3 v = -r.dir;
        r.cone.x += r.cone.y * t_hit;
        Surface s = hit_surface(h, v, r.cone.x, false);
        float density = 0.0;
        float cos_light = abs(dot(s.geometric, r.dir));
        if (s.emitter_density > 0.0 && pc.total_light_power > 0.0 && cos_light > 0.0) {
            density = s.emitter_density * t_hit * t_hit / (cos_light * pc.total_light_power);
        }
        radiance += r.throughput * s.emission * reached_light_weight(r.pdf, density);
        if (r.gather_only != 0u) break;
        uint dim = DIM_FIRST_VERTEX + DIMS_PER_VERTEX * depth;
        radiance += r.throughput * direct_light(s, v, r.pixel, dim, room_to_bounce(depth), shadow_rays);
        if (!next_chain_ray(s, v, depth, r)) break;
    }
    return radiance;
}

// The reference mode's primary ray for pixel p: through the point p + ½ − jitter of the image (the raster
// pass's jitter convention, camera_sample in src/math/lens.rs) from a point on the thin lens, aimed so that the
// plane at the focus distance stays sharp (docs/architecture.md, "Thin lens"). t_range clips at the near and far depths,
// as the raster pass does.
void camera_ray(GpuCamera c, ivec2 p, vec2 jitter, vec2 lens_uv, out vec3 origin, out vec3 dir, out vec2 t_range) {
    vec2 ndc = (vec2(p) + 0.5 - jitter) / vec2(pc.width, pc.height) * 2.0 - 1.0;
    // View space: x right, y up (the image's y runs down), looking down -z.
    vec2 plane = vec2(ndc.x, -ndc.y) * c.lens.xy;
    vec3 o_view;
    vec3 d_view;
    if (c.range.z != 0.0) {
        o_view = vec3(plane, 0.0);
        d_view = vec3(0.0, 0.0, -1.0);
    } else {
        vec2 offset = c.lens.z > 0.0 ? concentric_disk(lens_uv) * c.lens.z : vec2(0.0);
        o_view = vec3(offset, 0.0);
        d_view = vec3(plane * c.lens.w, -c.lens.w) - o_view;
    }
    origin = (c.world_from_camera * vec4(o_view, 1.0)).xyz;
    vec3 d = mat3(c.world_from_camera) * d_view;
    float len = length(d);
    dir = d / len;
    // Depth along the view axis grows by -d_view.z / len per unit of t.
    float depth_per_t = -d_view.z / len;
    t_range = vec2(c.range.x / depth_per_t, min(c.range.y / depth_per_t, 1e30));
}

// The visible surface's own light (or the background), for pixel `pixel` of the image: from the G-buffer, or
// (PRIMARY_RAYS) from the pixel's own primary ray. `r` becomes the path's chain ray when `chain` is set.
vec4 shade_primary(uvec2 pixel, uint lane, out ChainRay r, out bool chain, inout uint shadow_rays) {
    ivec2 p = ivec2(pixel);
    vec4 value = vec4(0.0);
    chain = false;
    r.pixel = pixel.y * pc.width + pixel.x;
    r.lane = lane;
    r.gather_only = 0u;
    r.cone = pixel_cone();
    if (PRIMARY_RAYS != 0u) {
        vec3 o;
        vec3 d;
        vec2 t_range;
        camera_ray(cameras[pc.counter_slot], p, sample2(r.pixel, DIM_PIXEL) - 0.5, sample2(r.pixel, DIM_LENS), o, d,
                   t_range);
        log_ray(0u, o, t_range.x, d, t_range.y);
        Hit h = trace_closest(o, d, t_range.x, t_range.y, r.cone);
        if (h.record != MISS) {
            r.cone.x += r.cone.y * h.t;
            Surface s = hit_surface(h, -d, r.cone.x, true);
            value = vec4(shade_visible(s, -d, r, chain, shadow_rays), 1.0);
        } else {
            value = vec4(background_seen(d), 0.0);
        }
    } else {
        uvec2 ids = texelFetch(gbuffer_ids, p, 0).xy;
        if (ids.x != 0u) {
            vec3 position = texelFetch(gbuffer[GBUFFER_POSITION], p, 0).xyz;
            vec3 v = pc.eye.w != 0.0 ? -pc.forward.xyz : normalize(pc.eye.xyz - position);
            r.cone.x += r.cone.y * distance(pc.eye.xyz, position);
            Surface s = gbuffer_surface(p, ids.y, v);
            value = vec4(shade_visible(s, v, r, chain, shadow_rays), 1.0);
        } else {
            // The direction this pixel looks in, through its own sub-pixel point and the lens centre.
            vec3 o;
            vec3 d;
            vec2 t_range;
            camera_ray(cameras[pc.counter_slot], p, sample2(r.pixel, DIM_PIXEL) - 0.5, vec2(0.5), o, d, t_range);
            value = vec4(background_seen(d), 0.0);
        }
    }
    return value;
}

// Adds a pixel's sample (its visible surface's light and its chain's) to its sum, in fixed point (the host
// zeroes the sums before a frame's first sample, or loads them from a checkpoint or a partial render).
void accumulate_sample(uvec2 pixel, vec4 value) {
    // A sample that went wrong must not poison the pixel's whole estimate.
    if (any(isnan(value)) || any(isinf(value))) value = vec4(0.0, 0.0, 0.0, value.w == value.w ? value.w : 0.0);
    // For the tests' error estimates: the sample's squared luminance instead of its coverage.
    if (pc.alpha_moment != 0u) value.w = luminance(value.rgb) * luminance(value.rgb);
    uint i = pixel.y * pc.width + pixel.x;
    sums[i] += to_fixed_point(value);
}
#endif
