// A path from its visible vertex on: what each vertex adds, where the path goes on (GGX gloss and translucency,
// diffuse bounces with --indirect, Russian roulette) and what each ray finds. Part of the accumulation pass's
// shading body (path_tracer.glsl).
#ifndef PATH_GLSL
#define PATH_GLSL
#include "camera_ray.glsl"
#include "direct_light.glsl"
#include "dispersion.glsl"
#include "surface.glsl"

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

// Where a path stands between two vertices: the next ray and what it carries. Vertex 0 is the visible surface:
// the G-buffer's, or where the camera ray (the reference mode) hits. accumulate.comp moves chain rays between
// lanes field by field (shuffle_chain): a field added here goes there too.
struct ChainRay {
    vec3 origin;
    // Solid-angle density of a reflection (for MIS), 0 for a refraction, DIFFUSE_BOUNCE for a diffuse bounce.
    float pdf;
    vec3 dir;
    uint pixel;
    vec3 throughput;
    vec2 cone;  // the ray cone: width at the origin, spread angle (pixel_cone)
    vec2 t_range;  // where along the ray a hit counts: the camera's near and far depths, or (0, 1e30)
    uint depth;    // the vertex the ray leads to
    // 1: the ray only gathers the light it reaches (lights and emitters, not the background) and the path
    // ends at its hit: BSDF sampling's estimate of the direct light at the vertex it left (a path's last
    // vertex, or the diffuse lobe without diffuse interreflection).
    uint gather_only;
    // The colour channel the path carries since it met a dispersive surface, else ALL_CHANNELS (dispersion.glsl).
    uint channel;
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
    float u_lobe = sample1(r.pixel, dim + VERTEX_LOBE_CHOICE);
    float p_diffuse = diffuse_probability(s.m, v);
    if (u_lobe < p_diffuse) {
        // With diffuse transmission, the rest of u_lobe chooses the side: through the surface with p_through.
        float p_through = diffuse_transmit_choice(s.m);
        bool through = p_through > 0.0 && u_lobe < p_diffuse * p_through;
        float p_side = through ? p_through : 1.0 - p_through;
        vec3 side = through ? -s.normal : s.normal;
        r.dir = sample_cosine(side, sample2(r.pixel, dim + VERTEX_LOBE_DIRECTION));
        float nl = dot(side, r.dir);
        if (nl <= 0.0 || dot(s.geometric, r.dir) * (through ? -1.0 : 1.0) <= 0.0) return false;
        vec3 diffuse;
        vec3 specular;
        layered_brdf_cos(s.m, s.normal, v, r.dir, diffuse, specular);
        // f·cos / (p_diffuse · p_side · cos/π).
        weight = diffuse * (PI / (nl * p_diffuse * p_side));
        r.pdf = DIFFUSE_BOUNCE;
        if (pc.indirect == 0u) r.gather_only = 1u;
    } else {
        // The rest of u_lobe chooses between reflection and refraction.
        u_lobe = (u_lobe - p_diffuse) / (1.0 - p_diffuse);
        if (!sample_layered_specular(s.m, s.normal, v, s.inside, sample2(r.pixel, dim + VERTEX_LOBE_DIRECTION), u_lobe, r.dir, weight, r.pdf)) {
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
        float u = unit_float(pcg_hash(sampling_key(pc.seed, r.pixel, dim + VERTEX_ROULETTE) ^ pcg_hash(path_index)));
        if (u >= survive) return false;
        r.throughput /= survive;
    }
    r.origin = offset_origin(s.position, s.geometric, r.dir);
    r.t_range = vec2(0.0, 1e30);
    return true;
}

// Whether surface `s` refracts each colour channel by its own index (dispersion.glsl): it disperses and transmits.
bool disperses(Surface s) {
    return DISPERSION != 0u && s.dispersion > 0.0 && s.m.transmission > 0.0;
}

// At a surface that disperses (disperses(s)): the path's channel, chosen here at random if it has none yet (the
// vertex's roulette key, salted: independent of its lobe and light samples), and the surface's index for it.
// Returns the factor on what the path finds from here on: 3 on a channel chosen here and 0 on the others, else 1.
vec3 disperse(inout Surface s, vec3 v, inout ChainRay r, uint dim) {
    vec3 weight = vec3(1.0);
    if (r.channel == ALL_CHANNELS) {
        uint key = sampling_key(pc.seed, r.pixel, dim + VERTEX_ROULETTE) ^ pcg_hash(path_index);
        r.channel = min(uint(3.0 * unit_float(pcg_hash(key ^ 0x2545f491u))), 2u);
        weight = vec3(0.0);
        weight[r.channel] = 3.0;
    }
    s.m.ior = dispersed_ior(s.m.ior, s.dispersion, r.channel);
    s.m.diffuse_share = diffuse_share_from(s.m, specular_albedo_terms(dot(s.normal, v), s.m.roughness));
    return weight;
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

// The background a pixel of the G-buffer mode shows where it has no surface: along its ray through its own
// sub-pixel point and the lens centre.
vec3 background_behind(ivec2 p, uint pixel) {
    vec3 o;
    vec3 d;
    vec2 t_range;
    camera_ray(cameras[pc.counter_slot], p, camera_sample2(pixel, DIM_PIXEL) - 0.5, vec2(0.5), o, d, t_range);
    return background_seen(d);
}

// The G-buffer's visible surface at path r's pixel, seen from the camera, the ray cone grown to it. False where the
// pixel has no surface; `background` is then what it shows. `refind`: the surface's material has layers, which the
// G-buffer has no room for (docs/architecture.md, "Layered materials"), so r becomes a short ray along the view
// direction through the stored position, either side of it by the margin offset_origin uses, to meet the surface
// again and evaluate it at that hit; the G-buffer's own (unlayered) surface stands in if the ray misses.
bool gbuffer_vertex(inout ChainRay r, out Surface s, out vec3 v, out vec3 background, out bool refind) {
    ivec2 p = ivec2(r.pixel % pc.width, r.pixel / pc.width);
    uvec4 ids = read_gbuffer_surface_ids(p);
    background = vec3(0.0);
    if (ids.x == 0u) {
        background = background_behind(p, r.pixel);
        return false;
    }
    vec3 position = read_gbuffer_position(p);
    v = pc.eye.w != 0.0 ? -pc.forward.xyz : normalize(pc.eye.xyz - position);
    r.cone.x += r.cone.y * distance(pc.eye.xyz, position);
    s = gbuffer_surface(p, ids, v);
    refind = LAYERS != 0u && materials[ids.y].clearcoat.w != 0.0;
    if (refind) {
        float margin = 1e-4 * (1.0 + max(max(abs(position.x), abs(position.y)), abs(position.z)));
        r.origin = position + v * margin;
        r.dir = -v;
        r.t_range = vec2(0.0, 2.0 * margin);
    }
    return true;
}

// A path of pixel `pixel` before its visible vertex: in the reference mode its camera ray through its own sub-pixel
// point and lens point.
ChainRay start_path(uvec2 pixel) {
    ChainRay r;
    r.pixel = pixel.y * pc.width + pixel.x;
    r.depth = 0u;
    r.pdf = 0.0;
    r.throughput = vec3(1.0);
    r.gather_only = 0u;
    r.channel = ALL_CHANNELS;
    r.cone = pixel_cone();
    r.origin = vec3(0.0);
    r.dir = vec3(0.0, 0.0, -1.0);
    r.t_range = vec2(0.0, 1e30);
    if (PRIMARY_RAYS != 0u) {
        camera_ray(cameras[pc.counter_slot], ivec2(pixel), camera_sample2(r.pixel, DIM_PIXEL) - 0.5,
                   camera_sample2(r.pixel, DIM_LENS), r.origin, r.dir, r.t_range);
    }
    return r;
}

// Shades path `r` from vertex r.depth: the visible vertex alone (r.depth 0), or the chain after it. The visible
// vertex adds its emission (or the background, with alpha 0) and one light sample; each chain ray finds a light
// (MIS against light sampling; nothing for a diffuse bounce), the background, or a surface whose emission and one
// light sample it adds before going on. `goes_on`: the visible vertex's path has a chain, whose ray `r` becomes.
//
// One body for every vertex, called from one site per shader (docs/performance.md, "One call of the shading body"):
// lavapipe inlines every call, and with the visible vertex and the chain each holding a copy of direct light and its
// shadow-ray traversal, LLVM took 1.4–2.2 times as long to compile the pass. The visible vertex multiplies by its
// throughput of exactly 1, so it gives the bits it gave in a function of its own, with or without chain code.
vec4 trace_path(inout ChainRay r, out bool goes_on, inout uint shadow_rays, inout uint secondary_rays) {
    vec3 radiance = vec3(0.0);
    float alpha = 0.0;
    goes_on = false;
    while (r.depth <= pc.max_depth) {
        // Without chain code every call shades a visible vertex: a constant, so that none of the chain's code is
        // compiled (a loop-carried depth kept it, and cost the pass three times its compile time).
        uint depth = CHAINS != 0u ? r.depth : 0u;
        r.depth = depth + 1u;
        Surface s;
        vec3 v;
        float t_hit = 0.0;
        bool from_gbuffer = depth == 0u && PRIMARY_RAYS == 0u;
        bool refind = false;
        if (from_gbuffer) {
            vec3 background;
            if (!gbuffer_vertex(r, s, v, background, refind)) {
                radiance = background;
                break;
            }
        }
        if (!from_gbuffer || refind) {
            if (depth > 0u) secondary_rays++;
            log_ray(0u, r.origin, r.t_range.x, r.dir, r.t_range.y);
            // The G-buffer's surface met again: whatever the raster pass's alpha test kept, with no test of its own.
            Hit h = trace_closest(r.origin, r.dir, r.t_range.x, r.t_range.y, r.cone, refind ? gl_RayFlagsOpaqueEXT : 0u);
            bool hit = h.record != MISS;
            t_hit = hit ? h.t : 1e30;
            if (depth > 0u) {
                float light_density;
                vec3 light = lights_along(r.origin, r.dir, t_hit, light_density);
                if (light != vec3(0.0)) {
                    radiance += r.throughput * light * reached_light_weight(r.pdf, light_density);
                    break;
                }
            }
            if (!hit && !refind) {
                radiance += depth == 0u ? background_seen(r.dir) : r.throughput * escaped(r);
                break;
            }
            if (hit) {
                if (!refind) {
                    v = -r.dir;
                    r.cone.x += r.cone.y * t_hit;
                }
                s = hit_surface(h, v, r.cone.x, depth == 0u);
                // Arriving from inside, the ray crossed the medium this surface bounds: Beer–Lambert absorption over
                // the segment (KHR_materials_volume), for everything it finds here and beyond.
                if (depth > 0u && s.inside) r.throughput *= exp(-s.absorption * t_hit);
            }
        }
        uint dim = DIM_FIRST_VERTEX + DIMS_PER_VERTEX * depth;
        // A dispersive visible vertex weighs its own light and its chain by the channel it chose, after Russian
        // roulette (any survival probability is unbiased); deeper vertices weigh everything from the hit on.
        vec3 channel_weight = vec3(1.0);
        if (depth == 0u) {
            alpha = 1.0;
            if ((pc.sabotage & SABOTAGE_FLIPPED_NORMALS) != 0u) s.normal = -s.normal;
            if (disperses(s)) channel_weight = disperse(s, v, r, dim);
            radiance += s.emission;
        } else {
            if (disperses(s)) r.throughput *= disperse(s, v, r, dim);
            float density = 0.0;
            float cos_light = abs(dot(s.geometric, r.dir));
            if (s.emitter_density > 0.0 && pc.total_light_power > 0.0 && cos_light > 0.0) {
                density = s.emitter_density * t_hit * t_hit / (cos_light * pc.total_light_power);
            }
            radiance += r.throughput * s.emission * reached_light_weight(r.pdf, density);
            if (r.gather_only != 0u) break;
        }
        radiance += r.throughput * direct_light(s, v, r.pixel, dim, room_to_bounce(depth), shadow_rays);
        bool next = CHAINS != 0u && next_chain_ray(s, v, depth, r);
        if (depth == 0u) {
            r.throughput *= channel_weight;
            radiance *= channel_weight;
            goes_on = next;
            break;
        }
        if (!next) break;
    }
    return vec4(radiance, alpha);
}

#endif
