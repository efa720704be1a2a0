//! `KHR_draco_mesh_compression`: a primitive whose attributes and indices are one Draco bitstream in a buffer view
//! (the extension's `bufferView`), its `attributes` naming which Draco attribute (by unique id) each glTF
//! attribute is. The primitive's accessors keep their count, type and component type but point at no data; the
//! decoded values are written into a buffer of their own and those accessors are pointed at it, so everything
//! after reads them as any accessor (bounds-checked by gltf_accessors). The decoder is the pure-Rust
//! `draco-core` (Apache-2.0), which reads the sequential and Edgebreaker (standard and valence) bitstreams the
//! C++ Draco encoder writes, including older bitstream versions.
use anyhow::{anyhow, bail, Context as _, Result};
use draco_core::{DataType, DecoderBuffer, FaceIndex, Mesh, MeshDecoder, PointAttribute, PointIndex};
use serde_json::{json, Value};

pub const EXTENSION: &str = "KHR_draco_mesh_compression";

/// glTF's accessor component types (glTF 2.0 §3.6.2.2).
const BYTE: u64 = 5120;
const UNSIGNED_BYTE: u64 = 5121;
const SHORT: u64 = 5122;
const UNSIGNED_SHORT: u64 = 5123;
const UNSIGNED_INT: u64 = 5125;
const FLOAT: u64 = 5126;

/// The file's JSON with every Draco-compressed primitive's accessors pointed at its decoded data, which is
/// appended to `buffers` as one new buffer; None when no primitive is compressed. `json` is the document's
/// JSON text (a `.gltf` file, or a `.glb`'s JSON chunk); `buffers` its buffers, loaded.
pub fn decode_primitives(json: &[u8], buffers: &mut Vec<Vec<u8>>) -> Result<Option<Vec<u8>>> {
    let mut root: Value = serde_json::from_slice(json).context("not valid JSON")?;
    let mut decoded = Vec::new();
    let mut new_views = Vec::new();
    let buffer_index = buffers.len();
    // The new views follow the file's own.
    let first_view = root.get("bufferViews").and_then(Value::as_array).map_or(0, Vec::len);
    let mesh_count = root.get("meshes").and_then(Value::as_array).map_or(0, Vec::len);
    for m in 0..mesh_count {
        let primitive_count = root["meshes"][m].get("primitives").and_then(Value::as_array).map_or(0, Vec::len);
        for p in 0..primitive_count {
            let Some(extension) = root["meshes"][m]["primitives"][p].pointer(&format!("/extensions/{EXTENSION}"))
            else {
                continue;
            };
            let extension = extension.clone();
            let mut out = DecodedPrimitive {
                root: &mut root,
                data: &mut decoded,
                views: &mut new_views,
                buffer_index,
                first_view,
            };
            out.decode(m, p, &extension, buffers).with_context(|| format!("mesh {m} primitive {p}: {EXTENSION}"))?;
        }
    }
    if new_views.is_empty() {
        return Ok(None);
    }
    let views = root.as_object_mut().ok_or_else(|| anyhow!("the document is not a JSON object"))?;
    let views = views.entry("bufferViews").or_insert_with(|| json!([]));
    views.as_array_mut().ok_or_else(|| anyhow!("bufferViews is not an array"))?.extend(new_views);
    let buffer = json!({ "byteLength": decoded.len() });
    root.as_object_mut()
        .expect("checked above")
        .entry("buffers")
        .or_insert_with(|| json!([]))
        .as_array_mut()
        .ok_or_else(|| anyhow!("buffers is not an array"))?
        .push(buffer);
    buffers.push(decoded);
    Ok(Some(serde_json::to_vec(&root)?))
}

/// Where one primitive's decoded values go: the new buffer's bytes and views, and the accessors (in `root`) that
/// read them.
struct DecodedPrimitive<'a> {
    root: &'a mut Value,
    data: &'a mut Vec<u8>,
    views: &'a mut Vec<Value>,
    buffer_index: usize,
    /// The document's index of the first new view.
    first_view: usize,
}

impl DecodedPrimitive<'_> {
    fn decode(&mut self, m: usize, p: usize, extension: &Value, buffers: &[Vec<u8>]) -> Result<()> {
        let view = extension.get("bufferView").and_then(Value::as_u64).ok_or_else(|| anyhow!("has no bufferView"))?;
        let bytes = self.view_bytes(view as usize, buffers)?;
        // A decoder bug met by malformed input becomes an error, not the end of the process.
        let decoded = std::panic::catch_unwind(|| {
            let mut mesh = Mesh::new();
            MeshDecoder::new().decode(&mut DecoderBuffer::new(bytes), &mut mesh).map(|()| mesh)
        });
        let mesh = match decoded {
            Ok(Ok(mesh)) => mesh,
            Ok(Err(e)) => bail!("bufferView {view} is not a Draco mesh the decoder reads: {e}"),
            Err(_) => bail!("bufferView {view} is not a Draco mesh the decoder reads (it failed on it)"),
        };
        let attributes = extension
            .get("attributes")
            .and_then(Value::as_object)
            .ok_or_else(|| anyhow!("has no attributes object"))?;
        let primitive = self.root["meshes"][m]["primitives"][p].clone();
        for (semantic, id) in attributes {
            let id = id.as_u64().and_then(|id| u32::try_from(id).ok()).ok_or_else(|| {
                anyhow!("attribute {semantic}: the Draco attribute id {id} is not a non-negative integer")
            })?;
            let accessor = primitive
                .pointer(&format!("/attributes/{semantic}"))
                .and_then(Value::as_u64)
                .ok_or_else(|| anyhow!("names attribute {semantic}, which the primitive does not have"))?;
            let source = mesh
                .attribute_by_unique_id(id)
                .ok_or_else(|| anyhow!("attribute {semantic}: the Draco mesh has no attribute with id {id}"))?;
            let values = attribute_bytes(source, &mesh, self.accessor(accessor)?)
                .with_context(|| format!("attribute {semantic}"))?;
            self.add(accessor, values)?;
        }
        let triangles = (0..mesh.num_faces()).flat_map(|f| mesh.face(FaceIndex(f as u32))).map(|p| p.0);
        match primitive.get("indices").and_then(Value::as_u64) {
            Some(accessor) => {
                let values = index_bytes(triangles, self.accessor(accessor)?).context("indices")?;
                self.add(accessor, values)
            }
            // Without an indices accessor the faces still say which points make triangles: give it one.
            None => {
                let indices: Vec<u32> = triangles.collect();
                let accessors = self.root.as_object_mut().expect("a document").entry("accessors");
                let accessors = accessors.or_insert_with(|| json!([])).as_array_mut();
                let accessors = accessors.ok_or_else(|| anyhow!("accessors is not an array"))?;
                accessors.push(json!({ "componentType": UNSIGNED_INT, "count": indices.len(), "type": "SCALAR" }));
                let accessor = accessors.len() as u64 - 1;
                self.root["meshes"][m]["primitives"][p]["indices"] = json!(accessor);
                self.add(accessor, indices.iter().flat_map(|i| i.to_le_bytes()).collect())
            }
        }
    }

    fn view_bytes<'b>(&self, view: usize, buffers: &'b [Vec<u8>]) -> Result<&'b [u8]> {
        let v = self.root.pointer(&format!("/bufferViews/{view}")).ok_or_else(|| anyhow!("no bufferView {view}"))?;
        let field = |name: &str| v.get(name).and_then(Value::as_u64).map(|n| n as usize);
        let buffer = field("buffer").ok_or_else(|| anyhow!("bufferView {view} names no buffer"))?;
        let (offset, length) = (field("byteOffset").unwrap_or(0), field("byteLength").unwrap_or(0));
        buffers
            .get(buffer)
            .and_then(|b| b.get(offset..offset.checked_add(length)?))
            .ok_or_else(|| anyhow!("bufferView {view} ({length} bytes at {offset}) lies outside buffer {buffer}"))
    }

    fn accessor(&self, index: u64) -> Result<AccessorFormat> {
        let a = self.root.pointer(&format!("/accessors/{index}")).ok_or_else(|| anyhow!("no accessor {index}"))?;
        let component_type = a.get("componentType").and_then(Value::as_u64).unwrap_or(0);
        let components = match a.get("type").and_then(Value::as_str).unwrap_or("") {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            other => bail!("accessor {index} has type {other:?}, which a Draco attribute cannot fill"),
        };
        let count = a.get("count").and_then(Value::as_u64).unwrap_or(0) as usize;
        Ok(AccessorFormat { index, component_type, components, count })
    }

    /// Appends `bytes` to the new buffer as a view of its own (4-byte aligned, as glTF asks of every component
    /// type) and marks accessor `index` to read it.
    fn add(&mut self, index: u64, bytes: Vec<u8>) -> Result<()> {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        self.views
            .push(json!({ "buffer": self.buffer_index, "byteOffset": self.data.len(), "byteLength": bytes.len() }));
        self.data.extend(bytes);
        let accessor = self.root.pointer_mut(&format!("/accessors/{index}")).and_then(Value::as_object_mut);
        let accessor = accessor.ok_or_else(|| anyhow!("accessor {index} is not an object"))?;
        accessor.insert("bufferView".into(), json!(self.first_view + self.views.len() - 1));
        accessor.insert("byteOffset".into(), json!(0));
        accessor.remove("sparse");
        Ok(())
    }
}

/// What an accessor the decoded values fill says they are.
struct AccessorFormat {
    index: u64,
    component_type: u64,
    components: usize,
    count: usize,
}

/// The Draco data type a glTF component type is decoded from, and its size in bytes.
fn draco_type(component_type: u64) -> Option<(DataType, usize)> {
    Some(match component_type {
        BYTE => (DataType::Int8, 1),
        UNSIGNED_BYTE => (DataType::Uint8, 1),
        SHORT => (DataType::Int16, 2),
        UNSIGNED_SHORT => (DataType::Uint16, 2),
        UNSIGNED_INT => (DataType::Uint32, 4),
        FLOAT => (DataType::Float32, 4),
        _ => return None,
    })
}

/// A Draco attribute's value at each of the mesh's points, as the accessor's components.
fn attribute_bytes(source: &PointAttribute, mesh: &Mesh, accessor: AccessorFormat) -> Result<Vec<u8>> {
    let AccessorFormat { index, component_type, components, count } = accessor;
    let (data_type, size) =
        draco_type(component_type).ok_or_else(|| anyhow!("accessor {index} has componentType {component_type}"))?;
    if source.data_type() != data_type || usize::from(source.num_components()) != components {
        bail!(
            "the Draco attribute holds {} × {:?}, accessor {index} {components} × componentType {component_type}",
            source.num_components(),
            source.data_type()
        );
    }
    if count != mesh.num_points() {
        bail!("accessor {index} counts {count} elements, the Draco mesh {} points", mesh.num_points());
    }
    let stride = components * size;
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
fn index_bytes(indices: impl Iterator<Item = u32>, accessor: AccessorFormat) -> Result<Vec<u8>> {
    let AccessorFormat { index, component_type, components, count } = accessor;
    let indices: Vec<u32> = indices.collect();
    if components != 1 || indices.len() != count {
        bail!("accessor {index} holds {count} × {components} values, the Draco mesh {} indices", indices.len());
    }
    let too_large = |i: u32| anyhow!("index {i} does not fit accessor {index}'s componentType {component_type}");
    let mut out = Vec::with_capacity(indices.len() * 4);
    for &i in &indices {
        match component_type {
            UNSIGNED_BYTE => out.push(u8::try_from(i).map_err(|_| too_large(i))?),
            UNSIGNED_SHORT => out.extend(u16::try_from(i).map_err(|_| too_large(i))?.to_le_bytes()),
            UNSIGNED_INT => out.extend(i.to_le_bytes()),
            _ => bail!("accessor {index}: indices cannot have componentType {component_type}"),
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

    fn accessor(view: Option<usize>, component_type: u64, count: usize, kind: &str) -> Value {
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
