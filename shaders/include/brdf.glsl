// The glTF 2.0 metallic-roughness BRDF (glTF 2.0 Appendix B): a Lambertian diffuse lobe weighted by 1 − F and a
// GGX (Trowbridge-Reitz) specular lobe with the height-correlated Smith visibility, Schlick's Fresnel; plus
// sampling of GGX visible normals (Heitz 2018) for the gloss and translucency rays of distributed ray tracing.
#ifndef BRDF_GLSL
#define BRDF_GLSL

const float PI = 3.14159265358979;

struct Shading {
    vec3 albedo;
    float metallic;
    float roughness;
    float transmission;
    float ior;
    float specular;       // KHR_materials_specular factor (times its texture's alpha)
    vec3 specular_color;  // KHR_materials_specular colour
    // What the specular layer leaves to the diffuse base seen from the viewer: 1 − the layer's directional
    // albedo there (albedo scaling; set where the view is known, surface.glsl's face_viewer; 1 until then).
    float diffuse_share;
    // The layers over the base (layers.glsl; docs/architecture.md, "Layered materials"), read only by the
    // accumulation pass and only where a scene has them (its LAYERS constant).
    float clearcoat;            // KHR_materials_clearcoat factor × texture (0: no coat)
    float clearcoat_roughness;  // factor × texture
    vec3 clearcoat_normal;      // the coat's shading normal: the vertex normal, or the coat's own normal texture
    vec3 sheen_color;           // KHR_materials_sheen colour × texture (black: no sheen)
    float sheen_roughness;      // factor × texture
    // What the coat leaves to the sheen and base under it, and the sheen to the base, seen from the viewer:
    // 1 − each layer's directional albedo there (face_viewer; 1 until then).
    float coat_share;
    float sheen_share;
    // KHR_materials_diffuse_transmission: the share of the diffuse lobe that passes to the other side (factor ×
    // texture; 0: none), and its colour.
    float diffuse_transmission;
    vec3 diffuse_transmission_color;
    // KHR_materials_iridescence: the film's factor (× texture), index and thickness (nm), and what it multiplies
    // the dielectric's and the metal's Fresnel by, seen from the viewer (layers.glsl's set_film; 1 without a film).
    float iridescence;
    float iridescence_ior;
    float iridescence_thickness;
    vec3 film_dielectric;
    vec3 film_metal;
    // KHR_materials_anisotropy: the strength (× texture; 0: an isotropic lobe, and always 0 in a pipeline without
    // layers, surface.glsl's face_viewer) and the direction the lobe stretches along (world space, in the tangent
    // plane up to the shading normal's tilt).
    float anisotropy;
    vec3 anisotropy_direction;
};

float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// An orthonormal basis (t, b, n) around a unit n (Duff et al. 2017).
void make_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// alpha = roughness², kept above a floor so a perfect mirror stays a (very narrow) lobe without NaN.
float ggx_alpha(float roughness) {
    return max(roughness * roughness, 1e-3);
}

float ggx_d(float nh, float a) {
    float a2 = a * a;
    float d = nh * nh * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

// Smith G1 for GGX at cosine c.
float smith_g1(float c, float a) {
    float a2 = a * a;
    return 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
}

// Height-correlated Smith visibility V = G2 / (4 n·l n·v).
float smith_visibility(float nl, float nv, float a) {
    float a2 = a * a;
    float gv = nl * sqrt(nv * nv * (1.0 - a2) + a2);
    float gl = nv * sqrt(nl * nl * (1.0 - a2) + a2);
    float d = gv + gl;
    return d > 0.0 ? 0.5 / d : 0.0;
}

// The dielectric's reflectance at normal incidence: F0 from the IOR, tinted by the specular colour and kept at
// most 1, scaled by the specular factor (KHR_materials_specular).
vec3 dielectric_f0(Shading m) {
    float r = (m.ior - 1.0) / (m.ior + 1.0);
    return min(vec3(r * r) * m.specular_color, vec3(1.0)) * m.specular;
}

// The anisotropic GGX lobe (KHR_materials_anisotropy; Heitz 2014, "Understanding the Masking-Shadowing Function in
// Microfacet-Based BRDFs", §5.3): roughness a.x along the lobe frame's first axis, a.y along its second; vectors in
// that frame (z the normal). Each reduces to its isotropic twin above where a.x = a.y.
float ggx_d_aniso(vec3 h, vec2 a) {
    float a2 = a.x * a.y;
    vec3 f = vec3(a.y * h.x, a.x * h.y, a2 * h.z);
    float w2 = a2 / dot(f, f);
    return a2 * w2 * w2 / PI;
}

float smith_g1_aniso(vec3 w, vec2 a) {
    return 2.0 * w.z / (w.z + length(vec3(a.x * w.x, a.y * w.y, w.z)));
}

float smith_visibility_aniso(vec3 l, vec3 v, vec2 a) {
    float gv = l.z * length(vec3(a.x * v.x, a.y * v.y, v.z));
    float gl = v.z * length(vec3(a.x * l.x, a.y * l.y, l.z));
    float d = gv + gl;
    return d > 0.0 ? 0.5 / d : 0.0;
}

bool anisotropic(Shading m) {
    return m.anisotropy > 0.0;
}

// The extension's roughness along the direction, mix(α, 1, strength²), and across it, α.
vec2 lobe_alphas(Shading m) {
    float a = ggx_alpha(m.roughness);
    return vec2(mix(a, 1.0, m.anisotropy * m.anisotropy), a);
}

// The anisotropic lobe's frame about n: the direction made perpendicular to n, then n × it (make_basis where the
// direction is along n).
void lobe_frame(Shading m, vec3 n, out vec3 t, out vec3 b) {
    vec3 d = m.anisotropy_direction - n * dot(n, m.anisotropy_direction);
    float len = length(d);
    if (!(len > 1e-6)) {
        make_basis(n, t, b);
        return;
    }
    t = d / len;
    b = cross(n, t);
}

vec3 to_lobe(vec3 w, vec3 t, vec3 b, vec3 n) {
    return vec3(dot(w, t), dot(w, b), dot(w, n));
}

// The material's Fresnel reflectance at v·h (Schlick), glTF 2.0 Appendix B: the dielectric's (F0 from the
// IOR, tinted by the specular colour and kept at most 1, F0 and F90 scaled by the specular factor:
// KHR_materials_specular) and the metal's (F0 the base colour), mixed by metalness. `base_share` is what the
// dielectric leaves to its base layer (diffuse and transmission): 1 − max(F_dielectric), the extension's
// fresnel_mix; the metal has no base layer.
vec3 fresnel(Shading m, float vh, out float base_share) {
    vec3 f0 = dielectric_f0(m);
    float x = clamp(1.0 - vh, 0.0, 1.0);
    float x2 = x * x;
    float w = x2 * x2 * x;
    vec3 dielectric = f0 + (vec3(m.specular) - f0) * w;
    vec3 metal = m.albedo + (vec3(1.0) - m.albedo) * w;
    if (m.film_dielectric != vec3(1.0) || m.film_metal != vec3(1.0)) {
        // A thin film (KHR_materials_iridescence) recolours both by its interference at the view angle.
        dielectric = min(dielectric * m.film_dielectric, vec3(1.0));
        metal = min(metal * m.film_metal, vec3(1.0));
    }
    base_share = 1.0 - max(dielectric.x, max(dielectric.y, dielectric.z));
    return mix(dielectric, metal, m.metallic);
}

// BRDF × cos for light arriving from l, seen from v, split into the diffuse and the specular lobe: the diffuse
// lobe is estimated by light sampling alone, the specular one by light sampling and by gloss rays, combined
// with multiple importance sampling (Veach and Guibas 1995).
void brdf_cos(Shading m, vec3 n, vec3 v, vec3 l, out vec3 diffuse, out vec3 specular) {
    diffuse = vec3(0.0);
    specular = vec3(0.0);
    float nl = dot(n, l);
    if (nl <= 0.0) return;
    float nv = dot(n, v);
    vec3 h = normalize(l + v);
    float base_share;
    vec3 f = fresnel(m, max(dot(v, h), 0.0), base_share);
    // The diffuse base gets what the specular layer does not reflect, over all directions (m.diffuse_share), not
    // glTF 2.0 Appendix B's 1 − F(v·h) per direction, which at grazing views adds up to more than arrives
    // (docs/architecture.md, "Energy: the diffuse base under the specular layer").
    diffuse = m.diffuse_share * (1.0 - m.metallic) * (1.0 - m.transmission) * m.albedo * (nl / PI);
    // Seen from below the shading normal (a bumped or interpolated normal turned away from the viewer) the
    // specular lobe reflects nothing, as sample_specular finds: light sampling and gloss rays agree.
    if (nv <= 0.0) return;
    if (anisotropic(m)) {
        vec3 t;
        vec3 b;
        lobe_frame(m, n, t, b);
        vec2 a2 = lobe_alphas(m);
        specular = f * ggx_d_aniso(to_lobe(h, t, b, n), a2) *
                   smith_visibility_aniso(to_lobe(l, t, b, n), to_lobe(v, t, b, n), a2) * nl;
        return;
    }
    float a = ggx_alpha(m.roughness);
    specular = f * ggx_d(max(dot(n, h), 0.0), a) * smith_visibility(nl, nv, a) * nl;
}

// What the dielectric's specular layer leaves to the diffuse base when seen at cosine nv: 1 − its directional
// albedo F0·E1 + (F90 − F0)·E5 (Schlick's Fresnel split in two terms, each tabulated over view cosine and
// roughness: `terms` from math::brdf's table), the largest channel's as fresnel's base_share takes.
float diffuse_share_from(Shading m, vec2 terms) {
    vec3 f0 = dielectric_f0(m);
    vec3 albedo = (f0 * terms.x + (vec3(m.specular) - f0) * terms.y) * m.film_dielectric;
    return clamp(1.0 - max(albedo.x, max(albedo.y, albedo.z)), 0.0, 1.0);
}

// The probability of choosing reflection at microfacet normal h (the rest refracts).
float reflect_probability(Shading m, float vh) {
    float base_share;
    vec3 f = fresnel(m, vh, base_share);
    float pr = luminance(f);
    float pt = luminance(base_share * m.transmission * (1.0 - m.metallic) * m.albedo);
    return pr + pt > 0.0 ? pr / (pr + pt) : 0.0;
}

// Solid-angle density with which sample_specular reflects towards l: the visible-normal density
// G1(v) D(h) / (4 n·v) (Heitz 2018, eq. 17 with the reflection Jacobian) times the reflection choice.
float specular_pdf(Shading m, vec3 n, vec3 v, vec3 l) {
    float nv = dot(n, v);
    if (nv <= 0.0 || dot(n, l) <= 0.0) return 0.0;
    vec3 h = normalize(l + v);
    float vh = max(dot(v, h), 0.0);
    if (anisotropic(m)) {
        vec3 t;
        vec3 b;
        lobe_frame(m, n, t, b);
        vec2 a2 = lobe_alphas(m);
        return smith_g1_aniso(to_lobe(v, t, b, n), a2) * ggx_d_aniso(to_lobe(h, t, b, n), a2) / (4.0 * nv) *
               reflect_probability(m, vh);
    }
    float a = ggx_alpha(m.roughness);
    return smith_g1(nv, a) * ggx_d(max(dot(n, h), 0.0), a) / (4.0 * nv) * reflect_probability(m, vh);
}

// With diffuse interreflection on, the probability that a path goes on by the diffuse lobe rather than the
// specular one: the lobes' rough weights (diffuse albedo against F0, the metal's colour and transmission), with
// at least a quarter left to the specular lobe where it has any weight, so glossy reflections stay sampled.
float diffuse_choice(Shading m) {
    float d = luminance((1.0 - m.metallic) * (1.0 - m.transmission) * m.albedo);
    float s = luminance(mix(dielectric_f0(m), m.albedo, m.metallic)) + luminance((1.0 - m.metallic) * m.transmission * m.albedo);
    if (!(d > 0.0)) return 0.0;
    return s > 0.0 ? min(d / (d + s), 0.75) : 1.0;
}

// The power heuristic (β = 2) weight of a strategy with density a against one with density b.
float power_heuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    return a2 + b2 > 0.0 ? a2 / (a2 + b2) : 0.0;
}

// A GGX visible normal for view ve in tangent space (z = normal), from u in [0,1)², with roughness a.x along the
// frame's x and a.y along its y (Heitz 2018, Listing 1, written for both).
vec3 sample_ggx_vndf_aniso(vec3 ve, vec2 a, vec2 u) {
    vec3 vh = normalize(vec3(a.x * ve.x, a.y * ve.y, ve.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(a.x * nh.x, a.y * nh.y, max(nh.z, 0.0)));
}

// The same for an isotropic lobe of roughness a.
vec3 sample_ggx_vndf(vec3 ve, float a, vec2 u) {
    return sample_ggx_vndf_aniso(ve, vec2(a), u);
}
// The specular continuation of a path at a surface: a direction around the ideal reflection (gloss) or
// refraction (translucency), chosen by their Fresnel weights, and the throughput weight of VNDF sampling
// (F·G2/G1(v) for reflection, the transmitted share·G1(l) for refraction). `inside`: v is inside the material (refraction leaves it). False when the path ends here.
// `pdf` is the reflection's solid-angle density (for MIS against light sampling); 0 for refraction, which light
// sampling never covers.
bool sample_specular(Shading m, vec3 n, vec3 v, bool inside, vec2 u, float u_lobe, out vec3 wi, out vec3 weight,
                     out float pdf) {
    wi = vec3(0.0);
    weight = vec3(0.0);
    pdf = 0.0;
    vec3 t;
    vec3 b;
    bool stretched = anisotropic(m);
    if (stretched) lobe_frame(m, n, t, b); else make_basis(n, t, b);
    vec3 ve = vec3(dot(v, t), dot(v, b), dot(v, n));
    if (ve.z <= 0.0) return false;
    float a = ggx_alpha(m.roughness);
    vec2 a2 = lobe_alphas(m);
    vec3 he = stretched ? sample_ggx_vndf_aniso(ve, a2, u) : sample_ggx_vndf(ve, a, u);
    vec3 h = normalize(t * he.x + b * he.y + n * he.z);
    float vh = max(dot(v, h), 0.0);
    float base_share;
    vec3 reflect_weight = fresnel(m, vh, base_share);
    vec3 transmit_weight = base_share * m.transmission * (1.0 - m.metallic) * m.albedo;
    float pr = luminance(reflect_weight);
    float pt = luminance(transmit_weight);
    if (!(pr + pt > 0.0)) return false;
    float p_reflect = pr / (pr + pt);
    if (u_lobe < p_reflect) {
        wi = reflect(-v, h);
        float nl = dot(n, wi);
        if (nl <= 0.0) return false;
        // f·cos / pdf = F · G2(v, l) / G1(v), with brdf_cos's height-correlated G2 = 4 n·l n·v V: the BRDF
        // the rays sample is the one light sampling evaluates (the separable G1(l) would be darker at grazing).
        if (stretched) {
            vec3 le = to_lobe(wi, t, b, n);
            float g1 = smith_g1_aniso(ve, a2);
            weight = reflect_weight / p_reflect * (4.0 * nl * ve.z * smith_visibility_aniso(le, ve, a2) / g1);
            pdf = g1 * ggx_d_aniso(he, a2) / (4.0 * ve.z) * p_reflect;
            return true;
        }
        weight = reflect_weight / p_reflect * (4.0 * nl * ve.z * smith_visibility(nl, ve.z, a) / smith_g1(ve.z, a));
        pdf = smith_g1(ve.z, a) * ggx_d(max(dot(n, h), 0.0), a) / (4.0 * ve.z) * p_reflect;
        return true;
    }
    float eta = inside ? m.ior : 1.0 / m.ior;
    wi = refract(-v, h, eta);
    if (dot(wi, wi) == 0.0) {
        // Total internal reflection: the transmitted share reflects.
        wi = reflect(-v, h);
        float nl = dot(n, wi);
        if (nl <= 0.0) return false;
        weight = transmit_weight / (1.0 - p_reflect) * (stretched ? smith_g1_aniso(to_lobe(wi, t, b, n), a2) : smith_g1(nl, a));
        return true;
    }
    float nl = -dot(n, wi);
    if (nl <= 0.0) return false;
    weight = transmit_weight / (1.0 - p_reflect) * (stretched ? smith_g1_aniso(-to_lobe(wi, t, b, n), a2) : smith_g1(nl, a));
    return true;
}
#endif
