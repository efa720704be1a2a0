//! `KHR_draco_mesh_compression`: a primitive whose attributes and indices are one Draco bitstream in a buffer view
//! (the extension's `bufferView`), its `attributes` naming which Draco attribute (by unique id) each glTF
//! attribute is. The primitive's accessors keep their count, type and component type but point at no data; the
//! decoded values are written into a buffer of their own and those accessors are pointed at it, so everything
//! after reads them as any accessor (bounds-checked by gltf_accessors). The decoder is the pure-Rust
//! `draco-core` (Apache-2.0), which reads the sequential and Edgebreaker (standard and valence) bitstreams the
//! C++ Draco encoder writes, including older bitstream versions.
use anyhow::{anyhow, bail, Context as _, Result};
use draco_core::{DataType, DecoderBuffer, FaceIndex, Mesh, MeshDecoder, PointAttribute, PointIndex};
use gltf::accessor::DataType as ComponentType;
use serde_json::{json, Value};

pub const EXTENSION: &str = "KHR_draco_mesh_compression";

/// glTF's UNSIGNED_INT component type (glTF 2.0 §3.6.2.2), of the indices accessor a primitive without one gets.
const UNSIGNED_INT: u32 = 5125;

/// The file's JSON with every Draco-compressed primitive's accessors pointed at its decoded data, which is
/// appended to `buffers` as one new buffer; None when no primitive is compressed. `document` is the file parsed
/// (what is read), `json` its JSON text (a `.gltf` file, or a `.glb`'s JSON chunk: what is rewritten), `buffers`
/// its buffers, loaded.
pub fn decode_primitives(
    document: &gltf::Document,
    json: &[u8],
    buffers: &mut Vec<Vec<u8>>,
) -> Result<Option<Vec<u8>>> {
    let mut root: Value = serde_json::from_slice(json).context("not valid JSON")?;
    let mut out = DecodedData { data: Vec::new(), views: Vec::new(), buffer_index: buffers.len() };
    // The new views follow the file's own.
    let first_view = document.views().len();
    for mesh in document.meshes() {
        for primitive in mesh.primitives() {
            let Some(extension) = primitive.extension_value(EXTENSION) else { continue };
            let (m, p) = (mesh.index(), primitive.index());
            let decoded = decode(document, &primitive, extension, buffers)
                .with_context(|| format!("mesh {m} primitive {p}: {EXTENSION}"))?;
            for (accessor, bytes) in decoded.attributes {
                let view = first_view + out.add(bytes);
                point_at(&mut root, accessor, view)?;
            }
            let view = first_view + out.add(decoded.indices.bytes);
            match decoded.indices.accessor {
                Some(accessor) => point_at(&mut root, accessor, view)?,
                // Without an indices accessor the faces still say which points make triangles: give it one.
                None => {
                    let count = decoded.indices.count;
                    let accessor =
                        json!({ "componentType": UNSIGNED_INT, "count": count, "type": "SCALAR", "bufferView": view });
                    let accessors = array(&mut root, "accessors")?;
                    accessors.push(accessor);
                    let index = accessors.len() - 1;
                    root["meshes"][m]["primitives"][p]["indices"] = json!(index);
                }
            }
        }
    }
    if out.views.is_empty() {
        return Ok(None);
    }
    array(&mut root, "bufferViews")?.extend(out.views);
    array(&mut root, "buffers")?.push(json!({ "byteLength": out.data.len() }));
    buffers.push(out.data);
    Ok(Some(serde_json::to_vec(&root)?))
}

/// The new buffer's bytes and views.
struct DecodedData {
    data: Vec<u8>,
    views: Vec<Value>,
    buffer_index: usize,
}

impl DecodedData {
    /// Appends `bytes` as a view of its own (4-byte aligned, as glTF asks of every component type); returns its
    /// place among the new views.
    fn add(&mut self, bytes: Vec<u8>) -> usize {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        self.views
            .push(json!({ "buffer": self.buffer_index, "byteOffset": self.data.len(), "byteLength": bytes.len() }));
        self.data.extend(bytes);
        self.views.len() - 1
    }
}

/// The document's top-level array `name`, made if the file has none.
fn array<'a>(root: &'a mut Value, name: &str) -> Result<&'a mut Vec<Value>> {
    let object = root.as_object_mut().ok_or_else(|| anyhow!("the document is not a JSON object"))?;
    object.entry(name).or_insert_with(|| json!([])).as_array_mut().ok_or_else(|| anyhow!("{name} is not an array"))
}

/// Points accessor `index` at bufferView `view` from its start.
fn point_at(root: &mut Value, index: usize, view: usize) -> Result<()> {
    let accessor = root.pointer_mut(&format!("/accessors/{index}")).and_then(Value::as_object_mut);
    let accessor = accessor.ok_or_else(|| anyhow!("accessor {index} is not an object"))?;
    accessor.insert("bufferView".into(), json!(view));
    accessor.insert("byteOffset".into(), json!(0));
    accessor.remove("sparse");
    Ok(())
}

/// One primitive's decoded values: each compressed attribute's accessor and bytes, and its indices.
struct DecodedPrimitive {
    attributes: Vec<(usize, Vec<u8>)>,
    indices: DecodedIndices,
}

struct DecodedIndices {
    /// The primitive's indices accessor, if it has one (else the bytes are u32).
    accessor: Option<usize>,
    bytes: Vec<u8>,
    count: usize,
}

fn decode(
    document: &gltf::Document,
    primitive: &gltf::Primitive<'_>,
    extension: &Value,
    buffers: &[Vec<u8>],
) -> Result<DecodedPrimitive> {
    let view = extension.get("bufferView").and_then(Value::as_u64).ok_or_else(|| anyhow!("has no bufferView"))?;
    let view = document.views().nth(view as usize).ok_or_else(|| anyhow!("no bufferView {view}"))?;
    let (offset, length) = (view.offset(), view.length());
    let bytes = buffers
        .get(view.buffer().index())
        .and_then(|b| b.get(offset..offset.checked_add(length)?))
        .ok_or_else(|| anyhow!("bufferView {} ({length} bytes at {offset}) lies outside its buffer", view.index()))?;
    // A decoder bug met by malformed input becomes an error, not the end of the process.
    let decoded = std::panic::catch_unwind(|| {
        let mut mesh = Mesh::new();
        MeshDecoder::new().decode(&mut DecoderBuffer::new(bytes), &mut mesh).map(|()| mesh)
    });
    let mesh = match decoded {
        Ok(Ok(mesh)) => mesh,
        Ok(Err(e)) => bail!("bufferView {} is not a Draco mesh the decoder reads: {e}", view.index()),
        Err(_) => bail!("bufferView {} is not a Draco mesh the decoder reads (it failed on it)", view.index()),
    };
    let ids =
        extension.get("attributes").and_then(Value::as_object).ok_or_else(|| anyhow!("has no attributes object"))?;
    let mut attributes = Vec::new();
    for (semantic, id) in ids {
        let id = id.as_u64().and_then(|id| u32::try_from(id).ok()).ok_or_else(|| {
            anyhow!("attribute {semantic}: the Draco attribute id {id} is not a non-negative integer")
        })?;
        let (_, accessor) = primitive
            .attributes()
            .find(|(s, _)| s.to_string() == *semantic)
            .ok_or_else(|| anyhow!("names attribute {semantic}, which the primitive does not have"))?;
        let source = mesh
            .attribute_by_unique_id(id)
            .ok_or_else(|| anyhow!("attribute {semantic}: the Draco mesh has no attribute with id {id}"))?;
        let values = attribute_bytes(source, &mesh, &accessor).with_context(|| format!("attribute {semantic}"))?;
        attributes.push((accessor.index(), values));
    }
    let triangles: Vec<u32> = (0..mesh.num_faces()).flat_map(|f| mesh.face(FaceIndex(f as u32))).map(|p| p.0).collect();
    let count = triangles.len();
    let indices = match primitive.indices() {
        Some(accessor) => DecodedIndices {
            accessor: Some(accessor.index()),
            bytes: index_bytes(&triangles, &accessor).context("indices")?,
            count,
        },
        None => {
            DecodedIndices { accessor: None, bytes: triangles.iter().flat_map(|i| i.to_le_bytes()).collect(), count }
        }
    };
    Ok(DecodedPrimitive { attributes, indices })
}

/// The Draco data type a glTF component type is decoded from.
fn draco_type(component_type: ComponentType) -> DataType {
    match component_type {
        ComponentType::I8 => DataType::Int8,
        ComponentType::U8 => DataType::Uint8,
        ComponentType::I16 => DataType::Int16,
        ComponentType::U16 => DataType::Uint16,
        ComponentType::U32 => DataType::Uint32,
        ComponentType::F32 => DataType::Float32,
    }
}

/// A Draco attribute's value at each of the mesh's points, as the accessor's components.
fn attribute_bytes(source: &PointAttribute, mesh: &Mesh, accessor: &gltf::Accessor<'_>) -> Result<Vec<u8>> {
    let (index, component_type, count) = (accessor.index(), accessor.data_type(), accessor.count());
    let components = accessor.dimensions().multiplicity();
    if source.data_type() != draco_type(component_type) || usize::from(source.num_components()) != components {
        bail!(
            "the Draco attribute holds {} × {:?}, accessor {index} {components} × {component_type:?}",
            source.num_components(),
            source.data_type()
        );
    }
    if count != mesh.num_points() {
        bail!("accessor {index} counts {count} elements, the Draco mesh {} points", mesh.num_points());
    }
    let stride = components * component_type.size();
    let mut out = vec![0u8; count * stride];
    for (point, value) in out.chunks_exact_mut(stride).enumerate() {
        let at = source.mapped_index(PointIndex(point as u32)).0 as usize;
        if at >= source.size() || !source.buffer().try_read(at * stride, value) {
            bail!("point {point} maps to value {at}, past the attribute's {} values", source.size());
        }
    }
    Ok(out)
}

/// The faces' point indices in the accessor's component type.
fn index_bytes(indices: &[u32], accessor: &gltf::Accessor<'_>) -> Result<Vec<u8>> {
    let (index, component_type, count) = (accessor.index(), accessor.data_type(), accessor.count());
    let components = accessor.dimensions().multiplicity();
    if components != 1 || indices.len() != count {
        bail!("accessor {index} holds {count} × {components} values, the Draco mesh {} indices", indices.len());
    }
    let too_large = |i: u32| anyhow!("index {i} does not fit accessor {index}'s {component_type:?}");
    let mut out = Vec::with_capacity(indices.len() * 4);
    for &i in indices {
        match component_type {
            ComponentType::U8 => out.push(u8::try_from(i).map_err(|_| too_large(i))?),
            ComponentType::U16 => out.extend(u16::try_from(i).map_err(|_| too_large(i))?.to_le_bytes()),
            ComponentType::U32 => out.extend(i.to_le_bytes()),
            _ => bail!("accessor {index}: indices cannot be {component_type:?}"),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::gltf_import::{load_gltf_bytes, LoadOptions};
    use base64::Engine as _;
    use draco_core::{EncoderBuffer, EncoderOptions, GeometryAttributeType, MeshEncoder};

    const UNSIGNED_SHORT: u32 = 5123;
    const FLOAT: u32 = 5126;

    /// Positions, normals, texture coordinates and triangle indices.
    type Grid = (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[f32; 2]>, Vec<u16>);

    /// A 4×3 grid of points, bent so no two triangles are alike, with normals and texture coordinates.
    fn grid() -> Grid {
        let (w, h) = (4u16, 3u16);
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let (u, v) = (f32::from(x) / 3.0, f32::from(y) / 2.0);
                positions.push([u, v, 0.1 * u * u - 0.05 * v]);
                let n = glam::Vec3::new(-0.2 * u, 0.05, 1.0).normalize();
                normals.push(n.to_array());
                uvs.push([u, 1.0 - v * 0.7]);
            }
        }
        let mut indices = Vec::new();
        for y in 0..h - 1 {
            for x in 0..w - 1 {
                let i = y * w + x;
                indices.extend([i, i + 1, i + w, i + 1, i + w + 1, i + w]);
            }
        }
        (positions, normals, uvs, indices)
    }

    fn floats<const N: usize>(values: &[[f32; N]]) -> Vec<u8> {
        values.iter().flatten().flat_map(|f| f.to_le_bytes()).collect()
    }

    fn data_uri(bytes: &[u8]) -> String {
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
    }

    fn accessor(view: Option<usize>, component_type: u32, count: usize, kind: &str) -> Value {
        let mut a = json!({ "componentType": component_type, "count": count, "type": kind });
        if let Some(view) = view {
            a["bufferView"] = json!(view);
        }
        a
    }

    /// A glTF document of one primitive: the grid, uncompressed (None) or as the given Draco bytes.
    fn document(draco: Option<&[u8]>, with_indices: bool) -> Vec<u8> {
        let (positions, normals, uvs, indices) = grid();
        let n = positions.len();
        let mut accessors = vec![
            accessor(None, FLOAT, n, "VEC3"),
            accessor(None, FLOAT, n, "VEC3"),
            accessor(None, FLOAT, n, "VEC2"),
            accessor(None, UNSIGNED_SHORT, indices.len(), "SCALAR"),
        ];
        accessors[0]["min"] = json!([0.0, 0.0, -0.1]);
        accessors[0]["max"] = json!([1.0, 1.0, 0.1]);
        let (buffer, views) = match draco {
            Some(bytes) => (bytes.to_vec(), vec![json!({ "buffer": 0, "byteLength": bytes.len() })]),
            None => {
                let parts = [floats(&positions), floats(&normals), floats(&uvs), bytemuck_u16(&indices)];
                let mut buffer = Vec::new();
                let mut views = Vec::new();
                for (i, part) in parts.iter().enumerate() {
                    views.push(json!({ "buffer": 0, "byteOffset": buffer.len(), "byteLength": part.len() }));
                    accessors[i]["bufferView"] = json!(i);
                    buffer.extend(part);
                }
                (buffer, views)
            }
        };
        let mut primitive = json!({ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 } });
        if with_indices {
            primitive["indices"] = json!(3);
        } else {
            accessors.pop();
        }
        let mut root = json!({
            "asset": { "version": "2.0" },
            "scene": 0,
            "scenes": [{ "nodes": [0] }],
            "nodes": [{ "mesh": 0 }],
            "meshes": [{ "primitives": [primitive] }],
            "accessors": accessors,
            "bufferViews": views,
            "buffers": [{ "byteLength": buffer.len(), "uri": data_uri(&buffer) }],
        });
        if draco.is_some() {
            root["meshes"][0]["primitives"][0]["extensions"] = json!({
                EXTENSION: { "bufferView": 0, "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 } }
            });
            root["extensionsUsed"] = json!([EXTENSION]);
            root["extensionsRequired"] = json!([EXTENSION]);
        }
        serde_json::to_vec(&root).unwrap()
    }

    fn bytemuck_u16(values: &[u16]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    /// The grid as a Draco mesh, encoded sequentially (method 0, points in order) or by Edgebreaker (1), with no
    /// quantization: lossless.
    fn encoded(method: i32) -> Vec<u8> {
        let (positions, normals, uvs, indices) = grid();
        let mut mesh = Mesh::new();
        let mut add = |kind, components: u8, bytes: Vec<u8>| {
            let mut a = PointAttribute::new();
            a.init(kind, components, DataType::Float32, false, positions.len());
            a.buffer_mut().write(0, &bytes);
            mesh.add_attribute(a)
        };
        assert_eq!(add(GeometryAttributeType::Position, 3, floats(&positions)), 0);
        assert_eq!(add(GeometryAttributeType::Normal, 3, floats(&normals)), 1);
        assert_eq!(add(GeometryAttributeType::TexCoord, 2, floats(&uvs)), 2);
        mesh.set_num_faces(indices.len() / 3);
        mesh.set_faces_from_flat_indices(&indices.iter().map(|&i| u32::from(i)).collect::<Vec<_>>());
        let mut encoder = MeshEncoder::new();
        encoder.set_mesh(mesh);
        let mut options = EncoderOptions::new();
        options.set_global_int("encoding_method", method);
        let mut out = EncoderBuffer::new();
        encoder.encode(&options, &mut out).unwrap();
        out.data().to_vec()
    }

    fn load(json: &[u8]) -> Result<crate::scene::Scene> {
        load_gltf_bytes(json, std::path::Path::new("."), &LoadOptions::default())
    }

    /// Each triangle as its corners' bits (position, normal, uv), starting at its least corner so a rotation of
    /// its corners (which keeps its facing) compares equal; the triangles sorted.
    fn triangles(scene: &crate::scene::Scene) -> Vec<[[u32; 8]; 3]> {
        let p = &scene.meshes[0].primitives[0];
        let corner = |i: u32| {
            let i = i as usize;
            let [a, b, c] = p.positions[i].to_array();
            let [d, e, f] = p.normals[i].to_array();
            let [g, h] = p.uvs[i].to_array();
            [a, b, c, d, e, f, g, h].map(f32::to_bits)
        };
        let mut out: Vec<[[u32; 8]; 3]> = p
            .indices
            .chunks_exact(3)
            .map(|t| {
                let mut c = [corner(t[0]), corner(t[1]), corner(t[2])];
                let least = (0..3).min_by_key(|&k| c[k]).unwrap();
                c.rotate_left(least);
                c
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn a_draco_primitive_loads_as_its_uncompressed_twin() {
        let plain = load(&document(None, true)).unwrap();
        // Sequential coding keeps the points' order: the same vertices and indices, bit for bit.
        let sequential = load(&document(Some(&encoded(0)), true)).unwrap();
        let (a, b) = (&plain.meshes[0].primitives[0], &sequential.meshes[0].primitives[0]);
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.normals, b.normals);
        assert_eq!(a.uvs, b.uvs);
        assert_eq!(a.indices, b.indices);
        assert!(sequential.warnings.is_empty(), "{:?}", sequential.warnings);
        // Edgebreaker renumbers points and rotates corners: the same triangles, each facing the same way.
        let edgebreaker = load(&document(Some(&encoded(1)), true)).unwrap();
        assert_eq!(triangles(&plain), triangles(&edgebreaker));
        assert_eq!(plain.meshes[0].primitives[0].indices.len(), 36);
        // A primitive with no indices accessor gets one from the Draco faces.
        let no_indices = load(&document(Some(&encoded(1)), false)).unwrap();
        assert_eq!(triangles(&plain), triangles(&no_indices));
    }

    #[test]
    fn broken_draco_data_is_an_error_that_names_the_extension_and_the_primitive() {
        let mut bytes = encoded(1);
        bytes.truncate(bytes.len() / 2);
        let e = format!("{:#}", load(&document(Some(&bytes), true)).unwrap_err());
        assert!(e.contains("mesh 0 primitive 0: KHR_draco_mesh_compression"), "{e}");
        assert!(e.contains("not a Draco mesh"), "{e}");
        // An accessor whose count is not the Draco mesh's points.
        let mut root: Value = serde_json::from_slice(&document(Some(&encoded(0)), true)).unwrap();
        root["accessors"][2]["count"] = json!(5);
        let e = format!("{:#}", load(&serde_json::to_vec(&root).unwrap()).unwrap_err());
        assert!(e.contains("attribute TEXCOORD_0") && e.contains("counts 5 elements"), "{e}");
        // Every truncation and every flipped byte of a bitstream loads or is an error; none ends the process.
        let good = encoded(1);
        for i in 0..good.len() {
            let mut flipped = good.clone();
            flipped[i] ^= 0x5a;
            for bytes in [&good[..i], &flipped[..]] {
                if let Err(e) = load(&document(Some(bytes), true)) {
                    assert!(format!("{e:#}").contains(EXTENSION), "{e:#}");
                }
            }
        }
        // An attribute id the Draco mesh does not have.
        let mut root: Value = serde_json::from_slice(&document(Some(&encoded(0)), true)).unwrap();
        root["meshes"][0]["primitives"][0]["extensions"][EXTENSION]["attributes"]["NORMAL"] = json!(7);
        let e = format!("{:#}", load(&serde_json::to_vec(&root).unwrap()).unwrap_err());
        assert!(e.contains("no attribute with id 7"), "{e}");
    }
}
