//! Writes a [`Scene`] as glTF 2.0: a `.gltf` JSON file and one `.bin` buffer beside it. Output is deterministic
//! (same scene, same bytes), which lets a test check that committed scenes match their generator.
use super::{Projection, Scene};
use anyhow::{bail, Context as _, Result};
use serde_json::{json, Value};
use std::path::Path;

const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The glTF JSON and the binary buffer for `scene`; the JSON names the buffer `bin_name`.
pub fn to_gltf(scene: &Scene, bin_name: &str) -> Result<(String, Vec<u8>)> {
    let mut buffer = BinaryBuffer::default();
    let meshes = scene.meshes.iter().map(|mesh| mesh_json(&mut buffer, mesh)).collect::<Result<Vec<_>>>()?;
    let mut extensions_used: Vec<&str> = Vec::new();
    let mut materials: Vec<Value> = Vec::new();
    for m in &scene.materials {
        let (material, extensions) = material_json(m)?;
        for name in extensions {
            if !extensions_used.contains(&name) {
                extensions_used.push(name);
            }
        }
        materials.push(material);
    }
    extensions_used.sort_unstable();
    let mut nodes: Vec<Value> = scene
        .instances
        .iter()
        .map(|i| {
            let mut node = json!({"name": i.name, "mesh": i.mesh});
            if i.world_from_object != glam::Mat4::IDENTITY {
                node["matrix"] = json!(i.world_from_object.to_cols_array());
            }
            node
        })
        .collect();
    let mut cameras = Vec::new();
    if let Some(camera) = &scene.camera {
        cameras.push(camera_json(camera));
        nodes.push(json!({"name": camera.name, "camera": 0, "matrix": camera.world_from_camera.to_cols_array()}));
    }
    let BinaryBuffer { bin, views, accessors } = buffer;
    let mut root = json!({
        "asset": {"version": "2.0", "generator": "strata scene library"},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": bin_name, "byteLength": bin.len()}],
    });
    if !cameras.is_empty() {
        root["cameras"] = json!(cameras);
    }
    if !extensions_used.is_empty() {
        root["extensionsUsed"] = json!(extensions_used);
    }
    let mut text = serde_json::to_string_pretty(&root).context("serializing glTF JSON")?;
    text.push('\n');
    Ok((text, bin))
}

/// The one binary buffer, its views and the accessors that read them, as they grow.
#[derive(Default)]
struct BinaryBuffer {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl BinaryBuffer {
    /// Appends `bytes` as a view (4-byte aligned) and an accessor of it: `accessor` holds the accessor's other
    /// fields. Returns the accessor's index.
    fn accessor(&mut self, bytes: &[u8], target: u32, mut accessor: Value) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let view = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len(), "target": target});
        self.views.push(view);
        self.bin.extend_from_slice(bytes);
        accessor["bufferView"] = json!(self.views.len() - 1);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }
}

/// A mesh's JSON, its vertex and index data appended to `buffer`.
fn mesh_json(buffer: &mut BinaryBuffer, mesh: &super::Mesh) -> Result<Value> {
    let mut primitives = Vec::new();
    for p in &mesh.primitives {
        if p.positions.is_empty() || p.indices.is_empty() {
            bail!("mesh {}: empty primitive", mesh.name);
        }
        let mut attributes = serde_json::Map::new();
        let (lo, hi) = p
            .positions
            .iter()
            .fold((glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let positions = buffer.accessor(
            bytemuck::cast_slice(&p.positions),
            ARRAY_BUFFER,
            json!({"componentType": FLOAT, "count": p.positions.len(), "type": "VEC3", "min": lo.to_array(),
                "max": hi.to_array()}),
        );
        attributes.insert("POSITION".into(), json!(positions));
        if p.normals.len() == p.positions.len() {
            let fields = json!({"componentType": FLOAT, "count": p.normals.len(), "type": "VEC3"});
            let normals = buffer.accessor(bytemuck::cast_slice(&p.normals), ARRAY_BUFFER, fields);
            attributes.insert("NORMAL".into(), json!(normals));
        }
        if p.uvs.len() == p.positions.len() {
            let fields = json!({"componentType": FLOAT, "count": p.uvs.len(), "type": "VEC2"});
            let uvs = buffer.accessor(bytemuck::cast_slice(&p.uvs), ARRAY_BUFFER, fields);
            attributes.insert("TEXCOORD_0".into(), json!(uvs));
        }
        let fields = json!({"componentType": UNSIGNED_INT, "count": p.indices.len(), "type": "SCALAR"});
        let indices = buffer.accessor(bytemuck::cast_slice(&p.indices), ELEMENT_ARRAY_BUFFER, fields);
        let mut primitive = json!({"attributes": attributes, "indices": indices, "mode": 4});
        if let Some(m) = p.material {
            primitive["material"] = json!(m);
        }
        primitives.push(primitive);
    }
    Ok(json!({"name": mesh.name, "primitives": primitives}))
}

/// A material's JSON and the extensions it uses.
fn material_json(m: &super::Material) -> Result<(Value, Vec<&'static str>)> {
    if m.base_color_texture.is_some() || m.normal_texture.is_some() || m.emissive_texture.is_some() {
        bail!("material {}: exporting textures is not supported", m.name);
    }
    let mut material = json!({"name": m.name, "pbrMetallicRoughness": {"baseColorFactor": m.base_color.to_array(),
        "metallicFactor": m.metallic, "roughnessFactor": m.roughness}});
    let mut extensions = serde_json::Map::new();
    let mut used = Vec::new();
    if m.is_emissive() {
        // emissiveFactor is clamped to [0, 1]; the rest goes into KHR_materials_emissive_strength.
        let strength = m.emissive.max_element().max(1.0);
        material["emissiveFactor"] = json!((m.emissive / strength).to_array());
        if strength > 1.0 {
            extensions.insert("KHR_materials_emissive_strength".into(), json!({"emissiveStrength": strength}));
            used.push("KHR_materials_emissive_strength");
        }
    }
    if m.transmission > 0.0 {
        extensions.insert("KHR_materials_transmission".into(), json!({"transmissionFactor": m.transmission}));
        used.push("KHR_materials_transmission");
    }
    if m.ior != 1.5 {
        extensions.insert("KHR_materials_ior".into(), json!({"ior": m.ior}));
        used.push("KHR_materials_ior");
    }
    if m.specular != 1.0 || m.specular_color != glam::Vec3::ONE {
        let mut specular = json!({"specularFactor": m.specular});
        if m.specular_color != glam::Vec3::ONE {
            specular["specularColorFactor"] = json!(m.specular_color.to_array());
        }
        extensions.insert("KHR_materials_specular".into(), specular);
        used.push("KHR_materials_specular");
    }
    if let Some(c) = m.clearcoat {
        if c.texture.is_some() || c.roughness_texture.is_some() || c.normal_texture.is_some() {
            bail!("material {}: exporting textures is not supported", m.name);
        }
        let coat = json!({"clearcoatFactor": c.factor, "clearcoatRoughnessFactor": c.roughness});
        extensions.insert("KHR_materials_clearcoat".into(), coat);
        used.push("KHR_materials_clearcoat");
    }
    if let Some(sheen) = m.sheen {
        if sheen.color_texture.is_some() || sheen.roughness_texture.is_some() {
            bail!("material {}: exporting textures is not supported", m.name);
        }
        let layer = json!({"sheenColorFactor": sheen.color.to_array(), "sheenRoughnessFactor": sheen.roughness});
        extensions.insert("KHR_materials_sheen".into(), layer);
        used.push("KHR_materials_sheen");
    }
    if let Some(a) = m.anisotropy {
        if a.texture.is_some() {
            bail!("material {}: exporting textures is not supported", m.name);
        }
        let lobe = json!({"anisotropyStrength": a.strength, "anisotropyRotation": a.rotation});
        extensions.insert("KHR_materials_anisotropy".into(), lobe);
        used.push("KHR_materials_anisotropy");
    }
    if let Some(i) = m.iridescence {
        if i.texture.is_some() || i.thickness_texture.is_some() {
            bail!("material {}: exporting textures is not supported", m.name);
        }
        let film = json!({"iridescenceFactor": i.factor, "iridescenceIor": i.ior,
            "iridescenceThicknessMinimum": i.thickness_min, "iridescenceThicknessMaximum": i.thickness_max});
        extensions.insert("KHR_materials_iridescence".into(), film);
        used.push("KHR_materials_iridescence");
    }
    if let Some(d) = m.diffuse_transmission {
        if d.texture.is_some() || d.color_texture.is_some() {
            bail!("material {}: exporting textures is not supported", m.name);
        }
        let lobe = json!({"diffuseTransmissionFactor": d.factor, "diffuseTransmissionColorFactor": d.color.to_array()});
        extensions.insert("KHR_materials_diffuse_transmission".into(), lobe);
        used.push("KHR_materials_diffuse_transmission");
    }
    if m.double_sided {
        material["doubleSided"] = json!(true);
    }
    if m.unlit {
        extensions.insert("KHR_materials_unlit".into(), json!({}));
        used.push("KHR_materials_unlit");
    }
    if !extensions.is_empty() {
        material["extensions"] = Value::Object(extensions);
    }
    Ok((material, used))
}

/// A camera's JSON (glTF 2.0 §5.12).
fn camera_json(camera: &super::Camera) -> Value {
    match camera.projection {
        Projection::Perspective { yfov, znear, zfar } => {
            let mut p = json!({"yfov": yfov, "znear": znear});
            if let Some(zfar) = zfar {
                p["zfar"] = json!(zfar);
            }
            json!({"name": camera.name, "type": "perspective", "perspective": p})
        }
        Projection::Orthographic { xmag, ymag, znear, zfar } => json!({"name": camera.name, "type": "orthographic",
            "orthographic": {"xmag": xmag, "ymag": ymag, "znear": znear, "zfar": zfar}}),
    }
}

/// Writes `scene` to `path` (`.gltf`) and its buffer beside it (`.bin`), each atomically.
pub fn write_gltf(scene: &Scene, path: &Path) -> Result<()> {
    let stem = path.file_stem().and_then(|s| s.to_str()).context("glTF path has no file name")?;
    let bin_name = format!("{stem}.bin");
    let (json, bin) = to_gltf(scene, &bin_name)?;
    let bin_path = path.with_file_name(&bin_name);
    crate::output::write_atomic(&bin_path, |f| std::io::Write::write_all(f, &bin).map_err(Into::into))?;
    crate::output::write_atomic(path, |f| std::io::Write::write_all(f, json.as_bytes()).map_err(Into::into))
}
