//! Bounds checks for glTF accessors, done before any data is read: the gltf crate's readers silently truncate
//! (or panic) when a buffer is shorter than its accessors claim, and strata must instead say which accessor
//! overruns which buffer.
use anyhow::{bail, Context as _, Result};

fn view_range(view: &gltf::buffer::View<'_>, buffers: &[Vec<u8>]) -> Result<(usize, usize)> {
    let buffer =
        buffers.get(view.buffer().index()).with_context(|| format!("bufferView {}: no such buffer", view.index()))?;
    let end = view.offset().checked_add(view.length()).context("bufferView range overflows")?;
    if end > buffer.len() {
        bail!(
            "bufferView {} (bytes {}..{end}) overruns buffer {} ({} bytes)",
            view.index(),
            view.offset(),
            view.buffer().index(),
            buffer.len()
        );
    }
    Ok((view.offset(), end))
}

/// Checks that `count` elements of `element_size` bytes at `offset` with `stride` fit in `view`.
fn check_elements(
    what: &str,
    view: &gltf::buffer::View<'_>,
    buffers: &[Vec<u8>],
    offset: usize,
    count: usize,
    element_size: usize,
    stride: usize,
) -> Result<()> {
    let (start, end) = view_range(view, buffers)?;
    if count == 0 {
        return Ok(());
    }
    let needed = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(element_size))
        .and_then(|n| n.checked_add(offset))
        .context("accessor size overflows")?;
    if needed > end - start {
        bail!(
            "{what}: {count} elements of {element_size} bytes (stride {stride}) at offset {offset} need {needed} bytes, \
             but bufferView {} holds {}",
            view.index(),
            end - start
        );
    }
    Ok(())
}

/// Fails unless every byte `accessor` reads lies inside its buffer view and buffer, and its sparse indices are
/// strictly increasing and below `count` (glTF 2.0 §3.6.2.3).
pub fn check_accessor(accessor: &gltf::Accessor<'_>, buffers: &[Vec<u8>]) -> Result<()> {
    let what =
        format!("accessor {}{}", accessor.index(), accessor.name().map(|n| format!(" \"{n}\"")).unwrap_or_default());
    let element_size = accessor.size();
    if let Some(view) = accessor.view() {
        let stride = view.stride().unwrap_or(element_size);
        if stride < element_size {
            bail!("{what}: byteStride {stride} is smaller than its element ({element_size} bytes)");
        }
        check_elements(&what, &view, buffers, accessor.offset(), accessor.count(), element_size, stride)?;
    }
    if let Some(sparse) = accessor.sparse() {
        let count = sparse.count();
        let indices = sparse.indices();
        let index_size = match indices.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let index_view = indices.view();
        check_elements(
            &format!("{what} sparse indices"),
            &index_view,
            buffers,
            indices.offset(),
            count,
            index_size,
            index_size,
        )?;
        let values = sparse.values();
        check_elements(
            &format!("{what} sparse values"),
            &values.view(),
            buffers,
            values.offset(),
            count,
            element_size,
            element_size,
        )?;
        // Now safe to read the indices.
        let (start, _) = view_range(&index_view, buffers)?;
        let data = &buffers[index_view.buffer().index()][start + indices.offset()..];
        let mut previous: Option<u32> = None;
        for i in 0..count {
            let at = i * index_size;
            let index = match index_size {
                1 => u32::from(data[at]),
                2 => u32::from(u16::from_le_bytes([data[at], data[at + 1]])),
                _ => u32::from_le_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]),
            };
            if index as usize >= accessor.count() || previous.is_some_and(|p| index <= p) {
                bail!("{what}: sparse index {index} at position {i} is out of order or ≥ count {}", accessor.count());
            }
            previous = Some(index);
        }
    }
    Ok(())
}

/// Collects a reader's values after the accessor was checked; a length mismatch is an error, not a truncation.
pub fn collect_exact<T>(what: &str, accessor: &gltf::Accessor<'_>, values: impl Iterator<Item = T>) -> Result<Vec<T>> {
    let values: Vec<T> = values.collect();
    if values.len() != accessor.count() {
        bail!("{what}: read {} values, accessor {} declares {}", values.len(), accessor.index(), accessor.count());
    }
    Ok(values)
}

/// Component types glTF allows for a use: (type, normalized).
pub type AllowedTypes = &'static [(gltf::accessor::DataType, bool)];

/// Fails unless `accessor` has one of the element shapes and component types glTF allows for its use
/// (glTF 2.0 §3.7.2.1 for attributes, §3.7.2.2 for indices, §3.11 for animation samplers). The gltf crate's
/// readers assume these and panic otherwise.
pub fn check_format(
    what: &str,
    accessor: &gltf::Accessor<'_>,
    dimensions: &[gltf::accessor::Dimensions],
    types: &[(gltf::accessor::DataType, bool)],
) -> Result<()> {
    let (dims, ty, normalized) = (accessor.dimensions(), accessor.data_type(), accessor.normalized());
    if !dimensions.contains(&dims) {
        bail!("{what}: accessor {} is {dims:?}, glTF allows {dimensions:?} here", accessor.index());
    }
    // `normalized` only matters for integer types; floats must not claim it.
    let ok = types.iter().any(|&(t, n)| t == ty && (t == gltf::accessor::DataType::F32 || n == normalized));
    if !ok || (ty == gltf::accessor::DataType::F32 && normalized) {
        let kind = if normalized { "normalized " } else { "" };
        bail!("{what}: accessor {} holds {kind}{ty:?} components, which glTF does not allow here", accessor.index());
    }
    Ok(())
}

/// The formats glTF allows per attribute semantic; `None` for semantics strata does not read. With `quantized`
/// (the file uses `KHR_mesh_quantization`), the extension's integer formats too.
pub fn attribute_formats(
    semantic: &gltf::Semantic,
    quantized: bool,
) -> Option<(&'static [gltf::accessor::Dimensions], AllowedTypes)> {
    use gltf::accessor::{DataType::*, Dimensions::*};
    const FLOAT: AllowedTypes = &[(F32, false)];
    const UV: AllowedTypes = &[(F32, false), (U8, true), (U16, true)];
    Some(match (semantic, quantized) {
        (gltf::Semantic::Positions, true) => (&[Vec3], QUANTIZED_POSITION),
        (gltf::Semantic::Normals, true) => (&[Vec3], QUANTIZED_DIRECTION),
        (gltf::Semantic::Tangents, true) => (&[Vec4], QUANTIZED_DIRECTION),
        (gltf::Semantic::TexCoords(_), true) => (&[Vec2], QUANTIZED_TEXCOORD),
        (gltf::Semantic::Positions | gltf::Semantic::Normals, false) => (&[Vec3], FLOAT),
        (gltf::Semantic::Tangents, false) => (&[Vec4], FLOAT),
        (gltf::Semantic::TexCoords(_), false) => (&[Vec2], UV),
        (gltf::Semantic::Colors(_), _) => (&[Vec3, Vec4], UV),
        // §3.7.3.2: joint indices are unsigned integers; weights floats or normalized unsigned integers.
        (gltf::Semantic::Joints(_), _) => (&[Vec4], &[(U8, false), (U16, false)]),
        (gltf::Semantic::Weights(_), _) => (&[Vec4], UV),
        _ => return None,
    })
}

/// `KHR_mesh_quantization`'s component types: positions (and morph targets' position displacements) of any
/// integer type up to 16 bits, normalized or not; normals and tangents (and their displacements) normalized
/// signed integers; texture coordinates any of them too.
pub const QUANTIZED_POSITION: AllowedTypes = &[
    (gltf::accessor::DataType::F32, false),
    (gltf::accessor::DataType::I8, false),
    (gltf::accessor::DataType::I8, true),
    (gltf::accessor::DataType::U8, false),
    (gltf::accessor::DataType::U8, true),
    (gltf::accessor::DataType::I16, false),
    (gltf::accessor::DataType::I16, true),
    (gltf::accessor::DataType::U16, false),
    (gltf::accessor::DataType::U16, true),
];
pub const QUANTIZED_DIRECTION: AllowedTypes = &[
    (gltf::accessor::DataType::F32, false),
    (gltf::accessor::DataType::I8, true),
    (gltf::accessor::DataType::I16, true),
];
pub const QUANTIZED_TEXCOORD: AllowedTypes = QUANTIZED_POSITION;
/// Morph targets' position displacements: signed types only (a displacement may point either way).
pub const QUANTIZED_DISPLACEMENT: AllowedTypes = &[
    (gltf::accessor::DataType::F32, false),
    (gltf::accessor::DataType::I8, false),
    (gltf::accessor::DataType::I8, true),
    (gltf::accessor::DataType::I16, false),
    (gltf::accessor::DataType::I16, true),
];

/// An integer component as a float: normalized values map to [0, 1] or [−1, 1] (glTF 2.0 §3.11's table:
/// c / (2ⁿ − 1) unsigned, max(c / (2ⁿ⁻¹ − 1), −1) signed), the others convert as they are
/// (`KHR_mesh_quantization`; the node's transform scales them back).
trait Component: gltf::accessor::Item + Copy {
    fn to_f32(self, normalized: bool) -> f32;
}

macro_rules! component {
    ($t:ty, $max:expr) => {
        impl Component for $t {
            fn to_f32(self, normalized: bool) -> f32 {
                if normalized {
                    (f32::from(self) / $max).max(-1.0)
                } else {
                    f32::from(self)
                }
            }
        }
    };
}
component!(i8, 127.0);
component!(u8, 255.0);
component!(i16, 32767.0);
component!(u16, 65535.0);

impl Component for f32 {
    fn to_f32(self, _: bool) -> f32 {
        self
    }
}

fn read_as<C: Component, const N: usize>(accessor: &gltf::Accessor<'_>, buffers: &[Vec<u8>]) -> Option<Vec<[f32; N]>>
where
    [C; N]: gltf::accessor::Item,
{
    let normalized = accessor.normalized();
    let values = gltf::accessor::Iter::<[C; N]>::new(accessor.clone(), |b: gltf::Buffer<'_>| {
        buffers.get(b.index()).map(Vec::as_slice)
    })?;
    Some(values.map(|v| v.map(|c| c.to_f32(normalized))).collect())
}

/// An accessor of N-component vectors as floats, whatever component type it holds (sparse substitutions
/// applied), after `check_format` and `check_accessor` passed; a length mismatch is an error.
pub fn read_floats<const N: usize>(
    what: &str,
    accessor: &gltf::Accessor<'_>,
    buffers: &[Vec<u8>],
) -> Result<Vec<[f32; N]>>
where
    [f32; N]: gltf::accessor::Item,
    [i8; N]: gltf::accessor::Item,
    [u8; N]: gltf::accessor::Item,
    [i16; N]: gltf::accessor::Item,
    [u16; N]: gltf::accessor::Item,
{
    use gltf::accessor::DataType::*;
    let values = match accessor.data_type() {
        F32 => read_as::<f32, N>(accessor, buffers),
        I8 => read_as::<i8, N>(accessor, buffers),
        U8 => read_as::<u8, N>(accessor, buffers),
        I16 => read_as::<i16, N>(accessor, buffers),
        U16 => read_as::<u16, N>(accessor, buffers),
        U32 => bail!("{what}: accessor {} holds U32 components, which no vertex attribute may", accessor.index()),
    };
    let values = values.with_context(|| format!("{what}: accessor {} cannot be read", accessor.index()))?;
    collect_exact(what, accessor, values.into_iter())
}
