//! Texture images as glTF files carry them: PNG and JPEG (glTF 2.0 §3.8), WebP (`EXT_texture_webp`) and KTX2
//! (`KHR_texture_basisu`'s container) with 8-bit uncompressed texels, raw or Zstandard-supercompressed, or with
//! Basis Universal texels (ETC1S, UASTC) transcoded to RGBA8. Every decoder is bounded: a corrupt header must not
//! make strata allocate gigabytes.
use super::material::TextureImage;
use anyhow::{anyhow, bail, Context as _, Result};

/// Largest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Decodes `bytes` (its MIME type, when the file gives one, else sniffed) into 8-bit RGBA.
pub fn decode_image(name: &str, bytes: &[u8], mime: Option<&str>) -> Result<TextureImage> {
    if mime == Some("image/ktx2") || bytes.starts_with(&KTX2_IDENTIFIER) {
        return decode_ktx2(name, bytes).context("KTX2");
    }
    let format = match mime {
        Some("image/png") => image::ImageFormat::Png,
        Some("image/jpeg") => image::ImageFormat::Jpeg,
        Some("image/webp") => image::ImageFormat::WebP,
        _ => image::guess_format(bytes).context("unknown image format (strata reads PNG, JPEG, WebP and KTX2)")?,
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

/// The 12 bytes every KTX2 file starts with (KTX 2.0 §3.1).
const KTX2_IDENTIFIER: [u8; 12] = [0xAB, b'K', b'T', b'X', b' ', b'2', b'0', 0xBB, b'\r', b'\n', 0x1A, b'\n'];

/// A KTX2 file's base mip level (strata makes its own mip chain) as RGBA8. Its texels are taken as stored: the
/// material that uses the texture says whether they are sRGB, as for PNG.
fn decode_ktx2(name: &str, bytes: &[u8]) -> Result<TextureImage> {
    use ktx2::{Format, SupercompressionScheme};
    let reader = ktx2::Reader::new(bytes).map_err(|e| anyhow!("not a valid KTX2 file: {e:?}"))?;
    let header = reader.header();
    let (width, height) = (header.pixel_width, header.pixel_height);
    if header.pixel_depth > 1 || header.layer_count > 1 || header.face_count != 1 {
        bail!(
            "a 3D, array or cube map texture ({}, {} layers, {} faces): glTF textures are 2D",
            header.pixel_depth,
            header.layer_count,
            header.face_count
        );
    }
    if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        bail!("{width}x{height} texels: each side must be 1 to {MAX_IMAGE_SIDE}");
    }
    // KTX 2.0 §3.4 and KHR_texture_basisu: Basis Universal payloads have no Vulkan format; ETC1S is the one
    // BasisLZ-supercompressed payload.
    let format = match header.format {
        Some(format) if header.supercompression_scheme != Some(SupercompressionScheme::BasisLZ) => format,
        _ => return transcode_basis(name, &reader, width, height),
    };
    let channels = match format {
        Format::R8G8B8A8_UNORM | Format::R8G8B8A8_SRGB | Format::B8G8R8A8_UNORM | Format::B8G8R8A8_SRGB => 4,
        Format::R8G8B8_UNORM | Format::R8G8B8_SRGB | Format::B8G8R8_UNORM | Format::B8G8R8_SRGB => 3,
        Format::R8G8_UNORM | Format::R8G8_SRGB => 2,
        Format::R8_UNORM | Format::R8_SRGB => 1,
        other => bail!(
            "texel format {other:?}: strata reads 8-bit uncompressed formats (R8 to R8G8B8A8) and Basis Universal"
        ),
    };
    let texels = width as usize * height as usize;
    let level = reader.levels().next().context("no mip level")?;
    let data = match header.supercompression_scheme {
        None => level.data.to_vec(),
        Some(SupercompressionScheme::Zstandard) => zstd_decompress(level.data, texels * channels)?,
        Some(other) => bail!("supercompression {other:?} (strata reads none and Zstandard)"),
    };
    if data.len() < texels * channels {
        bail!(
            "its base level holds {} bytes, {width}x{height} texels of {channels} bytes need {}",
            data.len(),
            texels * channels
        );
    }
    let bgr =
        [Format::B8G8R8A8_UNORM, Format::B8G8R8A8_SRGB, Format::B8G8R8_UNORM, Format::B8G8R8_SRGB].contains(&format);
    let mut rgba8 = Vec::with_capacity(texels * 4);
    for texel in data[..texels * channels].chunks_exact(channels) {
        // Missing channels read as a GPU samples them: green and blue 0, alpha 1.
        let mut rgba = [0, 0, 0, 255];
        rgba[..channels].copy_from_slice(texel);
        if bgr {
            rgba.swap(0, 2);
        }
        rgba8.extend(rgba);
    }
    Ok(TextureImage { name: name.to_owned(), width, height, rgba8 })
}

/// A KTX2 file's Basis Universal texels (ETC1S or UASTC, either supercompression) transcoded to RGBA8 by the
/// `basisu` crate, a port of Binomial's reference transcoder (tests/gltf_features.rs holds it to the reference's
/// bytes on scripts/make-basis-textures.sh's files). The base level only, as for every other KTX2 file.
fn transcode_basis(name: &str, reader: &ktx2::Reader<&[u8]>, width: u32, height: u32) -> Result<TextureImage> {
    use basisu::{DecodeFlags, TargetFormat, Transcoder};
    // The transcoder inflates a Zstandard level to the length its index records: bound that first, by the 16-byte
    // 4x4 blocks of UASTC, the largest Basis payload, at the level's size.
    for (i, level) in reader.levels().enumerate() {
        let blocks = |side: u32| u64::from(side.checked_shr(i as u32).unwrap_or(0).max(1).div_ceil(4));
        let largest = blocks(width) * blocks(height) * 16;
        if level.uncompressed_byte_length > largest {
            bail!(
                "mip level {i} claims {} uncompressed bytes; a {width}x{height} Basis Universal image's level \
                 holds at most {largest}",
                level.uncompressed_byte_length
            );
        }
    }
    let describe = |e: basisu::Error| match e {
        basisu::Error::InvalidData | basisu::Error::Truncated => {
            anyhow!("its Basis Universal data is corrupt or truncated ({e:?})")
        }
        other => anyhow!("its Basis Universal data cannot be transcoded: {other:?}"),
    };
    let transcoder = Transcoder::new(reader.data()).map_err(describe)?;
    if transcoder.is_video() {
        bail!("a Basis Universal video: glTF textures are single images");
    }
    if transcoder.base_dimensions() != (width, height) {
        bail!(
            "its Basis Universal data is {:?} texels, its KTX2 header says {width}x{height}",
            transcoder.base_dimensions()
        );
    }
    let rgba8 = transcoder.transcode(0, TargetFormat::Rgba32, DecodeFlags::NONE).map_err(describe)?;
    let expected = width as usize * height as usize * 4;
    if rgba8.len() != expected {
        bail!(
            "its Basis Universal base level transcoded to {} bytes, {width}x{height} RGBA8 texels are {expected}",
            rgba8.len()
        );
    }
    Ok(TextureImage { name: name.to_owned(), width, height, rgba8 })
}

/// A Zstandard frame's content, refusing more than `expected` bytes.
fn zstd_decompress(data: &[u8], expected: usize) -> Result<Vec<u8>> {
    use std::io::Read as _;
    let decoder = ruzstd::decoding::StreamingDecoder::new(data).map_err(|e| anyhow!("Zstandard: {e}"))?;
    let mut out = Vec::with_capacity(expected);
    decoder.take(expected as u64 + 1).read_to_end(&mut out).map_err(|e| anyhow!("Zstandard: {e}"))?;
    if out.len() > expected {
        bail!("its Zstandard data holds more than the {expected} bytes the base level needs");
    }
    Ok(out)
}
