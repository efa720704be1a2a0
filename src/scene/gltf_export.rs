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
    let mut bin: Vec<u8> = Vec::new();
    let mut views: Vec<Value> = Vec::new();
    let mut accessors: Vec<Value> = Vec::new();
    let mut push_view = |bin: &mut Vec<u8>, bytes: &[u8], target: u32| -> usize {
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target}));
        bin.extend_from_slice(bytes);
        views.len() - 1
    };
    let mut meshes = Vec::new();
    for mesh in &scene.meshes {
        let mut primitives = Vec::new();
        for p in &mesh.primitives {
            if p.positions.is_empty() || p.indices.is_empty() {
                bail!("mesh {}: empty primitive", mesh.name);
            }
            let mut attributes = serde_json::Map::new();
            let (lo, hi) =
                p.positions.iter().fold((glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN)), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
            let view = push_view(&mut bin, bytemuck::cast_slice(&p.positions), ARRAY_BUFFER);
            accessors.push(json!({"bufferView": view, "componentType": FLOAT, "count": p.positions.len(),
                "type": "VEC3", "min": lo.to_array(), "max": hi.to_array()}));
            attributes.insert("POSITION".into(), json!(accessors.len() - 1));
            if p.normals.len() == p.positions.len() {
                let view = push_view(&mut bin, bytemuck::cast_slice(&p.normals), ARRAY_BUFFER);
                accessors.push(
                    json!({"bufferView": view, "componentType": FLOAT, "count": p.normals.len(), "type": "VEC3"}),
                );
                attributes.insert("NORMAL".into(), json!(accessors.len() - 1));
            }
            if p.uvs.len() == p.positions.len() {
                let view = push_view(&mut bin, bytemuck::cast_slice(&p.uvs), ARRAY_BUFFER);
                accessors
                    .push(json!({"bufferView": view, "componentType": FLOAT, "count": p.uvs.len(), "type": "VEC2"}));
                attributes.insert("TEXCOORD_0".into(), json!(accessors.len() - 1));
            }
            let view = push_view(&mut bin, bytemuck::cast_slice(&p.indices), ELEMENT_ARRAY_BUFFER);
            accessors.push(
                json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": p.indices.len(), "type": "SCALAR"}),
            );
            let mut primitive = json!({"attributes": attributes, "indices": accessors.len() - 1, "mode": 4});
            if let Some(m) = p.material {
                primitive["material"] = json!(m);
            }
            primitives.push(primitive);
        }
        meshes.push(json!({"name": mesh.name, "primitives": primitives}));
    }
    let mut extensions_used: Vec<&str> = Vec::new();
    let mut materials: Vec<Value> = Vec::new();
    for m in &scene.materials {
        if m.base_color_texture.is_some() || m.normal_texture.is_some() || m.emissive_texture.is_some() {
            bail!("material {}: exporting textures is not supported", m.name);
        }
        let mut material = json!({"name": m.name, "pbrMetallicRoughness": {"baseColorFactor": m.base_color.to_array(),
            "metallicFactor": m.metallic, "roughnessFactor": m.roughness}});
        let mut extensions = serde_json::Map::new();
        if m.is_emissive() {
            // emissiveFactor is clamped to [0, 1]; the rest goes into KHR_materials_emissive_strength.
            let strength = m.emissive.max_element().max(1.0);
            material["emissiveFactor"] = json!((m.emissive / strength).to_array());
            if strength > 1.0 {
                extensions.insert("KHR_materials_emissive_strength".into(), json!({"emissiveStrength": strength}));
            }
        }
        if m.transmission > 0.0 {
            extensions.insert("KHR_materials_transmission".into(), json!({"transmissionFactor": m.transmission}));
        }
        if m.ior != 1.5 {
            extensions.insert("KHR_materials_ior".into(), json!({"ior": m.ior}));
        }
        if m.specular != 1.0 || m.specular_color != glam::Vec3::ONE {
            let mut specular = json!({"specularFactor": m.specular});
            if m.specular_color != glam::Vec3::ONE {
                specular["specularColorFactor"] = json!(m.specular_color.to_array());
            }
            extensions.insert("KHR_materials_specular".into(), specular);
        }
        if m.double_sided {
            material["doubleSided"] = json!(true);
        }
        for name in extensions.keys() {
            if !extensions_used.contains(&name.as_str()) {
                extensions_used.push(match name.as_str() {
                    "KHR_materials_emissive_strength" => "KHR_materials_emissive_strength",
                    "KHR_materials_transmission" => "KHR_materials_transmission",
                    "KHR_materials_specular" => "KHR_materials_specular",
                    _ => "KHR_materials_ior",
                });
            }
        }
        if !extensions.is_empty() {
            material["extensions"] = Value::Object(extensions);
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
        let projection = match camera.projection {
            Projection::Perspective { yfov, znear, zfar } => {
                let mut p = json!({"yfov": yfov, "znear": znear});
                if let Some(zfar) = zfar {
                    p["zfar"] = json!(zfar);
                }
                json!({"name": camera.name, "type": "perspective", "perspective": p})
            }
            Projection::Orthographic { xmag, ymag, znear, zfar } => json!({"name": camera.name, "type": "orthographic",
                "orthographic": {"xmag": xmag, "ymag": ymag, "znear": znear, "zfar": zfar}}),
        };
        cameras.push(projection);
        nodes.push(json!({"name": camera.name, "camera": 0, "matrix": camera.world_from_camera.to_cols_array()}));
    }
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

/// Writes `scene` to `path` (`.gltf`) and its buffer beside it (`.bin`), each atomically.
pub fn write_gltf(scene: &Scene, path: &Path) -> Result<()> {
    let stem = path.file_stem().and_then(|s| s.to_str()).context("glTF path has no file name")?;
    let bin_name = format!("{stem}.bin");
    let (json, bin) = to_gltf(scene, &bin_name)?;
    let bin_path = path.with_file_name(&bin_name);
    crate::output::write_atomic(&bin_path, |f| std::io::Write::write_all(f, &bin).map_err(Into::into))?;
    crate::output::write_atomic(path, |f| std::io::Write::write_all(f, json.as_bytes()).map_err(Into::into))
}
