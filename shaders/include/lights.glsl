// Sampling lights for soft shadows (Cook, Porter and Carpenter 1984): a point on an area light chosen per pixel
// and sample, with the solid-angle conversion (cos θ_light · area / distance²) or, for spheres, uniform sampling
// of the visible cone; and intersecting the lights that are not geometry along specular rays.
// Layout of GpuLight in accumulate_layout.glsl; CPU side in src/render/lights.rs.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL
#include "accumulate_layout.glsl"
#include "brdf.glsl"

struct LightSample {
    vec3 dir;    // unit, from the shaded point towards the light
    float dist;  // to the sampled point (infinite for directional lights)
    vec3 value;  // incident radiance / pdf (solid angle), or intensity / d² for delta lights
    float pdf;   // solid-angle density of the direction (0 for delta lights)
    bool delta;  // a point or directional light: no area, the specular lobe is evaluated directly
    vec2 bary;   // triangles: the sampled point's barycentrics of p1 and p2
};

// KHR_lights_punctual's smooth spot falloff for a light shining along `axis`, seen in direction `to_point`.
float spot_falloff(GpuLight l, vec3 to_point) {
    if (l.position_kind.w != LIGHT_SPOT) return 1.0;
    float cd = dot(l.normal.xyz, to_point);
    float scale = 1.0 / max(1e-3, l.cone.y - l.cone.x);
    float t = clamp((cd - l.cone.x) * scale, 0.0, 1.0);
    return t * t;
}

// KHR_lights_punctual's range of a point or spot light at distance d from it: the extension's recommended
// window max(min(1 − (d / range)⁴, 1), 0) on top of the inverse square law; 1 without a range.
float range_window(GpuLight l, float d) {
    float range = l.cone.z;
    if (!(range > 0.0) || (l.position_kind.w != LIGHT_POINT && l.position_kind.w != LIGHT_SPOT)) return 1.0;
    float q = d / range;
    return clamp(1.0 - q * q * q * q, 0.0, 1.0);
}

// Radiance of a sphere-shaped light: spheres carry it; a point or spot of radius r and intensity I has
// L = I / (π r²) (its projected disk emits I).
vec3 sphere_radiance(GpuLight l) {
    if (l.position_kind.w == LIGHT_SPHERE) return l.emission.rgb;
    float r = l.axis_u.w;
    return l.emission.rgb / (PI * r * r);
}

bool is_sphere_like(GpuLight l) {
    float k = l.position_kind.w;
    return k == LIGHT_SPHERE || ((k == LIGHT_POINT || k == LIGHT_SPOT) && l.axis_u.w > 0.0);
}

LightSample sample_light(GpuLight l, vec3 x, vec2 u) {
    LightSample s;
    s.value = vec3(0.0);
    s.pdf = 0.0;
    s.delta = false;
    s.dist = 0.0;
    s.dir = vec3(0.0, 1.0, 0.0);
    s.bary = vec2(0.0);
    float kind = l.position_kind.w;
    vec3 c = l.position_kind.xyz;
    if (kind == LIGHT_DIRECTIONAL) {
        s.dir = -l.normal.xyz;
        s.dist = 1e30;
        s.value = l.emission.rgb;
        s.delta = true;
        return s;
    }
    if (is_sphere_like(l)) {
        // Uniform in the cone of directions the sphere subtends; pdf = 1 / (2π (1 − cos θmax)).
        float r = l.axis_u.w;
        vec3 d = c - x;
        float dist2 = dot(d, d);
        if (dist2 <= r * r) return s;
        float sin2 = r * r / dist2;
        float cos_max = sqrt(max(0.0, 1.0 - sin2));
        float one_minus_cos_max = sin2 / (1.0 + cos_max);
        float cos_t = 1.0 - u.x * one_minus_cos_max;
        float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
        float phi = 2.0 * PI * u.y;
        vec3 w = d * inversesqrt(dist2);
        vec3 t;
        vec3 b;
        make_basis(w, t, b);
        s.dir = normalize((t * cos(phi) + b * sin(phi)) * sin_t + w * cos_t);
        float tc = dot(d, s.dir);
        s.dist = tc - sqrt(max(0.0, r * r - (dist2 - tc * tc)));
        s.value = sphere_radiance(l) * (2.0 * PI * one_minus_cos_max) * spot_falloff(l, -w) *
                  range_window(l, sqrt(dist2));
        s.pdf = 1.0 / (2.0 * PI * one_minus_cos_max);
        return s;
    }
    if (kind == LIGHT_POINT || kind == LIGHT_SPOT) {
        vec3 d = c - x;
        float dist2 = dot(d, d);
        if (!(dist2 > 0.0)) return s;
        s.dist = sqrt(dist2);
        s.dir = d / s.dist;
        s.value = l.emission.rgb / dist2 * spot_falloff(l, -s.dir) * range_window(l, s.dist);
        s.delta = true;
        return s;
    }
    // Area lights sampled uniformly by area: pdf_area = 1 / A, so L / pdf_ω = L · cos θ_light · A / d².
    vec3 y;
    if (kind == LIGHT_QUAD) {
        y = c + (2.0 * u.x - 1.0) * l.axis_u.xyz + (2.0 * u.y - 1.0) * l.axis_v.xyz;
    } else if (kind == LIGHT_DISK) {
        vec2 a = u * 2.0 - 1.0;
        vec2 disk = vec2(0.0);
        if (a.x != 0.0 || a.y != 0.0) {
            // Concentric mapping (Shirley and Chiu 1997), as math/lens.rs.
            float r;
            float theta;
            if (abs(a.x) > abs(a.y)) {
                r = a.x;
                theta = (PI / 4.0) * (a.y / a.x);
            } else {
                r = a.y;
                theta = PI / 2.0 - (PI / 4.0) * (a.x / a.y);
            }
            disk = r * vec2(cos(theta), sin(theta));
        }
        y = c + disk.x * l.axis_u.xyz + disk.y * l.axis_v.xyz;
    } else if (kind == LIGHT_PARALLELOGRAM) {
        y = c + u.x * l.axis_u.xyz + u.y * l.axis_v.xyz;
    } else {
        // Triangle: uniform barycentrics by Heitz's low-distortion map ("A Low-Distortion Map Between Triangle and
        // Square", 2019), which keeps a stratified sample's strata compact on the triangle.
        float su = sqrt(u.x);
        s.bary = vec2(su * (1.0 - u.y), su * u.y);
        y = c + s.bary.x * l.axis_u.xyz + s.bary.y * l.axis_v.xyz;
    }
    vec3 d = y - x;
    float dist2 = dot(d, d);
    if (!(dist2 > 0.0)) return s;
    s.dist = sqrt(dist2);
    s.dir = d / s.dist;
    float cos_light = -dot(l.normal.xyz, s.dir);
    if (l.normal.w != 0.0) cos_light = abs(cos_light);
    if (cos_light <= 0.0) return s;
    s.value = l.emission.rgb * cos_light * l.axis_v.w / dist2;
    s.pdf = dist2 / (cos_light * l.axis_v.w);
    return s;
}

// The solid-angle density with which sample_light picks the direction that reaches light `l` at distance t from
// x (the ray direction d), before the light's selection probability.
float light_pdf(GpuLight l, vec3 x, vec3 d, float t) {
    if (is_sphere_like(l)) {
        float r = l.axis_u.w;
        vec3 c = l.position_kind.xyz - x;
        float dist2 = dot(c, c);
        if (dist2 <= r * r) return 0.0;
        float sin2 = r * r / dist2;
        float one_minus_cos_max = sin2 / (1.0 + sqrt(max(0.0, 1.0 - sin2)));
        return 1.0 / (2.0 * PI * one_minus_cos_max);
    }
    float cos_light = abs(dot(l.normal.xyz, d));
    float area = l.axis_v.w;
    return cos_light > 0.0 && area > 0.0 ? t * t / (cos_light * area) : 0.0;
}

// The distance to light `l`'s surface along the ray (o, d) if it is hit in (0, t_max) on an emitting side;
// otherwise −1. Only for lights that are not geometry (spheres, spots and points with a radius, quads, disks).
float light_surface_hit(GpuLight l, vec3 o, vec3 d, float t_max) {
    float kind = l.position_kind.w;
    vec3 c = l.position_kind.xyz;
    if (is_sphere_like(l)) {
        float r = l.axis_u.w;
        vec3 oc = o - c;
        float bq = dot(oc, d);
        float cq = dot(oc, oc) - r * r;
        float disc = bq * bq - cq;
        if (disc < 0.0 || cq <= 0.0) return -1.0;
        float t = -bq - sqrt(disc);
        return t > 0.0 && t < t_max ? t : -1.0;
    }
    if (kind != LIGHT_QUAD && kind != LIGHT_DISK) return -1.0;
    vec3 n = l.normal.xyz;
    float denom = dot(d, n);
    if (denom == 0.0) return -1.0;
    // Emitting towards +n: the ray must travel against n unless both sides emit.
    if (denom > 0.0 && l.normal.w == 0.0) return -1.0;
    float t = dot(c - o, n) / denom;
    if (t <= 0.0 || t >= t_max) return -1.0;
    vec3 p = o + t * d - c;
    float su = dot(p, l.axis_u.xyz) / dot(l.axis_u.xyz, l.axis_u.xyz);
    float sv = dot(p, l.axis_v.xyz) / dot(l.axis_v.xyz, l.axis_v.xyz);
    bool inside = kind == LIGHT_QUAD ? (abs(su) <= 1.0 && abs(sv) <= 1.0) : (su * su + sv * sv <= 1.0);
    return inside ? t : -1.0;
}

// Whether the ray (o, d) meets light `l`'s surface in (0, t_max) on an emitting side, for shadow rays (what
// paths stop at, shadow rays must not see through).
bool light_blocks(GpuLight l, vec3 o, vec3 d, float t_max) {
    return light_surface_hit(l, o, d, t_max) > 0.0;
}

// The distance to light `l`'s surface along the ray (o, d) if it is hit in (0, t_max) on an emitting side, with
// the radiance it sends back along −d; otherwise −1. Only for lights that are not geometry.
float intersect_light(GpuLight l, vec3 o, vec3 d, float t_max, out vec3 radiance) {
    radiance = vec3(0.0);
    float t = light_surface_hit(l, o, d, t_max);
    if (t < 0.0) return -1.0;
    vec3 c = l.position_kind.xyz;
    radiance = is_sphere_like(l)
        ? sphere_radiance(l) * spot_falloff(l, normalize(o + t * d - c)) * range_window(l, length(o - c))
        : l.emission.rgb;
    return t;
}
#endif
