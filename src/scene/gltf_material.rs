//! glTF materials, textures and images: the metallic-roughness material with the extensions strata reads
//! (emissive strength, IOR, specular, transmission, unlit, texture transforms; the layers' own file,
//! gltf_layers), samplers, and which image each
//! texture reads (its KTX2 or WebP alternative, or its source; decoding is image_decode's).
use super::gltf_layers;
use super::gltf_uri::{read_uri, UriPolicy};
use super::image_decode::decode_image;
use super::material::{AlphaMode, Material, MipFilter, Sampler, Texture, TextureImage, TextureRef, UvTransform, Wrap};
use super::Scene;
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{Vec2, Vec3, Vec4};
use std::path::Path;

/// Every image of the file, read and decoded; an image that fails is its error, for [`textures`] to judge (a
/// texture's KTX2 or WebP alternative may fail where its fallback PNG serves).
pub(super) fn load_images(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    base: &Path,
    policy: UriPolicy,
) -> Vec<Result<TextureImage>> {
    document
        .images()
        .map(|image| -> Result<TextureImage> {
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

/// Extensions that give a texture another image (KTX2, WebP) beside or instead of its `source`.
pub(super) const IMAGE_EXTENSIONS: [&str; 2] = ["KHR_texture_basisu", "EXT_texture_webp"];

/// The image a texture's KHR_texture_basisu or EXT_texture_webp names, if any.
fn extension_image(texture: &gltf::Texture<'_>) -> Option<(&'static str, usize)> {
    IMAGE_EXTENSIONS.into_iter().find_map(|ext| {
        let source = texture.extension_value(ext)?.get("source")?.as_u64()?;
        Some((ext, source as usize))
    })
}

/// The file's textures, each with the image it reads: its extension's (KTX2, WebP) where that decodes, else its
/// `source`; and the file's images, where one that no texture can read fails the load and one only a fallback
/// replaced becomes a 1x1 placeholder with a warning. `srgb` is set later from the materials that use each
/// texture (mark_color_textures).
pub(super) fn textures(
    document: &gltf::Document,
    images: Vec<Result<TextureImage>>,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Texture>, Vec<TextureImage>)> {
    let mut excused = vec![false; images.len()];
    let mut textures = Vec::new();
    for t in document.textures() {
        let name = t.name().map(str::to_owned).unwrap_or_else(|| format!("texture {}", t.index()));
        let fallback = t.source().index();
        let image = match extension_image(&t) {
            Some((ext, index)) if index >= images.len() => bail!("{name}: its {ext} image {index} does not exist"),
            Some((_, index)) if images[index].is_ok() => index,
            Some((ext, index)) if index != fallback && images.get(fallback).is_some_and(Result::is_ok) => {
                if let Err(e) = &images[index] {
                    warnings
                        .push(format!("{name}: its {ext} image does not decode ({e:#}); reading its fallback source"));
                }
                excused[index] = true;
                fallback
            }
            _ => fallback,
        };
        textures.push(Texture { name, image, sampler: sampler(&t.sampler()), srgb: false });
    }
    let images = images
        .into_iter()
        .enumerate()
        .map(|(i, image)| match image {
            Ok(image) => Ok(image),
            Err(_) if excused[i] => Ok(TextureImage {
                name: format!("image {i} (unread)"),
                width: 1,
                height: 1,
                rgba8: vec![255, 0, 255, 255],
            }),
            Err(e) => Err(e),
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((textures, images))
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
            ("clearcoat", m.clearcoat.and_then(|c| c.texture), 1),
            ("clearcoat roughness", m.clearcoat.and_then(|c| c.roughness_texture), 1),
            ("clearcoat normal", m.clearcoat.and_then(|c| c.normal_texture), 0),
            ("sheen colour", m.sheen.and_then(|s| s.color_texture), 1),
            ("sheen roughness", m.sheen.and_then(|s| s.roughness_texture), 1),
            ("diffuse transmission", m.diffuse_transmission.and_then(|d| d.texture), 1),
            ("iridescence", m.iridescence.and_then(|i| i.texture), 1),
            ("anisotropy", m.anisotropy.and_then(|a| a.texture), 0),
            ("iridescence thickness", m.iridescence.and_then(|i| i.thickness_texture), 1),
            ("diffuse transmission colour", m.diffuse_transmission.and_then(|d| d.color_texture), 1),
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

/// `KHR_materials_dispersion`'s `dispersion` (20 / V_d; 0 without the extension): a number, at least 0.
fn dispersion(m: &gltf::Material<'_>) -> Result<f32> {
    let Some(extension) = m.extension_value("KHR_materials_dispersion") else { return Ok(0.0) };
    let Some(value) = extension.get("dispersion") else { return Ok(0.0) };
    let dispersion = value.as_f64().with_context(|| format!("\"dispersion\" is {value}, not a number"))? as f32;
    if !(dispersion >= 0.0 && dispersion.is_finite()) {
        bail!("\"dispersion\" is {dispersion}: it is 20 / the Abbe number, at least 0");
    }
    Ok(dispersion)
}

pub(super) fn material(m: gltf::Material<'_>, root: &gltf::json::Root) -> Result<Material> {
    let pbr = m.pbr_metallic_roughness();
    let defaults = Material::default();
    let name = m.name().map(str::to_owned).unwrap_or_else(|| format!("material {}", m.index().unwrap_or(0)));
    let normal_transform = normal_texture_transform(&m, &name, root)?;
    let dispersion = dispersion(&m).with_context(|| format!("material \"{name}\": KHR_materials_dispersion"))?;
    let texture_count = root.textures.len();
    let clearcoat = gltf_layers::clearcoat(&m, texture_count)
        .with_context(|| format!("material \"{name}\": {}", gltf_layers::CLEARCOAT))?;
    let sheen = gltf_layers::sheen(&m, texture_count)
        .with_context(|| format!("material \"{name}\": {}", gltf_layers::SHEEN))?;
    let anisotropy = gltf_layers::anisotropy(&m, texture_count)
        .with_context(|| format!("material \"{name}\": {}", gltf_layers::ANISOTROPY))?;
    let iridescence = gltf_layers::iridescence(&m, texture_count)
        .with_context(|| format!("material \"{name}\": {}", gltf_layers::IRIDESCENCE))?;
    let diffuse_transmission = gltf_layers::diffuse_transmission(&m, texture_count)
        .with_context(|| format!("material \"{name}\": {}", gltf_layers::DIFFUSE_TRANSMISSION))?;
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
        attenuation_color: m
            .volume()
            .map(|v| Vec3::from_array(v.attenuation_color()))
            .unwrap_or(defaults.attenuation_color),
        attenuation_distance: m.volume().map(|v| v.attenuation_distance()).unwrap_or(defaults.attenuation_distance),
        dispersion,
        clearcoat,
        sheen,
        diffuse_transmission,
        iridescence,
        anisotropy,
        bump: None,
        unlit: m.unlit(),
    })
}

/// Base colour, emissive, specular colour, sheen colour and diffuse transmission colour textures hold sRGB-encoded
/// colour; the rest hold linear data (glTF 2.0 §3.9, KHR_materials_specular, _sheen, _diffuse_transmission).
pub(super) fn mark_color_textures(scene: &mut Scene) {
    for m in &scene.materials {
        let sheen_color = m.sheen.and_then(|s| s.color_texture);
        let transmitted_color = m.diffuse_transmission.and_then(|d| d.color_texture);
        let colors =
            [m.base_color_texture, m.emissive_texture, m.specular_color_texture, sheen_color, transmitted_color];
        for t in colors.into_iter().flatten() {
            if let Some(texture) = scene.textures.get_mut(t.texture) {
                texture.srgb = true;
            }
        }
    }
}
