// Direct light at a path vertex: one light chosen by power, a point on it, its shadow ray, MIS against the
// BSDF's rays. Part of the accumulation pass's shading body (path_tracer.glsl).
#ifndef DIRECT_LIGHT_GLSL
#define DIRECT_LIGHT_GLSL
#include "path_vertex.glsl"
#include "layers.glsl"

// The light whose share of the power CDF (emission.w, the running sum) holds u.x, and u.x rescaled to [0, 1)
// within that share: the pick and the point on the light come from one 2D sample, so its stratification carries
// over to the light (pbrt-v4's SampleDiscrete does the same). With the pick drawn from a dimension of its own, a
// quad emitter made of two triangles got a random half of each pixel's stratified points per triangle, and direct
// light had 5.9× Mitsuba 3's variance at 64 multi-jittered spp (docs/performance.md, "Speed at equal error").
uint pick_light(inout vec2 u) {
    uint lo = 0u;
    uint hi = pc.light_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u.x < lights[pc.light_offset + mid].emission.w) hi = mid; else lo = mid + 1u;
    }
    uint picked = pc.light_offset + lo;
    float below = lo > 0u ? lights[picked - 1u].emission.w : 0.0;
    float share = lights[picked].emission.w - below;
    u.x = share > 0.0 ? clamp((u.x - below) / share, 0.0, 0.99999994) : 0.5;
    return picked;
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
float diffuse_probability(Shading m, vec3 v) {
    return pc.indirect != 0u || pc.direct_light == DIRECT_BSDF_SAMPLING ? layered_diffuse_choice(m, v) : 0.0;
}

// Whether a path may go on from vertex `depth` (--bounces): the MIS weights of that vertex's light sample
// count on it.
bool room_to_bounce(uint depth) {
    return depth + 1u < pc.max_depth;
}

// The probability that it goes on by the specular lobe: what scales the gloss rays' density for MIS.
float specular_share(Shading m, vec3 v) {
    return 1.0 - diffuse_probability(m, v);
}

// One light sample: the light picked by power, a point on it, its shadow ray. With MIS the diffuse lobe takes it
// whole and the specular lobe shares it with the gloss rays by the power heuristic, when a gloss ray follows
// from this vertex (`bsdf_follows`); where the path ends here no BSDF sample covers the specular lobe, so the
// light sample takes it whole as well. Light sampling alone takes every lobe whole; BSDF sampling alone leaves
// the lights to the rays, except delta lights, which no ray can hit.
vec3 direct_light(Surface s, vec3 v, uint pixel, uint dim, bool bsdf_follows, inout uint shadow_rays) {
    if (pc.light_count == 0u) return vec3(0.0);
    vec2 u = sample2(pixel, dim + VERTEX_LIGHT);
    uint picked = pick_light(u);
    GpuLight l = lights[picked];
    float p = l.cone.w;
    if (!(p > 0.0)) return vec3(0.0);
    bool environment = HAS_ENVIRONMENT != 0u && l.position_kind.w == LIGHT_ENVIRONMENT;
    LightSample ls = environment ? sample_environment_light(u) : sample_light(l, s.position, u);
    if (pc.direct_light == DIRECT_BSDF_SAMPLING && !ls.delta) return vec3(0.0);
    if (l.position_kind.w == LIGHT_TRIANGLE && l.uv2_material.z >= 0.0) {
        // The emitter's material where the sample landed, as a ray hit there would see it (hit_surface): its
        // emissive texture scales the radiance, and where alpha-masking cuts the surface out nothing emits.
        GpuMaterial m = materials[int(l.uv2_material.z)];
        vec3 w = vec3(1.0 - ls.bary.x - ls.bary.y, ls.bary);
        vec2 uv0 = w.x * l.uv01.xy + w.y * l.uv01.zw + w.z * l.uv2_material.xy;
        vec2 uv1 = w.x * l.uv1_01.xy + w.y * l.uv1_01.zw + w.z * l.uv1_2.xy;
        // A BLEND emitter's coverage sample: hashed from the point sampled on it, as a ray's from its hit.
        float coverage_u = m.alpha_mode != ALPHA_BLEND ? 0.0
            : unit_float(pcg_hash(pcg_hash(floatBitsToUint(ls.bary.x) ^ pc.sample_index) ^ floatBitsToUint(ls.bary.y)));
        if (ALPHA_TESTED != 0u && m.alpha_mode != ALPHA_OPAQUE && !material_covers(m, dot(w, l.corner_alpha.xyz), uv0, uv1, 0.0, coverage_u)) {
            return vec3(0.0);
        }
        if (m.emissive_texture >= 0) {
            ls.value *= textureLod(textures[nonuniformEXT(m.emissive_texture)], texture_uv(m.emissive_uv_rows, uv0, uv1), 0.0).rgb;
        }
    }
    // Light from behind the face reaches only a surface that transmits diffusely, and only where the shading normal
    // agrees that it is behind (as a light in front of the face but behind the shading normal reflects nothing).
    bool behind = dot(s.geometric, ls.dir) <= 0.0;
    if (ls.value == vec3(0.0) || (behind && !transmits_diffusely(s.m))) return vec3(0.0);
    if (transmits_diffusely(s.m) && behind != (dot(s.normal, ls.dir) < 0.0)) return vec3(0.0);
    vec3 diffuse;
    vec3 specular;
    layered_brdf_cos(s.m, s.normal, v, ls.dir, diffuse, specular);
    if (!ls.delta && pc.direct_light == DIRECT_MIS && bsdf_follows) {
        specular *= power_heuristic(p * ls.pdf, specular_share(s.m, v) * layered_specular_pdf(s.m, s.normal, v, ls.dir));
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

#endif
