//! glTF features the shared samples do not exercise, on small files written here: a GLB with a binary chunk,
//! sparse accessors, normalized integer attributes, the KHR extensions strata implements, alpha modes, morph
//! targets at the mesh's and nodes' weights, and the warnings for an optional extension and skins it does not.
mod common;
use common::cli::temp_dir;
use glam::{Vec2, Vec3, Vec4};
use serde_json::{json, Value};
use strata::scene::{AlphaMode, LightShape};

fn bytes_f32(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// Binary data: 3 positions (36 B), 3 u8-normalized UVs padded (8 B), 3 u16-normalized RGBA colours (24 B),
/// one sparse index (u8, padded to 4) and one sparse VEC3 value (12 B).
fn buffer() -> Vec<u8> {
    let mut b = bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    b.extend([0u8, 0, 255, 0, 0, 255, 0, 0]); // uv: (0,0) (1,0) (0,1), then padding
    for c in [[65535u16, 0, 0, 65535], [0, 65535, 0, 65535], [0, 0, 32768, 65535]] {
        b.extend(c.iter().flat_map(|v| v.to_le_bytes()));
    }
    b.extend([1u8, 0, 0, 0]); // sparse index 1
    b.extend(bytes_f32(&[2.0, 0.0, 0.0])); // vertex 1 becomes (2, 0, 0)
    b
}

fn document(buffer_entry: Value) -> Value {
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_texture_transform", "KHR_lights_punctual", "KHR_materials_emissive_strength",
                           "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_specular",
                           "EXT_made_up_extension"],
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"translation": [0, 3, 0],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "color": [1, 0.5, 0.25], "intensity": 4, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
        ]}},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1, "COLOR_0": 2}, "material": 0}]}],
        "materials": [{
            "name": "lit glass",
            "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": true,
            "emissiveFactor": [1, 0.5, 0],
            "extensions": {
                "KHR_materials_emissive_strength": {"emissiveStrength": 6},
                "KHR_materials_transmission": {"transmissionFactor": 0.8, "transmissionTexture": {"index": 0,
                    "extensions": {"KHR_texture_transform": {"scale": [3, 1]}}}},
                "KHR_materials_ior": {"ior": 1.33},
                "KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1, 0.8, 0.6],
                    "specularTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.25, 0]}}},
                    "specularColorTexture": {"index": 1, "texCoord": 1,
                        "extensions": {"KHR_texture_transform": {"scale": [0.5, 0.5]}}}}
            },
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 2], "rotation": 0}}}},
            "normalTexture": {"index": 0, "scale": 0.5, "texCoord": 1,
                "extensions": {"KHR_texture_transform": {"offset": [0, 0.25], "rotation": 1.5707964}}},
            "emissiveTexture": {"index": 0, "texCoord": 1}
        }],
        "textures": [{"source": 0, "sampler": 0}, {"source": 0}],
        "samplers": [{"wrapS": 33071, "wrapT": 33648, "magFilter": 9728, "minFilter": 9729}],
        "images": [{"uri": png_data_uri()}],
        "buffers": [buffer_entry],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 8},
            {"buffer": 0, "byteOffset": 44, "byteLength": 24},
            {"buffer": 0, "byteOffset": 68, "byteLength": 4},
            {"buffer": 0, "byteOffset": 72, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [2, 1, 0],
             "sparse": {"count": 1, "indices": {"bufferView": 3, "componentType": 5121},
                        "values": {"bufferView": 4}}},
            {"bufferView": 1, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC4"}
        ]
    })
}

fn png_data_uri() -> String {
    use base64::Engine as _;
    let mut png = Vec::new();
    let pixels = [255u8, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255];
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &pixels,
        2,
        2,
        image::ExtendedColorType::Rgba8,
    )
    .unwrap();
    format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(png))
}

fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + text.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn check(scene: &strata::scene::Scene) {
    let p = &scene.meshes[0].primitives[0];
    // Sparse: vertex 1 moved from (1, 0, 0) to (2, 0, 0); the others keep their base values.
    assert_eq!(p.positions, vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::Y]);
    // Normalized integers become [0, 1] floats.
    assert_eq!(p.uvs, vec![Vec2::ZERO, Vec2::X, Vec2::Y]);
    assert_eq!(p.colors[0], Vec4::new(1.0, 0.0, 0.0, 1.0));
    assert!((p.colors[2].z - 32768.0 / 65535.0).abs() < 1e-6);
    // Q_u, Q_v of the sparse-modified triangle: P = (2u, v, 0).
    assert!((p.dpdu[0] - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6 && (p.dpdv[0] - Vec3::Y).length() < 1e-6);

    let m = &scene.materials[0];
    assert_eq!(m.alpha_mode, AlphaMode::Mask { cutoff: 0.3 });
    assert!(m.double_sided);
    assert_eq!(m.emissive, Vec3::new(6.0, 3.0, 0.0), "emissiveFactor × emissiveStrength");
    assert_eq!((m.transmission, m.ior), (0.8, 1.33));
    let t = m.base_color_texture.unwrap().transform.unwrap();
    assert_eq!(t.apply(Vec2::new(0.25, 0.25)), Vec2::new(1.0, 0.5), "scale 2 then offset (0.5, 0)");
    // The normal texture's transform comes from its raw extension object (the gltf crate reads textureInfo's only):
    // rotate a quarter turn, then offset.
    let n = m.normal_texture.unwrap().transform.unwrap();
    assert!((n.apply(Vec2::X) - Vec2::new(0.0, -0.75)).length() < 1e-6, "{:?}", n.apply(Vec2::X));
    // TEXCOORD_1 is read for every texture but the normal one (its tangent frame follows TEXCOORD_0): only that
    // one is warned about.
    assert_eq!((m.emissive_texture.unwrap().tex_coord, m.normal_texture.unwrap().tex_coord), (1, 1));
    let transmission = m.transmission_texture.unwrap().transform.unwrap();
    assert_eq!(transmission.apply(Vec2::new(0.5, 0.5)), Vec2::new(1.5, 0.5));
    assert_eq!((m.specular, m.specular_color), (0.5, Vec3::new(1.0, 0.8, 0.6)));
    let specular = m.specular_texture.unwrap().transform.unwrap();
    assert_eq!(specular.apply(Vec2::new(0.5, 0.5)), Vec2::new(0.75, 0.5));
    // The specular colour texture holds sRGB colour, like base colour and emission (KHR_materials_specular).
    let specular_color = m.specular_color_texture.unwrap();
    assert_eq!((specular_color.texture, specular_color.tex_coord), (1, 1));
    assert_eq!(specular_color.transform.unwrap().apply(Vec2::new(0.5, 0.5)), Vec2::new(0.25, 0.25));
    assert!(scene.textures[1].srgb, "a texture used only as specular colour is sRGB");
    let sampler = scene.textures[0].sampler;
    assert_eq!(
        (sampler.wrap_s, sampler.wrap_t),
        (strata::scene::Wrap::ClampToEdge, strata::scene::Wrap::MirroredRepeat)
    );
    assert!(!sampler.mag_linear && sampler.min_linear && sampler.mipmaps == strata::scene::MipFilter::None);
    assert!(scene.textures[0].srgb);
    assert_eq!((scene.images[0].width, scene.images[0].height), (2, 2));

    assert_eq!(scene.lights.len(), 1);
    let light = &scene.lights[0];
    assert_eq!(light.shape, LightShape::Spot { inner_cone: 0.2, outer_cone: 0.5, radius: 0.0 });
    assert_eq!(light.emission, Vec3::new(4.0, 2.0, 1.0));
    assert_eq!(light.world_from_light.w_axis.truncate(), Vec3::new(0.0, 3.0, 0.0));
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
    assert!(scene.warnings[0].contains("EXT_made_up_extension"));
    assert!(scene.warnings[1].contains("\"lit glass\": its normal texture uses TEXCOORD_1"), "{:?}", scene.warnings[1]);
}

/// A normal texture's transform that is not a KHR_texture_transform object fails with the material's name.
#[test]
fn a_malformed_normal_texture_transform_names_its_material() {
    let dir = temp_dir("bad-transform");
    let bin = buffer();
    std::fs::write(dir.join("data.bin"), &bin).unwrap();
    let mut doc = document(json!({"byteLength": bin.len(), "uri": "data.bin"}));
    doc["materials"][0]["normalTexture"]["extensions"]["KHR_texture_transform"]["offset"] = json!("left");
    let path = dir.join("bad.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let error = format!("{:#}", strata::load_scene(&path).unwrap_err());
    assert!(error.contains("lit glass") && error.contains("KHR_texture_transform"), "{error}");
}

#[test]
fn glb_with_a_binary_chunk_and_every_feature() {
    let bin = buffer();
    let doc = document(json!({"byteLength": bin.len()}));
    let path = temp_dir("glb").join("features.glb");
    std::fs::write(&path, glb(&doc, &bin)).unwrap();
    check(&strata::load_scene(&path).unwrap());
}

#[test]
fn gltf_with_an_external_buffer_and_every_feature() {
    let dir = temp_dir("external");
    let bin = buffer();
    std::fs::write(dir.join("data with space.bin"), &bin).unwrap();
    let doc = document(json!({"byteLength": bin.len(), "uri": "data%20with%20space.bin"}));
    let path = dir.join("features.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    check(&strata::load_scene(&path).unwrap());
}

/// A triangle with one morph target (vertex 2 moves by +z, every normal tilts by +x), at the mesh's default
/// weight 0.5 on node 0, at weight 1 on node 1 and at 0.5 again on node 2; node 3 is skinned.
fn morphed_triangles() -> (Value, Vec<u8>) {
    let mut bin = bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // positions
    bin.extend(bytes_f32(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0])); // normals
    bin.extend(bytes_f32(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])); // target POSITION
    bin.extend(bytes_f32(&[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0])); // target NORMAL
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [{"mesh": 0}, {"mesh": 0, "weights": [1.0]}, {"mesh": 0, "weights": [0.5]},
                  {"mesh": 0, "skin": 0}],
        "skins": [{"joints": [0]}],
        "meshes": [{"weights": [0.5], "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1},
                                                      "targets": [{"POSITION": 2, "NORMAL": 3}]}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": (0..4).map(|i| json!({"buffer": 0, "byteOffset": 36 * i, "byteLength": 36})).collect::<Vec<_>>(),
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 1]},
            {"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC3"}
        ]
    });
    (doc, bin)
}

/// Morph targets apply at the mesh's default weights, or at a node's own (glTF 2.0 §3.7.2.2), nodes with the same
/// weights sharing one mesh; a skinned node gets a warning.
#[test]
fn morph_targets_apply_at_the_mesh_or_node_weights() {
    let (doc, bin) = morphed_triangles();
    let path = temp_dir("morph").join("morph.glb");
    std::fs::write(&path, glb(&doc, &bin)).unwrap();
    let scene = strata::load_scene(&path).unwrap();
    let mesh_of = |node: usize| scene.nodes[node].mesh.expect("a mesh");
    assert_eq!(mesh_of(0), 0);
    assert_eq!(mesh_of(2), 0, "weights equal to the mesh's share its mesh");
    assert_eq!(mesh_of(3), 0);
    assert_ne!(mesh_of(1), 0, "node 1's own weights need a mesh of their own");
    assert_eq!(scene.meshes.len(), 2);
    assert_eq!(scene.instances.len(), 4);
    let half = &scene.meshes[0].primitives[0];
    assert_eq!(half.positions, vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, 0.5)]);
    let tilted = Vec3::new(0.5, 0.0, 1.0).normalize();
    assert!(half.normals.iter().all(|n| n.abs_diff_eq(tilted, 1e-6)), "{:?}", half.normals);
    let full = &scene.meshes[mesh_of(1)].primitives[0];
    assert_eq!(full.positions, vec![Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, 1.0)]);
    assert!(full.normals.iter().all(|n| n.abs_diff_eq(Vec3::new(1.0, 0.0, 1.0).normalize(), 1e-6)));
    assert!(scene.warnings.iter().any(|w| w.contains("node 3 is skinned")), "{:?}", scene.warnings);
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
}

/// A morph target whose accessor has the wrong count fails with the mesh, the primitive and the target named.
#[test]
fn a_morph_target_of_the_wrong_length_is_an_error() {
    let (mut doc, bin) = morphed_triangles();
    doc["accessors"][2]["count"] = json!(2);
    let path = temp_dir("bad-morph").join("morph.glb");
    std::fs::write(&path, glb(&doc, &bin)).unwrap();
    let error = format!("{:#}", strata::load_scene(&path).unwrap_err());
    assert!(error.contains("mesh 0") && error.contains("morph target 0 POSITION"), "{error}");
}

/// Kenney's models (and other exporters) list a child among the scene's root nodes, against glTF 2.0 §3.5.2; every
/// viewer draws them. strata warns and keeps the hierarchy: the child is drawn once, where its parent puts it.
#[test]
fn a_child_listed_as_a_scene_root_is_drawn_once_as_a_child_with_a_warning() {
    let bin = buffer();
    let mut doc = document(json!({"byteLength": bin.len()}));
    // Node 2 holds node 0 (the mesh), moved up by 5; the scene lists both.
    doc["nodes"].as_array_mut().unwrap().push(json!({"name": "holder", "translation": [0, 5, 0], "children": [0]}));
    doc["scenes"] = json!([{"nodes": [2, 0, 1]}]);
    let path = temp_dir("listed-child").join("listed.glb");
    std::fs::write(&path, glb(&doc, &bin)).unwrap();
    let scene = strata::load_scene(&path).unwrap();
    assert_eq!(scene.instances.len(), 1, "the mesh is drawn once");
    assert_eq!(scene.instances[0].world_from_object.w_axis.y, 5.0, "as a child of its holder");
    assert_eq!(scene.roots, vec![2, 1]);
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("scene node 0") && w.contains("child of node 2") && w.contains("§3.5.2")),
        "{:?}",
        scene.warnings
    );
}

/// KHR_materials_unlit is read (no "not supported" warning), and written back by the exporter.
#[test]
fn unlit_materials_are_read_and_written() {
    let dir = temp_dir("unlit");
    let bin = buffer();
    std::fs::write(dir.join("data.bin"), &bin).unwrap();
    let mut doc = document(json!({"byteLength": bin.len(), "uri": "data.bin"}));
    doc["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_materials_unlit"));
    doc["materials"][0]["extensions"]["KHR_materials_unlit"] = json!({});
    let path = dir.join("unlit.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = strata::load_scene(&path).unwrap();
    assert!(scene.materials[0].unlit, "the material is unlit");
    assert!(!scene.warnings.iter().any(|w| w.contains("unlit")), "{:?}", scene.warnings);

    let mut library = strata::scene::library::cornell();
    library.materials[0].unlit = true;
    let exported = dir.join("cornell-unlit.gltf");
    strata::scene::gltf_export::write_gltf(&library, &exported).unwrap();
    let back = strata::load_scene(&exported).unwrap();
    assert!(back.materials[0].unlit && !back.materials[1].unlit, "the exporter writes KHR_materials_unlit");
}
