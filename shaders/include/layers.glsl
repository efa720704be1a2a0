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

// The thin film (KHR_materials_iridescence; CPU twin math::iridescence, which says how it follows Belcour and Barla
// 2017 and the extension's sample renderer). CIE XYZ to linear Rec.709, columns.
const mat3 XYZ_TO_REC709 = mat3(3.2404542, -0.9692660, 0.0556434, -1.5371385, 1.8760108, -0.2040259, -0.4985314,
                                0.0415560, 1.0572252);

// The exact unpolarised Fresnel reflectance from index n1 into n2 at cosine c (1 beyond the critical angle).
float dielectric_fresnel(float n1, float n2, float c) {
    float sin2_sq = (n1 / n2) * (n1 / n2) * (1.0 - c * c);
    if (sin2_sq >= 1.0) return 1.0;
    float c2 = sqrt(1.0 - sin2_sq);
    float rs = (n1 * c - n2 * c2) / (n1 * c + n2 * c2);
    float rp = (n2 * c - n1 * c2) / (n2 * c + n1 * c2);
    return 0.5 * (rs * rs + rp * rp);
}

// The colour matching functions' response to an interference of optical path difference `opd` (nm) with phase
// `shift` per XYZ channel, in linear Rec.709 (the paper's Fourier-space Gaussian fit).
vec3 film_sensitivity(float opd, vec3 shift) {
    float phase = 2.0 * PI * opd * 1.0e-9;
    vec3 val = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
    vec3 pos = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
    vec3 var = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
    vec3 xyz = val * sqrt(2.0 * PI * var) * cos(pos * phase + shift) * exp(-phase * phase * var);
    xyz.x += 9.7470e-14 * sqrt(2.0 * PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift.x) * exp(-4.5282e+09 * phase * phase);
    return XYZ_TO_REC709 * (xyz / 1.0685e-7);
}

// The film's reflectance per channel at view cosine c1 over a base of normal-incidence reflectance base_f0.
vec3 thin_film_fresnel(float c1, float film_ior, float thickness, vec3 base_f0) {
    float t = clamp(thickness / 0.03, 0.0, 1.0);
    float film = 1.0 + (film_ior - 1.0) * t * t * (3.0 - 2.0 * t);
    float cos2_sq = 1.0 - (1.0 / film) * (1.0 / film) * (1.0 - c1 * c1);
    if (cos2_sq < 0.0) return vec3(1.0);
    float c2 = sqrt(cos2_sq);
    float r12 = dielectric_fresnel(1.0, film, c1);
    float t121 = 1.0 - r12;
    float phi21 = PI - (film < 1.0 ? PI : 0.0);
    vec3 root = sqrt(clamp(base_f0, 0.0, 0.9999));
    vec3 base_ior = (1.0 + root) / (1.0 - root);
    vec3 f0_23 = (base_ior - film) / (base_ior + film);
    f0_23 *= f0_23;
    float x = clamp(1.0 - c2, 0.0, 1.0);
    float x2 = x * x;
    vec3 r23 = f0_23 + (1.0 - f0_23) * (x2 * x2 * x);
    vec3 phi23 = vec3(base_ior.x < film ? PI : 0.0, base_ior.y < film ? PI : 0.0, base_ior.z < film ? PI : 0.0);
    float opd = 2.0 * film * thickness * c2;
    vec3 r123 = clamp(r12 * r23, 0.0, 0.9999);
    vec3 rs = t121 * t121 * r23 / (1.0 - r123);
    vec3 reflectance = r12 + rs;
    vec3 cm = rs - t121;
    for (int k = 1; k <= 2; k++) {
        cm *= sqrt(r123);
        reflectance += cm * 2.0 * film_sensitivity(float(k) * opd, float(k) * (phi21 + phi23));
    }
    return max(reflectance, vec3(0.0));
}

// The film's factor on the dielectric's and the metal's Fresnel, seen at view cosine nv: its reflectance over the
// zero-thickness film's (the base's Schlick reflectance), mixed in by the film's factor; 1 without a film.
void set_film(inout Shading m, float nv) {
    if (!(m.iridescence > 0.0)) return;
    float c = clamp(nv, 0.0, 1.0);
    vec3 f0s[2] = vec3[2](dielectric_f0(m) / max(m.specular, 1e-6), m.albedo);
    vec3 ratios[2];
    for (int i = 0; i < 2; i++) {
        vec3 film = thin_film_fresnel(c, m.iridescence_ior, m.iridescence_thickness, f0s[i]);
        vec3 none = thin_film_fresnel(c, m.iridescence_ior, 0.0, f0s[i]);
        vec3 ratio = vec3(none.x > 0.0 ? film.x / none.x : 1.0, none.y > 0.0 ? film.y / none.y : 1.0,
                          none.z > 0.0 ? film.z / none.z : 1.0);
        ratios[i] = mix(vec3(1.0), ratio, m.iridescence);
    }
    m.film_dielectric = ratios[0];
    m.film_metal = ratios[1];
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

bool transmits_diffusely(Shading m) {
    return LAYERS != 0u && m.diffuse_transmission > 0.0;
}

// brdf_cos with the layers: the base's lobes under both layers' shares, the sheen (with the diffuse lobe) under the
// coat's, the coat (with the specular lobe) on top. With diffuse transmission the diffuse lobe reflects 1 − t of
// itself and passes t, tinted, to light from the other side of the surface (the extension's mix of a Lambertian BRDF
// and BTDF), in the diffuse lobe's estimators.
void layered_brdf_cos(Shading m, vec3 n, vec3 v, vec3 l, out vec3 diffuse, out vec3 specular) {
    brdf_cos(m, n, v, l, diffuse, specular);
    if (LAYERS == 0u) return;
    float under = m.coat_share * m.sheen_share;
    diffuse *= under;
    specular *= under;
    if (transmits_diffusely(m)) {
        float nl = dot(n, l);
        if (nl < 0.0) {
            float base = m.diffuse_share * (1.0 - m.metallic) * (1.0 - m.transmission) * m.diffuse_transmission;
            diffuse = under * base * m.diffuse_transmission_color * (-nl / PI);
            return;
        }
        diffuse *= 1.0 - m.diffuse_transmission;
    }
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
    vec3 diffuse_color = mix(m.albedo, m.diffuse_transmission_color, m.diffuse_transmission);
    float d = under * luminance((1.0 - m.metallic) * (1.0 - m.transmission) * diffuse_color) + m.coat_share * sheen * 0.5;
    float s = under * (luminance(mix(dielectric_f0(m), m.albedo, m.metallic)) +
                       luminance((1.0 - m.metallic) * m.transmission * m.albedo)) +
              m.clearcoat * COAT_F0;
    if (!(d > 0.0)) return 0.0;
    return s > 0.0 ? min(d / (d + s), 0.75) : 1.0;
}

// The probability that a diffuse bounce passes to the other side of the surface: the transmitted share's weight
// against the reflected share's and the sheen's (0 without diffuse transmission).
float diffuse_transmit_choice(Shading m) {
    if (!transmits_diffusely(m)) return 0.0;
    float back = m.diffuse_transmission * luminance(m.diffuse_transmission_color);
    float sheen = max(m.sheen_color.r, max(m.sheen_color.g, m.sheen_color.b));
    float front = (1.0 - m.diffuse_transmission) * luminance(m.albedo) * m.sheen_share + sheen * 0.5;
    return back + front > 0.0 ? back / (back + front) : 0.0;
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
