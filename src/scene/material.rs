//! Materials (glTF metallic-roughness PBR with the extensions strata implements), textures and samplers.
use glam::{Mat3, Vec2, Vec3, Vec4};

/// `KHR_texture_transform`: uv' = T · R · S · uv (the extension's order: scale, then rotate, then offset).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvTransform {
    pub offset: Vec2,
    /// Radians, counter-clockwise in UV space.
    pub rotation: f32,
    pub scale: Vec2,
}

impl UvTransform {
    /// The 3×3 matrix the extension's README gives: translation · rotation · scale.
    pub fn matrix(&self) -> Mat3 {
        let (s, c) = self.rotation.sin_cos();
        let translation = Mat3::from_cols(Vec3::X, Vec3::Y, self.offset.extend(1.0));
        // The extension rotates with this matrix (note the signs: UV space has v pointing down the image).
        let rotation = Mat3::from_cols(Vec3::new(c, -s, 0.0), Vec3::new(s, c, 0.0), Vec3::Z);
        let scale = Mat3::from_diagonal(self.scale.extend(1.0));
        translation * rotation * scale
    }

    pub fn apply(&self, uv: Vec2) -> Vec2 {
        (self.matrix() * uv.extend(1.0)).truncate()
    }
}

/// A material's use of a texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    pub texture: usize,
    /// Which TEXCOORD_n set (after `KHR_texture_transform`'s override).
    pub tex_coord: u32,
    pub transform: Option<UvTransform>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// How minification moves between mip levels (glTF's `*_MIPMAP_NEAREST` and `*_MIPMAP_LINEAR` filters).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MipFilter {
    /// No mipmaps: minification reads the full-size image.
    None,
    Nearest,
    Linear,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sampler {
    pub mag_linear: bool,
    pub min_linear: bool,
    /// Minification through mipmaps (any `*_MIPMAP_*` filter; linear between levels when unspecified).
    pub mipmaps: MipFilter,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
}

impl Default for Sampler {
    /// glTF leaves filters to the implementation when unset; wrap defaults to REPEAT (§5.26).
    fn default() -> Self {
        Self {
            mag_linear: true,
            min_linear: true,
            mipmaps: MipFilter::Linear,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
        }
    }
}

/// A texture: an image with a sampler. Whether it is sRGB follows from how materials use it.
#[derive(Debug, Clone)]
pub struct Texture {
    pub name: String,
    pub image: usize,
    pub sampler: Sampler,
    /// Used as colour (base colour, emissive, specular colour): its texels are sRGB-encoded (glTF 2.0 §3.9.2,
    /// KHR_materials_specular).
    pub srgb: bool,
}

/// A decoded image, 8-bit RGBA, top row first (glTF UV (0,0) is the image's top-left, §3.8.4).
#[derive(Clone)]
pub struct TextureImage {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}

impl std::fmt::Debug for TextureImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "TextureImage {{ name: {:?}, {}x{} }}", self.name, self.width, self.height)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AlphaMode {
    Opaque,
    /// Discard where alpha < cutoff.
    Mask {
        cutoff: f32,
    },
    /// Alpha as coverage: each sample keeps a point with probability alpha (stochastic transparency, the same
    /// test in the raster pass and for every ray), so the samples' mean is glTF's blend over what lies behind.
    Blend,
}

/// How the scene file adds procedural bump mapping (Blinn 1978) with a Perlin height field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BumpMap {
    pub kind: NoiseKind,
    /// Height amplitude in UV-space units of the surface.
    pub amplitude: f32,
    /// Noise frequency in cycles per UV unit.
    pub frequency: f32,
    pub octaves: u32,
    pub lacunarity: f32,
    pub gain: f32,
    /// How (B_u, B_v) is found: the noise's analytic gradient by default, the exact derivative of the field.
    /// Central differences at the default step lose the finest octaves: at the default fBm (frequency 8, four
    /// octaves) their gradient is off by 62% rms and the bumped normal by 10° on average (docs/performance.md,
    /// "Bumps: the analytic gradient by default").
    pub derivative: BumpDerivative,
    /// Central-difference step ε in UV units (default 1/64).
    pub epsilon: f32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoiseKind {
    Noise,
    Fbm,
    Turbulence,
    /// B = sin(2π·frequency·u): an analytic ripple along u, for checking bump mapping against a closed form.
    Sine,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BumpDerivative {
    CentralDifferences,
    Analytic,
}

impl Default for BumpMap {
    fn default() -> Self {
        Self {
            kind: NoiseKind::Fbm,
            amplitude: 0.02,
            frequency: 8.0,
            octaves: 4,
            lacunarity: 2.0,
            gain: 0.5,
            derivative: BumpDerivative::Analytic,
            epsilon: 1.0 / 64.0,
        }
    }
}

/// `KHR_materials_clearcoat`: a clear dielectric coat (IOR 1.5, F0 0.04) over the whole material, with its own
/// roughness and normal (docs/architecture.md, "Layered materials").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clearcoat {
    /// How much of the surface the coat covers, 0 to 1.
    pub factor: f32,
    /// Its R channel scales `factor`.
    pub texture: Option<TextureRef>,
    pub roughness: f32,
    /// Its G channel scales `roughness`.
    pub roughness_texture: Option<TextureRef>,
    /// The coat's own normal texture (tangent space, as the base's); without one the coat follows the
    /// interpolated vertex normal, not the base's normal texture or bump.
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
}

impl Default for Clearcoat {
    /// The extension's defaults: no coat, smooth.
    fn default() -> Self {
        Self {
            factor: 0.0,
            texture: None,
            roughness: 0.0,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        }
    }
}

/// `KHR_materials_sheen`: a layer of fibres over the base (the "Charlie" sheen lobe, Estevez and Kulla 2017),
/// coloured, with its own roughness (docs/architecture.md, "Layered materials").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sheen {
    /// Linear colour; black: no sheen.
    pub color: Vec3,
    /// sRGB; its RGB scales `color`.
    pub color_texture: Option<TextureRef>,
    pub roughness: f32,
    /// Its alpha channel scales `roughness`.
    pub roughness_texture: Option<TextureRef>,
}

impl Default for Sheen {
    /// The extension's defaults: black (no sheen), smooth.
    fn default() -> Self {
        Self { color: Vec3::ZERO, color_texture: None, roughness: 0.0, roughness_texture: None }
    }
}

/// `KHR_materials_diffuse_transmission`: a share of the diffuse lobe passes through the surface to the other side,
/// diffusely and tinted, as through a thin sheet of paper or a leaf (docs/architecture.md, "Layered materials").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseTransmission {
    /// The share of the diffuse lobe that transmits, 0 to 1.
    pub factor: f32,
    /// Its alpha channel scales `factor`.
    pub texture: Option<TextureRef>,
    /// Linear colour of the transmitted light.
    pub color: Vec3,
    /// sRGB; its RGB scales `color`.
    pub color_texture: Option<TextureRef>,
}

impl Default for DiffuseTransmission {
    /// The extension's defaults: nothing transmits; what would is white.
    fn default() -> Self {
        Self { factor: 0.0, texture: None, color: Vec3::ONE, color_texture: None }
    }
}

/// `KHR_materials_iridescence`: a thin dielectric film over the base whose interference tints the specular
/// reflection by view angle and thickness (Belcour and Barla 2017, "A Practical Extension to Microfacet Theory for
/// the Modeling of Varying Iridescence"; docs/architecture.md, "Layered materials").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Iridescence {
    /// How much of the specular reflection the film's replaces, 0 to 1.
    pub factor: f32,
    /// Its R channel scales `factor`.
    pub texture: Option<TextureRef>,
    /// The film's index of refraction.
    pub ior: f32,
    /// The film's thickness in nanometres: `thickness_max` without a thickness texture, else between the two by
    /// its G channel.
    pub thickness_min: f32,
    pub thickness_max: f32,
    pub thickness_texture: Option<TextureRef>,
}

impl Default for Iridescence {
    /// The extension's defaults: no film; where there is one, index 1.3 and 100 to 400 nm.
    fn default() -> Self {
        Self {
            factor: 0.0,
            texture: None,
            ior: 1.3,
            thickness_min: 100.0,
            thickness_max: 400.0,
            thickness_texture: None,
        }
    }
}

/// `KHR_materials_anisotropy`: the specular lobe stretched along a direction in the surface's tangent plane, as
/// brushed metal reflects (docs/architecture.md, "Layered materials").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anisotropy {
    /// 0 (isotropic) to 1: the roughness along the direction is mix(α, 1, strength²), across it α.
    pub strength: f32,
    /// Radians, counter-clockwise from the tangent (TEXCOORD_0's u direction on the surface).
    pub rotation: f32,
    /// RG: a direction in tangent space ([0, 1] for [−1, 1]), rotated by `rotation`; B scales `strength`.
    pub texture: Option<TextureRef>,
}

impl Default for Anisotropy {
    /// The extension's defaults: isotropic, along the tangent.
    fn default() -> Self {
        Self { strength: 0.0, rotation: 0.0, texture: None }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear RGBA base colour factor.
    pub base_color: Vec4,
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// Roughness in G, metalness in B (glTF 2.0 §3.9.2).
    pub metallic_roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    pub occlusion_texture: Option<TextureRef>,
    pub occlusion_strength: f32,
    /// Linear emitted radiance factor: `emissiveFactor` × `KHR_materials_emissive_strength`.
    pub emissive: Vec3,
    pub emissive_texture: Option<TextureRef>,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// `KHR_materials_transmission` factor (0 = opaque).
    pub transmission: f32,
    pub transmission_texture: Option<TextureRef>,
    /// `KHR_materials_ior` (default 1.5).
    pub ior: f32,
    /// `KHR_materials_specular` factor: scales the dielectric Fresnel reflection (0: a purely diffuse surface).
    pub specular: f32,
    /// `KHR_materials_specular` texture: its alpha channel scales `specular`.
    pub specular_texture: Option<TextureRef>,
    /// `KHR_materials_specular` colour: tints the dielectric reflectance at normal incidence (F0), which stays at
    /// most 1.
    pub specular_color: Vec3,
    /// `KHR_materials_specular` colour texture (sRGB): its RGB scales `specular_color`.
    pub specular_color_texture: Option<TextureRef>,
    /// `KHR_materials_volume`: the colour white light turns after `attenuation_distance` metres (world units)
    /// inside the material (Beer–Lambert absorption); infinity: no absorption.
    pub attenuation_color: Vec3,
    pub attenuation_distance: f32,
    /// `KHR_materials_dispersion`: 20 / the Abbe number V_d (0: none). The index of refraction follows Cauchy's
    /// two-term equation through `ior` at 587.56 nm; a transmissive surface refracts each colour channel by its
    /// own index (docs/architecture.md, "Dispersion").
    pub dispersion: f32,
    /// `KHR_materials_clearcoat` (None: no coat).
    pub clearcoat: Option<Clearcoat>,
    /// `KHR_materials_sheen` (None: no sheen).
    pub sheen: Option<Sheen>,
    /// `KHR_materials_diffuse_transmission` (None: the diffuse lobe only reflects).
    pub diffuse_transmission: Option<DiffuseTransmission>,
    /// `KHR_materials_iridescence` (None: no film).
    pub iridescence: Option<Iridescence>,
    /// `KHR_materials_anisotropy` (None: an isotropic specular lobe).
    pub anisotropy: Option<Anisotropy>,
    /// Procedural bump mapping from the scene file.
    pub bump: Option<BumpMap>,
    /// `KHR_materials_unlit`: the surface shows its base colour (factor × texture × vertex colour) as radiance,
    /// whatever the light, and reflects nothing.
    pub unlit: bool,
}

impl Default for Material {
    /// glTF's default material (§3.9.6): white, fully metallic and rough, single-sided, opaque.
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            transmission: 0.0,
            transmission_texture: None,
            ior: 1.5,
            specular: 1.0,
            specular_texture: None,
            specular_color: Vec3::ONE,
            specular_color_texture: None,
            attenuation_color: Vec3::ONE,
            attenuation_distance: f32::INFINITY,
            dispersion: 0.0,
            clearcoat: None,
            sheen: None,
            diffuse_transmission: None,
            iridescence: None,
            anisotropy: None,
            bump: None,
            unlit: false,
        }
    }
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emissive.max_element() > 0.0
    }

    /// Whether the material has a layer over its base (a clear coat, a sheen, a thin film), diffuse transmission or
    /// an anisotropic lobe, which
    /// shading must evaluate where its surface is seen: the G-buffer has no room for their parameters, so the
    /// accumulation pass evaluates such a surface at a ray hit (docs/architecture.md, "Layered materials").
    pub fn is_layered(&self) -> bool {
        !self.unlit
            && (self.clearcoat.is_some_and(|c| c.factor > 0.0)
                || self.sheen.is_some_and(|s| s.color.max_element() > 0.0)
                || self.diffuse_transmission.is_some_and(|d| d.factor > 0.0)
                || self.iridescence.is_some_and(|i| i.factor > 0.0)
                || self.anisotropy.is_some_and(|a| a.strength > 0.0))
    }

    /// Whether the material refracts each colour channel by its own index: it transmits and disperses.
    pub fn disperses(&self) -> bool {
        self.dispersion > 0.0 && self.transmission > 0.0
    }

    /// The absorption coefficient σ per metre inside the material (KHR_materials_volume): light crossing d metres
    /// keeps exp(−σ·d) = attenuation_color^(d / attenuation_distance) of itself. A colour channel of 0 absorbs
    /// everything past the surface (σ taken as 1e9 per metre, so that exp stays finite).
    pub fn absorption(&self) -> Vec3 {
        if !(self.attenuation_distance > 0.0 && self.attenuation_distance.is_finite()) {
            return Vec3::ZERO;
        }
        let color = self.attenuation_color.clamp(Vec3::ZERO, Vec3::ONE);
        Vec3::from_array(color.to_array().map(|c| if c > 0.0 { -c.ln() / self.attenuation_distance } else { 1e9 }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_transform_follows_the_extension_order() {
        // Scale then rotate then offset: (1, 0) scaled ×2 → (2, 0); rotated 90° → (0, −2) in the extension's
        // convention; offset (0.5, 0.5) → (0.5, −1.5).
        let t =
            UvTransform { offset: Vec2::splat(0.5), rotation: std::f32::consts::FRAC_PI_2, scale: Vec2::splat(2.0) };
        let uv = t.apply(Vec2::new(1.0, 0.0));
        assert!((uv - Vec2::new(0.5, -1.5)).length() < 1e-6, "{uv}");
    }
}
