//! The layered glTF materials' extensions, `KHR_materials_clearcoat`, `_sheen`, `_iridescence`, `_anisotropy` and
//! `_diffuse_transmission`, read from their
//! raw JSON (the gltf crate does not know them): factors checked against the ranges the extensions give, textures
//! against the file's, each error naming the extension and the property.
use super::material::{Anisotropy, Clearcoat, DiffuseTransmission, Iridescence, Sheen, TextureRef, UvTransform};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{Vec2, Vec3};
use serde_json::Value;

pub(super) const CLEARCOAT: &str = "KHR_materials_clearcoat";
pub(super) const SHEEN: &str = "KHR_materials_sheen";
pub(super) const DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";
pub(super) const IRIDESCENCE: &str = "KHR_materials_iridescence";
pub(super) const ANISOTROPY: &str = "KHR_materials_anisotropy";

/// A number property of an extension object in [0, 1], or `default` where absent.
fn unit_factor(ext: &Value, key: &str, default: f32) -> Result<f32> {
    let Some(value) = ext.get(key) else { return Ok(default) };
    let x = value.as_f64().with_context(|| format!("\"{key}\" is {value}, not a number"))? as f32;
    if !(0.0..=1.0).contains(&x) {
        bail!("\"{key}\" is {x}: it lies in [0, 1]");
    }
    Ok(x)
}

/// A textureInfo (or normalTextureInfo) property: its texture (which must exist among `texture_count`), its UV set
/// and its KHR_texture_transform; with `scale`, the normal texture's scale (default 1).
fn texture_info(ext: &Value, key: &str, texture_count: usize) -> Result<Option<(TextureRef, f32)>> {
    let Some(info) = ext.get(key) else { return Ok(None) };
    let context = || format!("\"{key}\"");
    let index = info.get("index").and_then(Value::as_u64).ok_or_else(|| anyhow!("has no texture \"index\""));
    let index = index.with_context(context)? as usize;
    if index >= texture_count {
        bail!("\"{key}\" names texture {index}; the file has {texture_count}");
    }
    let tex_coord = match info.get("texCoord") {
        None => 0,
        Some(v) => v.as_u64().filter(|&t| t <= u64::from(u32::MAX)).ok_or_else(|| anyhow!("\"texCoord\" is {v}"))?,
    } as u32;
    let scale = match info.get("scale") {
        None => 1.0,
        Some(v) => v.as_f64().ok_or_else(|| anyhow!("\"scale\" is {v}, not a number")).with_context(context)? as f32,
    };
    let mut texture = TextureRef { texture: index, tex_coord, transform: None };
    if let Some(raw) = info.get("extensions").and_then(|e| e.get("KHR_texture_transform")) {
        let t: gltf::json::extensions::texture::TextureTransform = serde_json::from_value(raw.clone())
            .map_err(|e| anyhow!("its KHR_texture_transform is malformed: {e}"))
            .with_context(context)?;
        texture.tex_coord = t.tex_coord.unwrap_or(tex_coord);
        texture.transform = Some(UvTransform {
            offset: Vec2::from_array(t.offset.0),
            rotation: t.rotation.0,
            scale: Vec2::from_array(t.scale.0),
        });
    }
    Ok(Some((texture, scale)))
}

/// `KHR_materials_clearcoat` of a material, if it has the extension.
pub(super) fn clearcoat(m: &gltf::Material<'_>, texture_count: usize) -> Result<Option<Clearcoat>> {
    let Some(ext) = m.extension_value(CLEARCOAT) else { return Ok(None) };
    let (normal_texture, normal_scale) = match texture_info(ext, "clearcoatNormalTexture", texture_count)? {
        Some((t, scale)) => (Some(t), scale),
        None => (None, 1.0),
    };
    Ok(Some(Clearcoat {
        factor: unit_factor(ext, "clearcoatFactor", 0.0)?,
        texture: texture_info(ext, "clearcoatTexture", texture_count)?.map(|t| t.0),
        roughness: unit_factor(ext, "clearcoatRoughnessFactor", 0.0)?,
        roughness_texture: texture_info(ext, "clearcoatRoughnessTexture", texture_count)?.map(|t| t.0),
        normal_texture,
        normal_scale,
    }))
}

/// A colour property of an extension object, three numbers in [0, 1], or `default` where absent.
fn color_factor(ext: &Value, key: &str, default: Vec3) -> Result<Vec3> {
    let Some(v) = ext.get(key) else { return Ok(default) };
    let channels: Option<Vec<f32>> =
        v.as_array().map(|a| a.iter().filter_map(Value::as_f64).map(|x| x as f32).collect());
    match channels.as_deref() {
        Some(&[r, g, b]) if [r, g, b].iter().all(|c| (0.0..=1.0).contains(c)) => Ok(Vec3::new(r, g, b)),
        _ => bail!("\"{key}\" is {v}: it is three numbers in [0, 1]"),
    }
}

/// `KHR_materials_sheen` of a material, if it has the extension.
pub(super) fn sheen(m: &gltf::Material<'_>, texture_count: usize) -> Result<Option<Sheen>> {
    let Some(ext) = m.extension_value(SHEEN) else { return Ok(None) };
    let color = color_factor(ext, "sheenColorFactor", Vec3::ZERO)?;
    Ok(Some(Sheen {
        color,
        color_texture: texture_info(ext, "sheenColorTexture", texture_count)?.map(|t| t.0),
        roughness: unit_factor(ext, "sheenRoughnessFactor", 0.0)?,
        roughness_texture: texture_info(ext, "sheenRoughnessTexture", texture_count)?.map(|t| t.0),
    }))
}

/// `KHR_materials_diffuse_transmission` of a material, if it has the extension.
pub(super) fn diffuse_transmission(
    m: &gltf::Material<'_>,
    texture_count: usize,
) -> Result<Option<DiffuseTransmission>> {
    let Some(ext) = m.extension_value(DIFFUSE_TRANSMISSION) else { return Ok(None) };
    Ok(Some(DiffuseTransmission {
        factor: unit_factor(ext, "diffuseTransmissionFactor", 0.0)?,
        texture: texture_info(ext, "diffuseTransmissionTexture", texture_count)?.map(|t| t.0),
        color: color_factor(ext, "diffuseTransmissionColorFactor", Vec3::ONE)?,
        color_texture: texture_info(ext, "diffuseTransmissionColorTexture", texture_count)?.map(|t| t.0),
    }))
}

/// A number property of an extension object, at least `min`, or `default` where absent.
fn number_at_least(ext: &Value, key: &str, min: f32, default: f32) -> Result<f32> {
    let Some(value) = ext.get(key) else { return Ok(default) };
    let x = value.as_f64().with_context(|| format!("\"{key}\" is {value}, not a number"))? as f32;
    if !(x >= min && x.is_finite()) {
        bail!("\"{key}\" is {x}: it is at least {min}");
    }
    Ok(x)
}

/// `KHR_materials_iridescence` of a material, if it has the extension.
pub(super) fn iridescence(m: &gltf::Material<'_>, texture_count: usize) -> Result<Option<Iridescence>> {
    let Some(ext) = m.extension_value(IRIDESCENCE) else { return Ok(None) };
    let defaults = Iridescence::default();
    let film = Iridescence {
        factor: unit_factor(ext, "iridescenceFactor", 0.0)?,
        texture: texture_info(ext, "iridescenceTexture", texture_count)?.map(|t| t.0),
        ior: number_at_least(ext, "iridescenceIor", 1.0, defaults.ior)?,
        thickness_min: number_at_least(ext, "iridescenceThicknessMinimum", 0.0, defaults.thickness_min)?,
        thickness_max: number_at_least(ext, "iridescenceThicknessMaximum", 0.0, defaults.thickness_max)?,
        thickness_texture: texture_info(ext, "iridescenceThicknessTexture", texture_count)?.map(|t| t.0),
    };
    Ok(Some(film))
}

/// `KHR_materials_anisotropy` of a material, if it has the extension.
pub(super) fn anisotropy(m: &gltf::Material<'_>, texture_count: usize) -> Result<Option<Anisotropy>> {
    let Some(ext) = m.extension_value(ANISOTROPY) else { return Ok(None) };
    let rotation = match ext.get("anisotropyRotation") {
        None => 0.0,
        Some(v) => match v.as_f64() {
            Some(r) if r.is_finite() => r as f32,
            _ => bail!("\"anisotropyRotation\" is {v}, not a number of radians"),
        },
    };
    Ok(Some(Anisotropy {
        strength: unit_factor(ext, "anisotropyStrength", 0.0)?,
        rotation,
        texture: texture_info(ext, "anisotropyTexture", texture_count)?.map(|t| t.0),
    }))
}
