//! `EXT_meshopt_compression`: buffer views stored compressed by meshoptimizer's codecs (gltfpack's `-c`). Each such
//! view names its compressed bytes (buffer, offset, length) and how to decode them (mode ATTRIBUTES, TRIANGLES or
//! INDICES; filter NONE, OCTAHEDRAL or EXPONENTIAL); the decoded bytes go where the view itself points, usually a
//! "fallback" buffer with no data of its own. Accessors then read them as any view. The codecs are the pure-Rust
//! port `meshopt-rs`; the octahedral and exponential filters, applied after the codec, are its ports of
//! meshoptimizer's scalar reference code. The quaternion filter is written here from the extension's Appendix B:
//! the port's reads the components as unsigned and predates the extension's formulation.
use anyhow::{anyhow, bail, Result};
use serde::Deserialize;

pub const EXTENSION: &str = "EXT_meshopt_compression";

/// The most bytes a fallback buffer may declare: it is memory strata allocates before decoding into it, not data
/// the file holds (the file itself is read bounded, 4 GiB).
pub const MAX_FALLBACK_BYTES: usize = 1 << 30;

/// What a buffer view's extension object holds.
#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct CompressedView {
    buffer: usize,
    #[serde(default)]
    byte_offset: usize,
    byte_length: usize,
    byte_stride: usize,
    count: usize,
    mode: String,
    #[serde(default = "no_filter")]
    filter: String,
}

fn no_filter() -> String {
    "NONE".into()
}

/// A fallback buffer's bytes (zero until compressed views decode into them), or None for a buffer with data of
/// its own. A declared length above [`MAX_FALLBACK_BYTES`] is an error.
pub fn fallback_bytes(buffer: &gltf::Buffer<'_>) -> Option<Result<Vec<u8>>> {
    let fallback = buffer.extension_value(EXTENSION).and_then(|e| e.get("fallback")).and_then(|f| f.as_bool());
    if fallback != Some(true) {
        return None;
    }
    Some(if buffer.length() > MAX_FALLBACK_BYTES {
        Err(anyhow!(
            "buffer {} ({EXTENSION} fallback) declares {} bytes; strata decodes at most {MAX_FALLBACK_BYTES}",
            buffer.index(),
            buffer.length()
        ))
    } else {
        Ok(vec![0; buffer.length()])
    })
}

/// Decodes every compressed buffer view of `document` into `buffers`, where each view points.
pub fn decode_views(document: &gltf::Document, buffers: &mut [Vec<u8>]) -> Result<()> {
    for view in document.views() {
        let Some(value) = view.extension_value(EXTENSION) else { continue };
        let what = format!("bufferView {} ({EXTENSION})", view.index());
        let c: CompressedView =
            serde_json::from_value(value.clone()).map_err(|e| anyhow!("{what}: not a valid extension object: {e}"))?;
        let source = buffers
            .get(c.buffer)
            .and_then(|b| b.get(c.byte_offset..c.byte_offset.checked_add(c.byte_length)?))
            .ok_or_else(|| anyhow!("{what}: its compressed bytes lie outside buffer {}", c.buffer))?
            .to_vec();
        let size = c.count.checked_mul(c.byte_stride).filter(|&s| s <= view.length());
        let Some(size) = size else {
            bail!("{what}: {} × {} bytes do not fit the view's {} bytes", c.count, c.byte_stride, view.length());
        };
        let target_buffer = view.buffer().index();
        let range = view.offset()..view.offset().saturating_add(size);
        if buffers.get(target_buffer).is_none_or(|b| b.len() < range.end) {
            bail!("{what}: the view lies outside buffer {target_buffer}");
        }
        let decoded = decode(&c, &source).map_err(|e| anyhow!("{what}: {e}"))?;
        buffers[target_buffer][range].copy_from_slice(&decoded);
    }
    Ok(())
}

/// One view's bytes, decoded and filtered.
fn decode(c: &CompressedView, source: &[u8]) -> Result<Vec<u8>> {
    match c.mode.as_str() {
        "ATTRIBUTES" => {
            if c.byte_stride == 0 || c.byte_stride % 4 != 0 || c.byte_stride > 256 {
                bail!("ATTRIBUTES need a byteStride that is a multiple of 4 up to 256, not {}", c.byte_stride);
            }
            let mut data = decode_attributes(source, c.count, c.byte_stride)?;
            filter(&c.filter, c.byte_stride, &mut data)?;
            Ok(data)
        }
        "TRIANGLES" | "INDICES" => {
            if c.filter != "NONE" {
                bail!("{} data takes no filter, not {}", c.mode, c.filter);
            }
            if c.byte_stride != 2 && c.byte_stride != 4 {
                bail!("{} need a byteStride of 2 or 4, not {}", c.mode, c.byte_stride);
            }
            if c.mode == "TRIANGLES" && c.count % 3 != 0 {
                bail!("TRIANGLES need a count divisible by 3, not {}", c.count);
            }
            let mut indices = vec![0u32; c.count];
            let decoded = if c.mode == "TRIANGLES" {
                meshopt_rs::index::buffer::decode_index_buffer(&mut indices, source).map_err(|e| anyhow!("{e:?}"))
            } else {
                meshopt_rs::index::sequence::decode_index_sequence(&mut indices, source).map_err(|e| anyhow!("{e:?}"))
            };
            decoded.map_err(|e| anyhow!("the index codec failed: {e}"))?;
            Ok(if c.byte_stride == 2 {
                indices.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect()
            } else {
                indices.iter().flat_map(|&i| i.to_le_bytes()).collect()
            })
        }
        other => bail!("unknown mode {other:?} (ATTRIBUTES, TRIANGLES or INDICES)"),
    }
}

/// The vertex codec for a stride known only at run time: the port takes the vertex as a type.
fn decode_attributes(source: &[u8], count: usize, stride: usize) -> Result<Vec<u8>> {
    fn with<const N: usize>(source: &[u8], count: usize) -> Result<Vec<u8>> {
        let mut vertices = vec![[0u32; N]; count];
        meshopt_rs::vertex::buffer::decode_vertex_buffer(&mut vertices, source)
            .map_err(|e| anyhow!("the vertex codec failed: {e:?}"))?;
        Ok(vertices.iter().flatten().flat_map(|w| w.to_ne_bytes()).collect())
    }
    macro_rules! strides {
        ($($n:literal)*) => {
            match stride / 4 {
                $($n => with::<$n>(source, count),)*
                _ => unreachable!("checked by the caller"),
            }
        };
    }
    strides!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32 33 34 35 36 37
        38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60 61 62 63 64)
}

/// The filter a view names, applied in place to its decoded vertices.
fn filter(name: &str, stride: usize, data: &mut [u8]) -> Result<()> {
    match name {
        "NONE" => {}
        "OCTAHEDRAL" => match stride {
            4 => meshopt_rs::vertex::filter::decode_filter_oct_8(bytemuck::cast_slice_mut(data)),
            8 => {
                let mut words: Vec<[u16; 4]> = data
                    .chunks_exact(8)
                    .map(|v| std::array::from_fn(|k| u16::from_le_bytes([v[2 * k], v[2 * k + 1]])))
                    .collect();
                meshopt_rs::vertex::filter::decode_filter_oct_16(&mut words);
                for (v, w) in data.chunks_exact_mut(8).zip(&words) {
                    for k in 0..4 {
                        v[2 * k..2 * k + 2].copy_from_slice(&w[k].to_le_bytes());
                    }
                }
            }
            _ => bail!("the OCTAHEDRAL filter needs a byteStride of 4 or 8, not {stride}"),
        },
        "EXPONENTIAL" => {
            let mut words: Vec<u32> =
                data.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect();
            meshopt_rs::vertex::filter::decode_filter_exp(&mut words);
            for (out, w) in data.chunks_exact_mut(4).zip(&words) {
                out.copy_from_slice(&w.to_le_bytes());
            }
        }
        "QUATERNION" => {
            if stride != 8 {
                bail!("the QUATERNION filter needs a byteStride of 8, not {stride}");
            }
            for v in data.chunks_exact_mut(8) {
                let input: [i16; 4] = std::array::from_fn(|k| i16::from_le_bytes([v[2 * k], v[2 * k + 1]]));
                for (k, c) in decode_quaternion(input).iter().enumerate() {
                    v[2 * k..2 * k + 2].copy_from_slice(&c.to_le_bytes());
                }
            }
        }
        other => bail!("unknown filter {other:?} (NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL)"),
    }
    Ok(())
}

/// One quaternion of the QUATERNION filter (EXT_meshopt_compression, Appendix B, filter 2): three components
/// scaled by √2 as signed normalized integers, the fourth holding 1.0 at the same bit count with the index of the
/// omitted largest component in its two low bits; out come four 16-bit normalized components.
fn decode_quaternion(input: [i16; 4]) -> [i16; 4] {
    let range = std::f32::consts::FRAC_1_SQRT_2;
    let one = f32::from(input[3] | 3);
    let [x, y, z] = [0, 1, 2].map(|k| f32::from(input[k]) / one * range);
    let w = (1.0 - x * x - y * y - z * z).max(0.0).sqrt();
    // C's round: half away from zero, as Rust's f32::round.
    let snorm = |v: f32| (v * 32767.0).round() as i16;
    let largest = (input[3] & 3) as usize;
    let mut output = [0i16; 4];
    output[(largest + 1) % 4] = snorm(x);
    output[(largest + 2) % 4] = snorm(y);
    output[(largest + 3) % 4] = snorm(z);
    output[largest] = snorm(w);
    output
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worked by hand from Appendix B: the identity (largest w, index 3) and a quarter turn about +Y (largest y,
    /// index 1, so the inputs are z, w, x in that cyclic order, w = √½ stored as √½·√2 = 1.0), and a negative
    /// component, which the port's unsigned reading gets wrong.
    #[test]
    fn quaternions_decode_as_the_extension_specifies() {
        assert_eq!(decode_quaternion([0, 0, 0, 32767]), [0, 0, 0, 32767]);
        assert_eq!(decode_quaternion([0, 32767, 0, (32767 & !3) | 1]), [0, 23170, 0, 23170]);
        // −½ on x with w largest: x = −16384/32767·√½ = −0.35356, w = √(1 − x²) = 0.93541.
        assert_eq!(decode_quaternion([-16384, 0, 0, 32767]), [-11585, 0, 0, 30651]);
        let mut bytes: Vec<u8> = [0i16, 32767, 0, (32767 & !3) | 1].iter().flat_map(|c| c.to_le_bytes()).collect();
        filter("QUATERNION", 8, &mut bytes).unwrap();
        assert_eq!(bytes, [0i16, 23170, 0, 23170].iter().flat_map(|c| c.to_le_bytes()).collect::<Vec<_>>());
        assert!(filter("QUATERNION", 4, &mut [0; 4]).unwrap_err().to_string().contains("byteStride of 8"));
    }
}
