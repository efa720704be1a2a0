// The layers over a glTF material's base (docs/architecture.md, "Layered materials"): KHR_materials_sheen's fibres
// (the "Charlie" lobe: Estevez and Kulla 2017, "Production Friendly Microfacet Sheen BRDF") and over them
// KHR_materials_clearcoat's clear coat (GGX with a dielectric's Fresnel, IOR 1.5). As the extensions give it, each
// layer adds its lobe and scales what lies under it by what it leaves (albedo scaling): the coat by 1 − c·E_coat(v),
// the sheen by 1 − max(colour)·E_sheen(v), each E the layer's directional albedo towards the viewer from the albedo
// tables (math::brdf), so that a white base under any layers reflects what arrives in a white furnace
// (tests/layers.rs). The sheen lobe joins the diffuse lobe's estimators (light sampling; cosine-weighted bounces), the
// coat the specular lobe's (light sampling and gloss rays, one mixture density for MIS). Part of the accumulation
// pass's shading body (included by surface.glsl); a scene without layers (LAYERS 0) compiles none of it.
// CPU twins: math::sheen, math::ggx.
#ifndef LAYERS_GLSL
#define LAYERS_GLSL

// An albedo table (the one starting at albedo_tables[first]) at view cosine `nv` and `roughness`, read
// bilinearly, clamped at its edges, as math::brdf::lookup reads it.
vec2 albedo_table(uint first, float nv, float roughness) {
    float x = clamp(clamp(nv, 0.0, 1.0) * float(SPECULAR_ALBEDO_MU_STEPS) - 0.5, 0.0, float(SPECULAR_ALBEDO_MU_STEPS - 1u));
    float y = clamp(roughness, 0.0, 1.0) * float(SPECULAR_ALBEDO_ROUGHNESS_STEPS - 1u);
    uint x0 = uint(floor(x));
    uint y0 = uint(floor(y));
    uint x1 = min(x0 + 1u, SPECULAR_ALBEDO_MU_STEPS - 1u);
    uint y1 = min(y0 + 1u, SPECULAR_ALBEDO_ROUGHNESS_STEPS - 1u);
    float fx = x - float(x0);
    float fy = y - float(y0);
    uint row0 = first + y0 * SPECULAR_ALBEDO_MU_STEPS;
    uint row1 = first + y1 * SPECULAR_ALBEDO_MU_STEPS;
    vec2 top = mix(albedo_tables[row0 + x0], albedo_tables[row0 + x1], fx);
    vec2 bottom = mix(albedo_tables[row1 + x0], albedo_tables[row1 + x1], fx);
    return mix(top, bottom, fy);
}

// The specular lobe's directional albedo terms (E1, E5) at view cosine `nv` and `roughness` (math::brdf).
vec2 specular_albedo_terms(float nv, float roughness) {
    return albedo_table(0u, nv, roughness);
}

// The coat's reflectance at normal incidence: ((1.5 − 1) / (1.5 + 1))², its Fresnel reaching 1 at grazing.
const float COAT_F0 = 0.04;

float sheen_alpha(float roughness) {
    float r = max(roughness, 1e-3);
    return r * r;
}

// The Charlie distribution (the paper's eq. 2): (2 + 1/α) sin^(1/α)(θ_h) / (2π).
float charlie_d(float nh, float a) {
    float sin2 = max(1.0 - nh * nh, 0.0);
    return (2.0 + 1.0 / a) * pow(sin2, 0.5 / a) / (2.0 * PI);
}

// The paper's fit of ln Λ (its Table 1, eq. 3), between its fits at roughness 0 and 1 by (1 − α)², as the
// extension's sample renderer interpolates.
float sheen_lambda_fit(float x, float a) {
    float t = (1.0 - a) * (1.0 - a);
    float fa = mix(21.5473, 25.3245, t);
    float fb = mix(3.82987, 3.32435, t);
    float fc = mix(0.19823, 0.16801, t);
    float fd = mix(-1.97760, -1.27393, t);
    float fe = mix(-4.32054, -4.85967, t);
    return fa / (1.0 + fb * pow(x, fc)) + fd * x + fe;
}

float sheen_lambda(float c, float a) {
    return c < 0.5 ? exp(sheen_lambda_fit(c, a)) : exp(2.0 * sheen_lambda_fit(0.5, a) - sheen_lambda_fit(1.0 - c, a));
}

// V = 1 / ((1 + Λ(v) + Λ(l)) · 4 n·l n·v), kept within [0, 1] as the sample renderer keeps it.
float sheen_visibility(float nl, float nv, float a) {
    return clamp(1.0 / ((1.0 + sheen_lambda(nv, a) + sheen_lambda(nl, a)) * (4.0 * nv * nl)), 0.0, 1.0);
}

// The white sheen lobe's directional albedo at view cosine nv. A smooth sheen seen at grazing reflects more than
// arrives (up to 1.5, math::brdf's test), so the lobe is divided by max(1, E) and reflects min(E, 1).
float sheen_albedo(float nv, float roughness) {
    return albedo_table(SHEEN_ALBEDO_TABLE, nv, roughness).x;
}

// The coat's directional albedo at view cosine nv: Schlick's F0 + (1 − F0)(1 − v·h)⁵ through the GGX terms.
float coat_albedo(float nv, float roughness) {
    vec2 terms = specular_albedo_terms(nv, roughness);
    return COAT_F0 * terms.x + (1.0 - COAT_F0) * terms.y;
}

bool has_sheen(Shading m) {
    return LAYERS != 0u && max(m.sheen_color.r, max(m.sheen_color.g, m.sheen_color.b)) > 0.0;
}

bool has_coat(Shading m) {
    return LAYERS != 0u && m.clearcoat > 0.0;
}

// What the coat leaves to the layers under it and the sheen to the base, seen from v (the normals on v's side).
void set_layer_shares(inout Shading m, vec3 n, vec3 v) {
    m.coat_share = has_coat(m) ? 1.0 - m.clearcoat * coat_albedo(dot(m.clearcoat_normal, v), m.clearcoat_roughness) : 1.0;
    float sheen = max(m.sheen_color.r, max(m.sheen_color.g, m.sheen_color.b));
    m.sheen_share = has_sheen(m) ? 1.0 - sheen * min(sheen_albedo(dot(n, v), m.sheen_roughness), 1.0) : 1.0;
}

// The coat's BRDF × cos (about its own normal) for light from l seen from v.
float coat_cos(Shading m, vec3 v, vec3 l) {
    vec3 nc = m.clearcoat_normal;
    float nl = dot(nc, l);
    float nv = dot(nc, v);
    if (nl <= 0.0 || nv <= 0.0) return 0.0;
    vec3 h = normalize(l + v);
    float a = ggx_alpha(m.clearcoat_roughness);
    float x = clamp(1.0 - dot(v, h), 0.0, 1.0);
    float x2 = x * x;
    float f = COAT_F0 + (1.0 - COAT_F0) * x2 * x2 * x;
    return m.clearcoat * f * ggx_d(max(dot(nc, h), 0.0), a) * smith_visibility(nl, nv, a) * nl;
}

// The sheen's BRDF × cos (about the base's normal n), colour included, divided by max(1, E).
vec3 sheen_cos(Shading m, vec3 n, vec3 v, vec3 l) {
    float nl = dot(n, l);
    float nv = dot(n, v);
    if (nl <= 0.0 || nv <= 0.0) return vec3(0.0);
    float a = sheen_alpha(m.sheen_roughness);
    float lobe = charlie_d(max(dot(n, normalize(l + v)), 0.0), a) * sheen_visibility(nl, nv, a) * nl;
    return m.sheen_color * (lobe / max(sheen_albedo(nv, m.sheen_roughness), 1.0));
}

// brdf_cos with the layers: the base's lobes under both layers' shares, the sheen (with the diffuse lobe) under the
// coat's, the coat (with the specular lobe) on top.
void layered_brdf_cos(Shading m, vec3 n, vec3 v, vec3 l, out vec3 diffuse, out vec3 specular) {
    brdf_cos(m, n, v, l, diffuse, specular);
    if (LAYERS == 0u) return;
    float under = m.coat_share * m.sheen_share;
    diffuse *= under;
    specular *= under;
    if (has_sheen(m)) diffuse += m.coat_share * sheen_cos(m, n, v, l);
    if (has_coat(m)) specular += vec3(coat_cos(m, v, l));
}

// The probability that a gloss ray samples the coat rather than the base's specular lobe: their rough weights
// (the coat's albedo against the base's F0, metal colour and transmission under the layers' shares).
float coat_choice(Shading m, vec3 v) {
    if (!has_coat(m)) return 0.0;
    float coat = m.clearcoat * coat_albedo(dot(m.clearcoat_normal, v), m.clearcoat_roughness);
    float base = m.coat_share * m.sheen_share *
                 (luminance(mix(dielectric_f0(m), m.albedo, m.metallic)) +
                  luminance((1.0 - m.metallic) * m.transmission * m.albedo));
    return base > 0.0 ? coat / (coat + base) : 1.0;
}

// The coat's visible-normal density towards l (Heitz 2018, as specular_pdf), before the coat's choice.
float coat_pdf(Shading m, vec3 v, vec3 l) {
    vec3 nc = m.clearcoat_normal;
    float nv = dot(nc, v);
    if (nv <= 0.0 || dot(nc, l) <= 0.0) return 0.0;
    float a = ggx_alpha(m.clearcoat_roughness);
    return smith_g1(nv, a) * ggx_d(max(dot(nc, normalize(l + v)), 0.0), a) / (4.0 * nv);
}

// specular_pdf with the coat: the density of the mixture the gloss rays sample.
float layered_specular_pdf(Shading m, vec3 n, vec3 v, vec3 l) {
    float p_coat = coat_choice(m, v);
    float base = p_coat < 1.0 ? specular_pdf(m, n, v, l) : 0.0;
    return p_coat > 0.0 ? p_coat * coat_pdf(m, v, l) + (1.0 - p_coat) * base : base;
}

// diffuse_choice with the layers: the diffuse lobe's weight under both shares plus the sheen's, against the
// specular lobe's under both shares plus the coat's.
float layered_diffuse_choice(Shading m, vec3 v) {
    if (LAYERS == 0u) return diffuse_choice(m);
    float under = m.coat_share * m.sheen_share;
    float sheen = max(m.sheen_color.r, max(m.sheen_color.g, m.sheen_color.b));
    float d = under * luminance((1.0 - m.metallic) * (1.0 - m.transmission) * m.albedo) + m.coat_share * sheen * 0.5;
    float s = under * (luminance(mix(dielectric_f0(m), m.albedo, m.metallic)) +
                       luminance((1.0 - m.metallic) * m.transmission * m.albedo)) +
              m.clearcoat * COAT_F0;
    if (!(d > 0.0)) return 0.0;
    return s > 0.0 ? min(d / (d + s), 0.75) : 1.0;
}

// sample_specular with the coat: the coat's visible normals (probability coat_choice) or the base's lobe; a
// reflection is weighed by the whole specular BRDF over the mixture's density (one-sample MIS, Veach 1997 §9.2),
// a refraction by the base's transmission under the layers' shares.
bool sample_layered_specular(Shading m, vec3 n, vec3 v, bool inside, vec2 u, float u_lobe, out vec3 wi,
                             out vec3 weight, out float pdf) {
    float p_coat = coat_choice(m, v);
    if (!(p_coat > 0.0)) return sample_specular(m, n, v, inside, u, u_lobe, wi, weight, pdf);
    wi = vec3(0.0);
    weight = vec3(0.0);
    pdf = 0.0;
    if (u_lobe < p_coat) {
        vec3 nc = m.clearcoat_normal;
        vec3 t;
        vec3 b;
        make_basis(nc, t, b);
        vec3 ve = vec3(dot(v, t), dot(v, b), dot(v, nc));
        if (ve.z <= 0.0) return false;
        vec3 he = sample_ggx_vndf(ve, ggx_alpha(m.clearcoat_roughness), u);
        wi = reflect(-v, normalize(t * he.x + b * he.y + nc * he.z));
    } else {
        vec3 base_weight;
        float base_pdf;
        float u_base = (u_lobe - p_coat) / (1.0 - p_coat);
        if (!sample_specular(m, n, v, inside, u, u_base, wi, base_weight, base_pdf)) return false;
        if (base_pdf == 0.0) {
            // Refraction (or its total internal reflection): no coat lobe covers it.
            weight = base_weight * (m.coat_share * m.sheen_share / (1.0 - p_coat));
            return true;
        }
    }
    pdf = layered_specular_pdf(m, n, v, wi);
    if (!(pdf > 0.0)) return false;
    vec3 diffuse;
    vec3 specular;
    layered_brdf_cos(m, n, v, wi, diffuse, specular);
    weight = specular / pdf;
    return true;
}
#endif
