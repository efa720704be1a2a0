//! The G-buffer's layout, defined once for Rust; mirrored by `shaders/include/gbuffer_layout.glsl` (the tests
//! below pin sizes and offsets to the GLSL std430 rules).
use crate::scene::{AlphaMode, BumpDerivative, BumpMap, Material, NoiseKind};
use crate::shaders::constants as c;
use ash::vk;
use glam::{Mat3, Mat4, Vec4};

/// One colour attachment: its debug name and format. What each holds and how is gbuffer_encoding.glsl's (Rust's
/// twin: `render::gbuffer_encoding`). World position is stored, not reconstructed from depth: the accumulation
/// pass starts rays there and needs full precision, and each sample has its own sheared, jittered projection that
/// reconstruction would have to replay.
pub struct Attachment {
    pub name: &'static str,
    pub format: vk::Format,
}

/// The colour attachments at their locations (`GBUFFER_ATTACHMENT_*` in shared_constants.glsl, the one
/// definition of both sides; the unit test below holds this order to it).
pub const ATTACHMENTS: [Attachment; 6] = [
    Attachment { name: "position", format: vk::Format::R32G32B32A32_SFLOAT },
    Attachment { name: "albedo", format: vk::Format::R8G8B8A8_SRGB },
    Attachment { name: "material", format: vk::Format::R8G8B8A8_UNORM },
    Attachment { name: "emission", format: vk::Format::R16G16B16A16_SFLOAT },
    // The specular colour texture's texel (1 without one): the material's factor, which may exceed 1, is
    // applied where the G-buffer is read.
    Attachment { name: "specular", format: vk::Format::R8G8B8A8_SRGB },
    Attachment { name: "surface ids", format: vk::Format::R32G32B32A32_UINT },
];

/// Attachment locations, from shared_constants.glsl.
pub mod attachment {
    use crate::shaders::constants as c;
    pub const POSITION: usize = c::GBUFFER_ATTACHMENT_POSITION as usize;
    pub const ALBEDO: usize = c::GBUFFER_ATTACHMENT_ALBEDO as usize;
    pub const MATERIAL: usize = c::GBUFFER_ATTACHMENT_MATERIAL as usize;
    pub const EMISSION: usize = c::GBUFFER_ATTACHMENT_EMISSION as usize;
    pub const SPECULAR: usize = c::GBUFFER_ATTACHMENT_SPECULAR as usize;
    /// Last, so that the float attachments keep their locations as indices of the accumulation pass's sampler
    /// array.
    pub const SURFACE_IDS: usize = c::GBUFFER_ATTACHMENT_SURFACE_IDS as usize;
}

/// The decoded channels of a read-back G-buffer (`GBufferFrame::at`), each as RGBA floats.
pub const POSITION: usize = 0;
/// xyz the bumped normal, w the bump height B(u, v).
pub const SHADING_NORMAL: usize = 1;
/// xyz the face normal, w the specular factor.
pub const GEOMETRIC_NORMAL: usize = 2;
pub const ALBEDO: usize = 3;
pub const MATERIAL: usize = 4;
pub const EMISSION: usize = 5;
pub const SPECULAR_COLOR: usize = 6;
pub const CHANNELS: usize = 7;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Bytes per pixel of the G-buffer, depth included (for the memory budget).
pub fn bytes_per_pixel() -> usize {
    ATTACHMENTS.iter().map(|a| crate::vk::memory::texel_size(a.format).unwrap_or(4)).sum::<usize>() + 4
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GBufferPush {
    pub clip_from_world: Mat4,
    pub view_z_row: Vec4,
    /// The draw record of the draw and its material's index (both set before each draw, as a
    /// `GBufferDrawPush` at `GBufferPush::DRAW_OFFSET`).
    pub draw: u32,
    pub material: u32,
    pub pad: [u32; 2],
}

impl GBufferPush {
    /// Where `draw` and `material` are in the block: the members pushed again before each draw.
    pub const DRAW_OFFSET: u32 = std::mem::offset_of!(GBufferPush, draw) as u32;
}

/// What the G-buffer pass pushes before each draw, at `GBufferPush::DRAW_OFFSET`. The material's index is pushed
/// rather than read from the draw record because llvmpipe loads a storage buffer's fields with one scalar load only
/// where the index is a constant or a push constant: indexed by a field of another buffer, every field of the
/// material was gathered lane by lane, and the Cornell box's pass without bumps took 12 ms at 512² where it takes
/// 5 now (docs/performance.md, "The G-buffer pass: the material by a pushed index").
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GBufferDrawPush {
    pub draw: u32,
    pub material: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GBufferDraw {
    pub world_from_object: Mat4,
    pub normal_rows: [Vec4; 3],
    pub instance: u32,
    /// The sample's key for BLEND's stochastic coverage.
    pub coverage_key: u32,
    pub pad: [u32; 2],
}

impl GBufferDraw {
    /// `coverage_key`: the sample's key for BLEND's stochastic coverage (the fragment shader hashes it with the
    /// pixel and triangle).
    /// The draw's material is not here: it is pushed with the draw's index (`GBufferDrawPush`).
    pub fn new(world_from_object: Mat4, instance: u32, coverage_key: u32) -> Self {
        let normal = Mat3::from_mat4(world_from_object).inverse().transpose();
        let normal = if normal.is_finite() { normal } else { Mat3::ZERO };
        Self {
            world_from_object,
            normal_rows: [0, 1, 2].map(|r| normal.row(r).extend(0.0)),
            instance,
            coverage_key,
            pad: [0; 2],
        }
    }
}

/// Mirrors `Bump` in `bump.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBump {
    pub kind: i32,
    pub amplitude: f32,
    pub frequency: f32,
    pub octaves: u32,
    pub lacunarity: f32,
    pub gain: f32,
    pub derivative: i32,
    pub epsilon: f32,
}

impl GpuBump {
    pub const NONE: GpuBump = GpuBump {
        kind: c::BUMP_NONE,
        amplitude: 0.0,
        frequency: 1.0,
        octaves: 1,
        lacunarity: 2.0,
        gain: 0.5,
        derivative: 0,
        epsilon: 1.0 / 64.0,
    };

    pub fn from_bump(bump: Option<&BumpMap>) -> Self {
        let Some(b) = bump else { return Self::NONE };
        Self {
            kind: match b.kind {
                NoiseKind::Noise => c::BUMP_NOISE,
                NoiseKind::Fbm => c::BUMP_FBM,
                NoiseKind::Turbulence => c::BUMP_TURBULENCE,
                NoiseKind::Sine => c::BUMP_SINE,
            },
            amplitude: b.amplitude,
            frequency: b.frequency,
            octaves: b.octaves,
            lacunarity: b.lacunarity,
            gain: b.gain,
            derivative: match b.derivative {
                BumpDerivative::CentralDifferences => c::BUMP_CENTRAL_DIFFERENCES,
                BumpDerivative::Analytic => c::BUMP_ANALYTIC,
            },
            epsilon: b.epsilon,
        }
    }
}

/// Mirrors `GpuMaterial` in `gbuffer_layout.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuMaterial {
    pub base_color: Vec4,
    /// rgb: emitted radiance; w: specular factor.
    pub emissive: Vec4,
    pub metallic: f32,
    pub roughness: f32,
    pub transmission: f32,
    pub ior: f32,
    pub normal_scale: f32,
    pub alpha_cutoff: f32,
    pub alpha_mode: i32,
    pub double_sided: i32,
    pub base_color_texture: i32,
    /// Its R channel scales the transmission factor (KHR_materials_transmission); -1: none.
    pub transmission_texture: i32,
    pub normal_texture: i32,
    pub emissive_texture: i32,
    pub base_color_uv_rows: [Vec4; 2],
    pub bump: GpuBump,
    /// Roughness in G, metalness in B, scaling the factors (glTF 2.0 §3.9.2); -1: none.
    pub metallic_roughness_texture: i32,
    /// Its alpha channel scales the specular factor (KHR_materials_specular); -1: none.
    pub specular_texture: i32,
    /// Its RGB scales the specular colour (KHR_materials_specular); -1: none.
    pub specular_color_texture: i32,
    /// 1: KHR_materials_unlit (the base colour as radiance, no reflection); 0 otherwise.
    pub unlit: i32,
    /// Each texture's KHR_texture_transform: the first two rows of its 3×3 matrix (identity without one).
    pub metallic_roughness_uv_rows: [Vec4; 2],
    pub normal_uv_rows: [Vec4; 2],
    pub emissive_uv_rows: [Vec4; 2],
    pub transmission_uv_rows: [Vec4; 2],
    /// rgb: the KHR_materials_specular colour, tinting the dielectric F0; w: unused.
    pub specular_color: Vec4,
    pub specular_uv_rows: [Vec4; 2],
    pub specular_color_uv_rows: [Vec4; 2],
    /// rgb: the absorption coefficient σ per metre inside (KHR_materials_volume, `Material::absorption`); w: the
    /// dispersion, 20 / V_d (KHR_materials_dispersion; 0: none).
    pub absorption: Vec4,
    /// KHR_materials_clearcoat: x the factor (0: no coat), y the roughness, z the coat normal texture's scale, w 1
    /// where the material has a layer or diffuse transmission (`Material::is_layered`), else 0.
    pub clearcoat: Vec4,
    /// KHR_materials_sheen: rgb the colour (black: no sheen), a the roughness.
    pub sheen: Vec4,
    /// R scales the coat's factor; -1: none (and likewise below).
    pub clearcoat_texture: i32,
    /// G scales the coat's roughness.
    pub clearcoat_roughness_texture: i32,
    pub clearcoat_normal_texture: i32,
    /// sRGB; RGB scales the sheen colour.
    pub sheen_color_texture: i32,
    /// A scales the sheen roughness.
    pub sheen_roughness_texture: i32,
    /// A scales the diffuse transmission factor (KHR_materials_diffuse_transmission).
    pub diffuse_transmission_texture: i32,
    /// sRGB; RGB scales the diffuse transmission colour.
    pub diffuse_transmission_color_texture: i32,
    pub pad: i32,
    pub clearcoat_uv_rows: [Vec4; 2],
    pub clearcoat_roughness_uv_rows: [Vec4; 2],
    pub clearcoat_normal_uv_rows: [Vec4; 2],
    pub sheen_color_uv_rows: [Vec4; 2],
    pub sheen_roughness_uv_rows: [Vec4; 2],
    /// KHR_materials_diffuse_transmission: rgb the colour, a the factor (0: none).
    pub diffuse_transmission: Vec4,
    pub diffuse_transmission_uv_rows: [Vec4; 2],
    pub diffuse_transmission_color_uv_rows: [Vec4; 2],
    /// KHR_materials_iridescence: x the factor (0: no film), y the film's index, z and w its thickness range (nm).
    pub iridescence: Vec4,
    /// R scales the iridescence factor.
    pub iridescence_texture: i32,
    /// G places the thickness between the range's ends (without one: its maximum).
    pub iridescence_thickness_texture: i32,
    pub pad1: [i32; 2],
    pub iridescence_uv_rows: [Vec4; 2],
    pub iridescence_thickness_uv_rows: [Vec4; 2],
    /// KHR_materials_anisotropy: x the strength (0: isotropic), y and z the rotation's cosine and sine, w unused.
    pub anisotropy: Vec4,
    /// RG a tangent-space direction, B scales the strength.
    pub anisotropy_texture: i32,
    pub pad2: [i32; 3],
    pub anisotropy_uv_rows: [Vec4; 2],
}

impl GpuMaterial {
    /// `texture_sizes`: width and height of each of the scene's textures, in texels (level 0).
    pub fn new(m: &Material, texture_sizes: &[(u32, u32)]) -> Self {
        let texture = |t: Option<crate::scene::TextureRef>| {
            t.filter(|t| t.texture < texture_sizes.len()).map(|t| t.texture as i32).unwrap_or(c::NO_TEXTURE)
        };
        // The first row's spare w says which UV set the texture reads: 1 for TEXCOORD_1, else TEXCOORD_0 (the
        // importer warns about the sets strata does not load). The second row's holds the texture's level of
        // detail per unit of UV footprint (texel_lod_offset), which ray hits add to their ray cone's.
        let uv_rows = |t: Option<crate::scene::TextureRef>| {
            let uv = t.and_then(|t| t.transform).map(|t| t.matrix()).unwrap_or(Mat3::IDENTITY);
            let set = if t.is_some_and(|t| t.tex_coord == 1) { 1.0 } else { 0.0 };
            let size = t.and_then(|t| texture_sizes.get(t.texture)).copied().unwrap_or((1, 1));
            [uv.row(0).extend(set), uv.row(1).extend(texel_lod_offset(size, uv))]
        };
        // An unlit material has no layers (KHR_materials_unlit): they are left out with the rest of its shading.
        let coat = m.clearcoat.filter(|_| !m.unlit).unwrap_or_default();
        let sheen = m.sheen.filter(|_| !m.unlit).unwrap_or_default();
        let transmits = m.diffuse_transmission.filter(|_| !m.unlit).unwrap_or_default();
        let film = m.iridescence.filter(|_| !m.unlit).unwrap_or_default();
        let stretch = m.anisotropy.filter(|_| !m.unlit).unwrap_or_default();
        let (alpha_mode, alpha_cutoff) = match m.alpha_mode {
            AlphaMode::Opaque => (c::ALPHA_OPAQUE, 0.0),
            AlphaMode::Mask { cutoff } => (c::ALPHA_MASK, cutoff),
            // The cutoff is unused: BLEND's test draws its own (alpha_test_passes).
            AlphaMode::Blend => (c::ALPHA_BLEND, 0.0),
        };
        Self {
            base_color: m.base_color,
            // An unlit material's emissive factor means nothing (KHR_materials_unlit): it is no light.
            emissive: if m.unlit { glam::Vec3::ZERO } else { m.emissive }.extend(m.specular),
            metallic: m.metallic,
            roughness: m.roughness,
            transmission: m.transmission,
            ior: m.ior,
            normal_scale: m.normal_scale,
            alpha_cutoff,
            alpha_mode,
            double_sided: i32::from(m.double_sided),
            base_color_texture: texture(m.base_color_texture),
            transmission_texture: texture(m.transmission_texture),
            normal_texture: texture(m.normal_texture),
            emissive_texture: texture(m.emissive_texture),
            base_color_uv_rows: uv_rows(m.base_color_texture),
            bump: GpuBump::from_bump(m.bump.as_ref()),
            metallic_roughness_texture: texture(m.metallic_roughness_texture),
            specular_texture: texture(m.specular_texture),
            specular_color_texture: texture(m.specular_color_texture),
            unlit: i32::from(m.unlit),
            metallic_roughness_uv_rows: uv_rows(m.metallic_roughness_texture),
            // The tangent frame (dpdu, dpdv) follows TEXCOORD_0, so normal textures read it.
            normal_uv_rows: uv_rows(m.normal_texture.map(|t| crate::scene::TextureRef { tex_coord: 0, ..t })),
            emissive_uv_rows: uv_rows(m.emissive_texture),
            transmission_uv_rows: uv_rows(m.transmission_texture),
            specular_color: m.specular_color.extend(0.0),
            specular_uv_rows: uv_rows(m.specular_texture),
            specular_color_uv_rows: uv_rows(m.specular_color_texture),
            absorption: m.absorption().extend(m.dispersion),
            clearcoat: Vec4::new(
                coat.factor,
                coat.roughness,
                coat.normal_scale,
                if m.is_layered() { 1.0 } else { 0.0 },
            ),
            sheen: sheen.color.extend(sheen.roughness),
            clearcoat_texture: texture(coat.texture),
            clearcoat_roughness_texture: texture(coat.roughness_texture),
            clearcoat_normal_texture: texture(coat.normal_texture),
            sheen_color_texture: texture(sheen.color_texture),
            sheen_roughness_texture: texture(sheen.roughness_texture),
            diffuse_transmission_texture: texture(transmits.texture),
            diffuse_transmission_color_texture: texture(transmits.color_texture),
            pad: 0,
            clearcoat_uv_rows: uv_rows(coat.texture),
            clearcoat_roughness_uv_rows: uv_rows(coat.roughness_texture),
            // The coat's normal texture, like the base's, reads TEXCOORD_0, whose derivatives are its tangent frame.
            clearcoat_normal_uv_rows: uv_rows(
                coat.normal_texture.map(|t| crate::scene::TextureRef { tex_coord: 0, ..t }),
            ),
            sheen_color_uv_rows: uv_rows(sheen.color_texture),
            sheen_roughness_uv_rows: uv_rows(sheen.roughness_texture),
            diffuse_transmission: transmits.color.extend(transmits.factor),
            diffuse_transmission_uv_rows: uv_rows(transmits.texture),
            diffuse_transmission_color_uv_rows: uv_rows(transmits.color_texture),
            iridescence: Vec4::new(film.factor, film.ior, film.thickness_min, film.thickness_max),
            iridescence_texture: texture(film.texture),
            iridescence_thickness_texture: texture(film.thickness_texture),
            pad1: [0; 2],
            iridescence_uv_rows: uv_rows(film.texture),
            iridescence_thickness_uv_rows: uv_rows(film.thickness_texture),
            anisotropy: Vec4::new(stretch.strength, stretch.rotation.cos(), stretch.rotation.sin(), 0.0),
            anisotropy_texture: texture(stretch.texture),
            pad2: [0; 3],
            // Its directions live in the tangent frame of TEXCOORD_0, which it reads as normal textures do.
            anisotropy_uv_rows: uv_rows(stretch.texture.map(|t| crate::scene::TextureRef { tex_coord: 0, ..t })),
        }
    }
}

/// The level of detail a texture adds to a footprint measured in its UV set: ½·log2(width · height · |det A|),
/// the log2 of texels per unit of UV length through the transform A (Akenine-Möller et al., "Texture Level of
/// Detail Strategies for Real-Time Ray Tracing", Ray Tracing Gems, 2019, ch. 20: the texture's share of the
/// ray cone's level of detail, its size and A's area scale taken out of the triangle term). Clamped, so a
/// degenerate transform reads level 0.
pub fn texel_lod_offset((width, height): (u32, u32), uv_transform: Mat3) -> f32 {
    let a = uv_transform.x_axis.x * uv_transform.y_axis.y - uv_transform.y_axis.x * uv_transform.x_axis.y;
    let texels_per_uv_area = width as f32 * height as f32 * a.abs();
    if texels_per_uv_area > 0.0 {
        (0.5 * texels_per_uv_area.log2()).clamp(-64.0, 64.0)
    } else {
        -64.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    #[test]
    fn layouts_match_glsl_std430() {
        // 88 bytes of GLSL block, padded to 16 (within the 128 bytes every device offers).
        assert_eq!(size_of::<GBufferPush>(), 96);
        assert_eq!(GBufferPush::DRAW_OFFSET, 80);
        assert_eq!(offset_of!(GBufferPush, material), 84);
        // Pushed as one GBufferDrawPush over both members.
        assert_eq!(size_of::<GBufferDrawPush>(), 8);
        assert_eq!(offset_of!(GBufferDrawPush, material), 84 - GBufferPush::DRAW_OFFSET as usize);
        assert_eq!(size_of::<GBufferDraw>(), 128);
        assert_eq!(offset_of!(GBufferDraw, normal_rows), 64);
        assert_eq!(offset_of!(GBufferDraw, instance), 112);
        assert_eq!(size_of::<GpuBump>(), 32);
        assert_eq!(offset_of!(GpuMaterial, emissive), 16);
        assert_eq!(offset_of!(GpuMaterial, metallic), 32);
        assert_eq!(offset_of!(GpuMaterial, alpha_mode), 56);
        assert_eq!(offset_of!(GpuMaterial, base_color_texture), 64);
        assert_eq!(offset_of!(GpuMaterial, base_color_uv_rows), 80);
        assert_eq!(offset_of!(GpuMaterial, bump), 112);
        assert_eq!(offset_of!(GpuMaterial, transmission_texture), 68);
        assert_eq!(offset_of!(GpuMaterial, metallic_roughness_texture), 144);
        assert_eq!(offset_of!(GpuMaterial, metallic_roughness_uv_rows), 160);
        assert_eq!(offset_of!(GpuMaterial, transmission_uv_rows), 256);
        assert_eq!(offset_of!(GpuMaterial, specular_texture), 148);
        assert_eq!(offset_of!(GpuMaterial, specular_color), 288);
        assert_eq!(offset_of!(GpuMaterial, specular_uv_rows), 304);
        assert_eq!(offset_of!(GpuMaterial, specular_color_texture), 152);
        assert_eq!(offset_of!(GpuMaterial, specular_color_uv_rows), 336);
        assert_eq!(offset_of!(GpuMaterial, absorption), 368);
        assert_eq!(offset_of!(GpuMaterial, clearcoat), 384);
        assert_eq!(offset_of!(GpuMaterial, sheen), 400);
        assert_eq!(offset_of!(GpuMaterial, clearcoat_texture), 416);
        assert_eq!(offset_of!(GpuMaterial, sheen_roughness_texture), 432);
        assert_eq!(offset_of!(GpuMaterial, clearcoat_uv_rows), 448);
        assert_eq!(offset_of!(GpuMaterial, sheen_roughness_uv_rows), 576);
        assert_eq!(offset_of!(GpuMaterial, diffuse_transmission), 608);
        assert_eq!(offset_of!(GpuMaterial, diffuse_transmission_color_uv_rows), 656);
        assert_eq!(offset_of!(GpuMaterial, iridescence), 688);
        assert_eq!(offset_of!(GpuMaterial, iridescence_texture), 704);
        assert_eq!(offset_of!(GpuMaterial, iridescence_thickness_uv_rows), 752);
        assert_eq!(offset_of!(GpuMaterial, anisotropy), 784);
        assert_eq!(offset_of!(GpuMaterial, anisotropy_uv_rows), 816);
        assert_eq!(size_of::<GpuMaterial>(), 848);
    }

    #[test]
    fn a_textures_level_offset_counts_texels_per_uv_length_through_its_transform() {
        use crate::scene::UvTransform;
        use glam::Vec2;
        assert_eq!(texel_lod_offset((256, 256), Mat3::IDENTITY), 8.0);
        assert_eq!(texel_lod_offset((512, 128), Mat3::IDENTITY), 8.0);
        // Scaling UVs by 8 packs 8× the texels into a unit of UV length; rotation and offset change nothing.
        let tiled = UvTransform { offset: Vec2::new(0.3, 0.1), rotation: 0.7, scale: Vec2::splat(8.0) };
        assert!((texel_lod_offset((48, 48), tiled.matrix()) - (48f32.log2() + 3.0)).abs() < 1e-5);
        assert_eq!(texel_lod_offset((48, 48), Mat3::ZERO), -64.0);
        let m = Material {
            base_color_texture: Some(crate::scene::TextureRef { texture: 1, tex_coord: 0, transform: None }),
            ..Default::default()
        };
        let gpu = GpuMaterial::new(&m, &[(2, 2), (1024, 1024)]);
        assert_eq!(gpu.base_color_texture, 1);
        assert_eq!(gpu.base_color_uv_rows[1].w, 10.0);
    }

    #[test]
    fn each_attachment_sits_at_the_location_shared_constants_give_it() {
        use super::attachment as a;
        let named = [
            (a::POSITION, "position"),
            (a::ALBEDO, "albedo"),
            (a::MATERIAL, "material"),
            (a::EMISSION, "emission"),
            (a::SPECULAR, "specular"),
            (a::SURFACE_IDS, "surface ids"),
        ];
        for (location, name) in named {
            assert_eq!(ATTACHMENTS[location].name, name);
        }
        assert_eq!(a::SURFACE_IDS, ATTACHMENTS.len() - 1, "the surface ids come last");
    }

    #[test]
    fn the_gbuffer_fits_its_memory_budget() {
        // Issue 30's budget is 100 bytes per pixel with the sums; the G-buffer takes 56 of them.
        assert_eq!(bytes_per_pixel(), 56);
    }
}
