//! glTF materials, textures and images: the metallic-roughness material with the extensions strata reads
//! (emissive strength, IOR, specular, transmission, texture transforms), samplers, and PNG/JPEG decoding with
//! a size limit.
use super::gltf_uri::{read_uri, UriPolicy};
use super::material::{AlphaMode, Material, MipFilter, Sampler, Texture, TextureImage, TextureRef, UvTransform, Wrap};
use super::Scene;
use anyhow::{anyhow, Context as _, Result};
use glam::{Vec2, Vec3, Vec4};
use std::path::Path;

/// Largest image side accepted (a corrupt header must not make strata allocate gigabytes).
const MAX_IMAGE_SIDE: u32 = 16384;

pub(super) fn load_images(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    base: &Path,
    policy: UriPolicy,
) -> Result<Vec<TextureImage>> {
    document
        .images()
        .map(|image| {
            let name = image.name().map(str::to_owned).unwrap_or_else(|| format!("image {}", image.index()));
            let (bytes, mime) = match image.source() {
                gltf::image::Source::View { view, mime_type } => {
                    let buffer = &buffers[view.buffer().index()];
                    let end = view.offset().checked_add(view.length()).filter(|&e| e <= buffer.len());
                    let end =
                        end.ok_or_else(|| anyhow!("{name}: its bufferView overruns buffer {}", view.buffer().index()))?;
                    (buffer[view.offset()..end].to_vec(), Some(mime_type))
                }
                gltf::image::Source::Uri { uri, mime_type } => {
                    (read_uri(uri, base, policy).with_context(|| name.clone())?, mime_type)
                }
            };
            decode_image(&name, &bytes, mime).with_context(|| format!("{name} does not decode"))
        })
        .collect()
}

fn decode_image(name: &str, bytes: &[u8], mime: Option<&str>) -> Result<TextureImage> {
    let format = match mime {
        Some("image/png") => image::ImageFormat::Png,
        Some("image/jpeg") => image::ImageFormat::Jpeg,
        _ => image::guess_format(bytes).context("unknown image format (strata reads PNG and JPEG)")?,
    };
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    reader.limits(limits);
    let decoded = reader.decode()?.to_rgba8();
    Ok(TextureImage {
        name: name.to_owned(),
        width: decoded.width(),
        height: decoded.height(),
        rgba8: decoded.into_raw(),
    })
}

/// The file's textures: each names its image and its sampler; `srgb` is set later from the materials that use
/// it (mark_color_textures).
pub(super) fn textures(document: &gltf::Document) -> Vec<Texture> {
    document
        .textures()
        .map(|t| Texture {
            name: t.name().map(str::to_owned).unwrap_or_else(|| format!("texture {}", t.index())),
            image: t.source().index(),
            sampler: sampler(&t.sampler()),
            srgb: false,
        })
        .collect()
}

fn sampler(s: &gltf::texture::Sampler<'_>) -> Sampler {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |w: WrappingMode| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let defaults = Sampler::default();
    let (min_linear, mipmaps) = match s.min_filter() {
        None => (defaults.min_linear, defaults.mipmaps),
        Some(MinFilter::Nearest) => (false, MipFilter::None),
        Some(MinFilter::Linear) => (true, MipFilter::None),
        Some(MinFilter::NearestMipmapNearest) => (false, MipFilter::Nearest),
        Some(MinFilter::LinearMipmapNearest) => (true, MipFilter::Nearest),
        Some(MinFilter::NearestMipmapLinear) => (false, MipFilter::Linear),
        Some(MinFilter::LinearMipmapLinear) => (true, MipFilter::Linear),
    };
    Sampler {
        mag_linear: s.mag_filter().map(|f| f == MagFilter::Linear).unwrap_or(defaults.mag_linear),
        min_linear,
        mipmaps,
        wrap_s: wrap(s.wrap_s()),
        wrap_t: wrap(s.wrap_t()),
    }
}

fn texture_ref(info: &gltf::texture::Info<'_>) -> TextureRef {
    let transform = info.texture_transform();
    TextureRef {
        texture: info.texture().index(),
        tex_coord: transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord()),
        transform: transform.map(|t| uv_transform(t.offset(), t.rotation(), t.scale())),
    }
}

/// A normal texture's KHR_texture_transform: the gltf crate reads the extension on textureInfo only, so it is
/// read here from the normalTextureInfo's raw extension object.
fn normal_texture_transform(
    m: &gltf::Material<'_>,
    name: &str,
    root: &gltf::json::Root,
) -> Result<Option<UvTransform>> {
    let raw = m
        .index()
        .and_then(|i| root.materials.get(i))
        .and_then(|json| json.normal_texture.as_ref())
        .and_then(|t| t.extensions.as_ref())
        .and_then(|e| e.others.get("KHR_texture_transform"));
    let Some(raw) = raw else { return Ok(None) };
    let t: gltf::json::extensions::texture::TextureTransform = serde_json::from_value(raw.clone())
        .map_err(|e| anyhow!("{name}: its normal texture's KHR_texture_transform is malformed: {e}"))?;
    Ok(Some(uv_transform(t.offset.0, t.rotation.0, t.scale.0)))
}

fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
    UvTransform { offset: Vec2::from_array(offset), rotation, scale: Vec2::from_array(scale) }
}

/// strata loads TEXCOORD_0 and TEXCOORD_1, and normal textures follow TEXCOORD_0 (their tangent frame is its
/// derivatives; README, known limits): say so where a material asks for another set.
pub(super) fn warn_about_unread_uv_sets(scene: &mut Scene) {
    let mut warnings = Vec::new();
    for m in &scene.materials {
        let uses = [
            ("base colour", m.base_color_texture, 1),
            ("metallic-roughness", m.metallic_roughness_texture, 1),
            ("normal", m.normal_texture, 0),
            ("emissive", m.emissive_texture, 1),
            ("transmission", m.transmission_texture, 1),
            ("specular", m.specular_texture, 1),
            ("specular colour", m.specular_color_texture, 1),
        ];
        for (what, t, last_read) in uses {
            if let Some(t) = t.filter(|t| t.tex_coord > last_read) {
                warnings.push(format!(
                    "material \"{}\": its {what} texture uses TEXCOORD_{}; strata reads it with TEXCOORD_0",
                    m.name, t.tex_coord
                ));
            }
        }
    }
    scene.warnings.extend(warnings);
}

pub(super) fn material(m: gltf::Material<'_>, root: &gltf::json::Root) -> Result<Material> {
    let pbr = m.pbr_metallic_roughness();
    let defaults = Material::default();
    let name = m.name().map(str::to_owned).unwrap_or_else(|| format!("material {}", m.index().unwrap_or(0)));
    let normal_transform = normal_texture_transform(&m, &name, root)?;
    Ok(Material {
        name,
        base_color: Vec4::from_array(pbr.base_color_factor()),
        base_color_texture: pbr.base_color_texture().as_ref().map(texture_ref),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        metallic_roughness_texture: pbr.metallic_roughness_texture().as_ref().map(texture_ref),
        normal_texture: m.normal_texture().map(|n| TextureRef {
            texture: n.texture().index(),
            tex_coord: n.tex_coord(),
            transform: normal_transform,
        }),
        normal_scale: m.normal_texture().map(|n| n.scale()).unwrap_or(1.0),
        occlusion_texture: m.occlusion_texture().map(|o| TextureRef {
            texture: o.texture().index(),
            tex_coord: o.tex_coord(),
            transform: None,
        }),
        occlusion_strength: m.occlusion_texture().map(|o| o.strength()).unwrap_or(1.0),
        emissive: Vec3::from_array(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
        emissive_texture: m.emissive_texture().as_ref().map(texture_ref),
        alpha_mode: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        double_sided: m.double_sided(),
        transmission: m.transmission().map(|t| t.transmission_factor()).unwrap_or(0.0),
        transmission_texture: m.transmission().and_then(|t| t.transmission_texture()).as_ref().map(texture_ref),
        ior: m.ior().unwrap_or(defaults.ior),
        specular: m.specular().map(|s| s.specular_factor()).unwrap_or(defaults.specular),
        specular_texture: m.specular().and_then(|s| s.specular_texture()).as_ref().map(texture_ref),
        specular_color: m
            .specular()
            .map(|s| Vec3::from_array(s.specular_color_factor()))
            .unwrap_or(defaults.specular_color),
        specular_color_texture: m.specular().and_then(|s| s.specular_color_texture()).as_ref().map(texture_ref),
        bump: None,
        unlit: m.unlit(),
    })
}

/// Base colour, emissive and specular colour textures hold sRGB-encoded colour; the rest hold linear data (glTF
/// 2.0 §3.9, KHR_materials_specular).
pub(super) fn mark_color_textures(scene: &mut Scene) {
    for m in &scene.materials {
        for t in [m.base_color_texture, m.emissive_texture, m.specular_color_texture].into_iter().flatten() {
            if let Some(texture) = scene.textures.get_mut(t.texture) {
                texture.srgb = true;
            }
        }
    }
}
