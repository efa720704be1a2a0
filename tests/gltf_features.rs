//! glTF features the shared samples do not exercise, on small files written here: a GLB with a binary chunk,
//! sparse accessors, normalized integer attributes, the KHR extensions strata implements, alpha modes, morph
//! targets at the mesh's and nodes' weights, the warning for an optional extension it does not read, and the error for a skin without joint data.
use crate::common;
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
                           "KHR_materials_volume", "KHR_materials_dispersion", "EXT_made_up_extension"],
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
                "KHR_materials_dispersion": {"dispersion": 0.5},
                "KHR_materials_volume": {"thicknessFactor": 0.1, "attenuationDistance": 2.0,
                    "attenuationColor": [0.5, 1.0, 0.25]},
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
    // KHR_materials_volume: σ = −ln(colour) / distance.
    assert_eq!((m.attenuation_color, m.attenuation_distance), (Vec3::new(0.5, 1.0, 0.25), 2.0));
    // KHR_materials_dispersion: 20 / V_d, read as it is (no warning below names it).
    assert_eq!(m.dispersion, 0.5);
    assert!(m.disperses() && scene.disperses(), "transmissive and dispersive");
    let sigma = m.absorption();
    assert!((sigma - Vec3::new(2f32.ln() / 2.0, 0.0, 4f32.ln() / 2.0)).abs().max_element() < 1e-6, "{sigma}");
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

/// A dispersion that is not a number at least 0 fails with the material's name and the extension's.
#[test]
fn a_dispersion_below_zero_or_not_a_number_names_its_material() {
    let dir = temp_dir("bad-dispersion");
    let bin = buffer();
    std::fs::write(dir.join("data.bin"), &bin).unwrap();
    for (value, says) in [(json!(-0.5), "at least 0"), (json!("strong"), "not a number")] {
        let mut doc = document(json!({"byteLength": bin.len(), "uri": "data.bin"}));
        doc["materials"][0]["extensions"]["KHR_materials_dispersion"]["dispersion"] = value;
        let path = dir.join("bad.gltf");
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        let error = format!("{:#}", strata::load_scene(&path).unwrap_err());
        assert!(
            error.contains("lit glass") && error.contains("KHR_materials_dispersion") && error.contains(says),
            "{error}"
        );
    }
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
/// weights sharing one mesh. Node 3's skin is refused while its mesh has no JOINTS_0/WEIGHTS_0 (§3.7.3.1).
#[test]
fn morph_targets_apply_at_the_mesh_or_node_weights() {
    let (mut doc, bin) = morphed_triangles();
    let path = temp_dir("morph").join("morph.glb");
    std::fs::write(&path, glb(&doc, &bin)).unwrap();
    let err = format!("{:#}", strata::load_scene(&path).unwrap_err());
    assert!(err.contains("node \"node 3\"") && err.contains("needs JOINTS_0 and WEIGHTS_0"), "{err}");
    doc["nodes"][3].as_object_mut().unwrap().remove("skin");
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
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
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

/// Vertex data and the accessors over it, each attribute in its own strided view (elements on 4-byte
/// boundaries, as glTF 2.0 §3.6.2.4 and KHR_mesh_quantization ask).
#[derive(Default)]
struct VertexData {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

/// One quantized component type: glTF's code, its bytes, and how a component is written.
#[derive(Clone, Copy)]
struct Quantized {
    code: u32,
    size: usize,
    normalized: bool,
}

const I8_NORM: Quantized = Quantized { code: 5120, size: 1, normalized: true };
const I8: Quantized = Quantized { code: 5120, size: 1, normalized: false };
const U8: Quantized = Quantized { code: 5121, size: 1, normalized: false };
const I16_NORM: Quantized = Quantized { code: 5122, size: 2, normalized: true };
const U16_NORM: Quantized = Quantized { code: 5123, size: 2, normalized: true };
const U16: Quantized = Quantized { code: 5123, size: 2, normalized: false };

impl Quantized {
    /// The float glTF's table makes of component `c` (glTF 2.0 §3.11; KHR_mesh_quantization).
    fn float(self, c: i32) -> f32 {
        let max = match (self.code, self.size) {
            (5120, _) => 127.0,
            (5121, _) => 255.0,
            (5122, _) => 32767.0,
            _ => 65535.0,
        };
        if self.normalized {
            (c as f32 / max).max(-1.0)
        } else {
            c as f32
        }
    }
}

impl VertexData {
    /// Adds an accessor of `kind` ("VEC2" ...) over `elements`: as `q`'s integers, or (`q` None) as floats.
    fn add(&mut self, kind: &str, elements: &[Vec<i32>], q: Option<Quantized>, as_float: Quantized) -> usize {
        let size = q.map_or(4, |q| q.size);
        let stride = (elements[0].len() * size).next_multiple_of(4);
        let offset = self.bytes.len();
        for e in elements {
            let mut bytes: Vec<u8> = match q {
                Some(q) if q.size == 1 => e.iter().map(|&c| c as u8).collect(),
                Some(_) => e.iter().flat_map(|&c| (c as u16).to_le_bytes()).collect(),
                None => e.iter().flat_map(|&c| as_float.float(c).to_le_bytes()).collect(),
            };
            bytes.resize(stride, 0);
            self.bytes.extend(bytes);
        }
        self.views.push(
            json!({"buffer": 0, "byteOffset": offset, "byteLength": stride * elements.len(), "byteStride": stride}),
        );
        let mut accessor = json!({"bufferView": self.views.len() - 1, "componentType": q.map_or(5126, |q| q.code),
                                  "count": elements.len(), "type": kind});
        if q.is_some_and(|q| q.normalized) {
            accessor["normalized"] = json!(true);
        }
        // glTF asks POSITION accessors for bounds; others may have them.
        if kind == "VEC3" {
            let bound = |f: fn(i32, i32) -> i32| {
                (0..3).map(|i| elements.iter().map(|e| e[i]).reduce(f).unwrap()).collect::<Vec<_>>()
            };
            let (lo, hi) = (bound(i32::min), bound(i32::max));
            let float = |v: Vec<i32>| v.into_iter().map(|c| json!(as_float.float(c))).collect::<Vec<_>>();
            (accessor["min"], accessor["max"]) = match q {
                Some(_) => (json!(lo), json!(hi)),
                None => (json!(float(lo)), json!(float(hi))),
            };
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }
}

/// A triangle whose every attribute (and morph target) is quantized with `quantize` set, else the same values
/// as the floats glTF's tables make of them: its float twin.
fn quantized_triangle(quantize: bool) -> (Value, Vec<u8>) {
    let mut data = VertexData::default();
    let mut add =
        |kind: &str, elements: Vec<Vec<i32>>, q: Quantized| data.add(kind, &elements, quantize.then_some(q), q);
    let position = add("VEC3", vec![vec![0, 0, 0], vec![32767, 0, -32767], vec![0, 16384, 1000]], I16_NORM);
    let normal = add("VEC3", vec![vec![0, 0, 127], vec![0, 90, 90], vec![-127, 0, 1]], I8_NORM);
    let tangent =
        add("VEC4", vec![vec![32767, 0, 0, 32767], vec![0, 32767, 0, -32767], vec![23170, 23170, 0, 32767]], I16_NORM);
    let uv0 = add("VEC2", vec![vec![0, 0], vec![65535, 0], vec![0, 30000]], U16_NORM);
    let uv1 = add("VEC2", vec![vec![0, 0], vec![3, 0], vec![0, 200]], U8);
    let displacement = add("VEC3", vec![vec![0, 0, 0], vec![-3, 2, 0], vec![0, 0, 7]], I8);
    let normal_shift = add("VEC3", vec![vec![64, 0, 0], vec![0, 0, 0], vec![0, -32767, 0]], I16_NORM);
    // A second primitive: unnormalized 16-bit positions, 8-bit normalized signed texture coordinates.
    let position2 = add("VEC3", vec![vec![0, 0, 0], vec![4000, 0, 0], vec![0, 65535, 2]], U16);
    let uv2 = add("VEC2", vec![vec![-127, 0], vec![127, 64], vec![0, -128]], I8_NORM);
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": if quantize { json!(["KHR_mesh_quantization"]) } else { json!([]) },
        "extensionsRequired": if quantize { json!(["KHR_mesh_quantization"]) } else { json!([]) },
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "scale": [0.001, 0.001, 0.001]}],
        "meshes": [{"weights": [0.5], "primitives": [
            {"attributes": {"POSITION": position, "NORMAL": normal, "TANGENT": tangent, "TEXCOORD_0": uv0,
                            "TEXCOORD_1": uv1},
             "targets": [{"POSITION": displacement, "NORMAL": normal_shift}]},
            {"attributes": {"POSITION": position2, "TEXCOORD_0": uv2}}
        ]}],
        "buffers": [{"byteLength": data.bytes.len()}],
        "bufferViews": data.views,
        "accessors": data.accessors
    });
    (doc, data.bytes)
}

/// KHR_mesh_quantization: a triangle whose positions, normals, tangents, both UV sets and morph targets are 8- and
/// 16-bit integers, normalized and not, loads to the very vertices of its float twin; without the extension
/// declared, the same file is refused with the extension named.
#[test]
fn a_quantized_mesh_loads_as_its_float_twin() {
    let dir = temp_dir("quantized");
    let load = |name: &str, (doc, bin): (Value, Vec<u8>)| {
        let path = dir.join(name);
        std::fs::write(&path, glb(&doc, &bin)).unwrap();
        strata::load_scene(&path)
    };
    let quantized = load("quantized.glb", quantized_triangle(true)).expect("the quantized file loads");
    let twin = load("twin.glb", quantized_triangle(false)).expect("its float twin loads");
    assert!(quantized.warnings.is_empty(), "{:?}", quantized.warnings);
    for (q, f) in quantized.meshes[0].primitives.iter().zip(&twin.meshes[0].primitives) {
        assert_eq!(q.positions, f.positions);
        assert_eq!(q.normals, f.normals);
        assert_eq!(q.tangents, f.tangents);
        assert_eq!((&q.uvs, &q.uvs1), (&f.uvs, &f.uvs1));
    }
    // The morph target applied at weight 0.5, the conversion as glTF's table says.
    let p = &quantized.meshes[0].primitives[0];
    assert_eq!(p.positions[1], Vec3::new(1.0 - 1.5, 1.0, -1.0));
    assert_eq!(p.uvs1[2], Vec2::new(0.0, 200.0));
    assert_eq!(quantized.meshes[0].primitives[1].uvs[2], Vec2::new(0.0, -1.0), "-128/127 clamps to -1");
    assert_eq!(quantized.meshes[0].primitives.len(), 2);

    let (mut doc, bin) = quantized_triangle(true);
    doc["extensionsUsed"] = json!([]);
    doc["extensionsRequired"] = json!([]);
    let error = format!("{:#}", load("undeclared.glb", (doc, bin)).unwrap_err());
    assert!(error.contains("POSITION") && error.contains("KHR_mesh_quantization"), "{error}");
}

/// A triangle drawn by a node with EXT_mesh_gpu_instancing: `copies` (translation, rotation, scale); with
/// `instanced` false, the twin that places the same copies as child nodes of the same parent.
fn instanced_triangles(instanced: bool, copies: &[(Vec3, glam::Quat, Vec3)]) -> (Value, Vec<u8>) {
    let mut bin = bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let translations: Vec<f32> = copies.iter().flat_map(|c| c.0.to_array()).collect();
    bin.extend(bytes_f32(&translations));
    // Rotations as normalized 16-bit integers, as the extension allows.
    for c in copies {
        bin.extend(c.1.to_array().iter().flat_map(|&v| ((v * 32767.0).round() as i16).to_le_bytes()));
    }
    let scales: Vec<f32> = copies.iter().flat_map(|c| c.2.to_array()).collect();
    bin.extend(bytes_f32(&scales));
    let n = copies.len();
    let parent = json!({"translation": [0, 0, -5], "rotation": [0, 0.38268343, 0, 0.9238795]});
    let nodes = if instanced {
        let mut node = parent.clone();
        node["mesh"] = json!(0);
        node["extensions"] =
            json!({"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 1, "ROTATION": 2, "SCALE": 3}}});
        vec![node]
    } else {
        let mut node = parent.clone();
        node["children"] = json!((1..=n).collect::<Vec<_>>());
        let mut nodes = vec![node];
        for c in copies {
            // The twin's rotation is the one the 16-bit accessor holds, normalized as strata normalizes it.
            let q = c.1.to_array().map(|v| ((v * 32767.0).round() as i16) as f32 / 32767.0);
            let q = glam::Quat::from_array(q).normalize().to_array();
            nodes.push(json!({"mesh": 0, "translation": c.0.to_array(), "rotation": q, "scale": c.2.to_array()}));
        }
        nodes
    };
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": if instanced { json!(["EXT_mesh_gpu_instancing"]) } else { json!([]) },
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 12 * n},
            {"buffer": 0, "byteOffset": 36 + 12 * n, "byteLength": 8 * n},
            {"buffer": 0, "byteOffset": 36 + 20 * n, "byteLength": 12 * n}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": n, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5122, "normalized": true, "count": n, "type": "VEC4"},
            {"bufferView": 3, "componentType": 5126, "count": n, "type": "VEC3"}
        ]
    });
    (doc, bin)
}

/// EXT_mesh_gpu_instancing: a node drawing three copies of a triangle (16-bit rotations) makes three instances
/// placed exactly where the twin file's three child nodes put them; copies whose attributes disagree in count
/// are an error naming the node and the attribute.
#[test]
fn gpu_instancing_places_each_copy_like_a_child_node() {
    use glam::Quat;
    let copies = [
        (Vec3::new(1.0, 0.0, 0.0), Quat::IDENTITY, Vec3::ONE),
        (Vec3::new(0.0, 2.0, 0.0), Quat::from_rotation_z(0.7), Vec3::new(2.0, 1.0, 1.0)),
        (Vec3::new(-1.0, 0.0, 3.0), Quat::from_rotation_x(-1.2), Vec3::splat(0.5)),
    ];
    let dir = temp_dir("instancing");
    let load = |name: &str, (doc, bin): (Value, Vec<u8>)| {
        let path = dir.join(name);
        std::fs::write(&path, glb(&doc, &bin)).unwrap();
        strata::load_scene(&path)
    };
    let instanced = load("instanced.glb", instanced_triangles(true, &copies)).expect("the instanced file loads");
    let twin = load("twin.glb", instanced_triangles(false, &copies)).expect("its twin loads");
    assert!(instanced.warnings.is_empty(), "{:?}", instanced.warnings);
    assert_eq!(instanced.instances.len(), 3);
    let (a, b) = (instanced.instance_transforms_at(0.0), twin.instance_transforms_at(0.0));
    for (k, (a, b)) in a.iter().zip(&b).enumerate() {
        assert!(a.abs_diff_eq(*b, 1e-5), "copy {k}: {a} against the child node's {b}");
        assert!(a.abs_diff_eq(instanced.instances[k].world_from_object, 1e-6), "copy {k} at rest");
    }
    assert!(!a[0].abs_diff_eq(a[1], 1e-3), "the copies are placed apart");

    let (mut doc, bin) = instanced_triangles(true, &copies);
    doc["accessors"][3]["count"] = json!(2);
    let error = format!("{:#}", load("uneven.glb", (doc, bin)).unwrap_err());
    assert!(error.contains("EXT_mesh_gpu_instancing") && error.contains("SCALE has 2 elements"), "{error}");
}

/// 2x2 RGBA texels every encoding below holds: red, green, blue (half alpha), white.
const TEXELS: [u8; 16] = [255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 128, 255, 255, 255, 255];

fn data_uri(mime: &str, bytes: &[u8]) -> String {
    use base64::Engine as _;
    format!("data:{mime};base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// A KTX2 file (KTX 2.0 §3) of one 2x2 level: `format` (a VkFormat), `scheme` (0 none, 1 BasisLZ, 2 Zstandard),
/// its level's bytes as stored and their size uncompressed. A minimal data format descriptor (its size alone).
fn ktx2(format: u32, scheme: u32, level: &[u8], uncompressed: usize) -> Vec<u8> {
    let mut b = vec![0xAB, b'K', b'T', b'X', b' ', b'2', b'0', 0xBB, b'\r', b'\n', 0x1A, b'\n'];
    for v in [format, 1, 2, 2, 0, 0, 1, 1, scheme] {
        b.extend(v.to_le_bytes());
    }
    let (dfd, data) = (80u32 + 24, 80u64 + 24 + 4);
    for v in [dfd, 4, 0, 0] {
        b.extend(v.to_le_bytes());
    }
    b.extend([0u64, 0].iter().flat_map(|v| v.to_le_bytes()));
    b.extend([data, level.len() as u64, uncompressed as u64].iter().flat_map(|v| v.to_le_bytes()));
    b.extend(4u32.to_le_bytes());
    b.extend(level);
    b
}

/// A base-colour texture whose image comes through `extension` (KHR_texture_basisu or EXT_texture_webp) from
/// `uri`, with `fallback` as its `source` when given.
fn textured_triangle(extension: &str, uri: String, fallback: Option<String>) -> Value {
    let mut images = vec![json!({"uri": uri})];
    let mut texture = json!({"extensions": {extension: {"source": 0}}});
    if let Some(f) = fallback {
        images.push(json!({"uri": f}));
        texture["source"] = json!(1);
    }
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": [extension],
        "extensionsRequired": if texture.get("source").is_some() { json!([]) } else { json!([extension]) },
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [texture],
        "images": images,
        "buffers": [{"byteLength": 60, "uri": data_uri("application/octet-stream",
            &bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]))}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
        ]
    })
}

/// Compressed and alternative texture containers decode to their PNG twin's texels: WebP (lossless,
/// EXT_texture_webp) and KTX2 (KHR_texture_basisu's container) as raw RGBA8, Zstandard-supercompressed RGBA8 and
/// raw RGB8 (alpha 1), each the texture's only image. Corrupt Basis Universal texels are an error naming the
/// image, or, where the texture has a PNG `source` too, a warning and the PNG.
#[test]
fn webp_and_ktx2_textures_decode_to_their_png_twins_texels() {
    use image::ImageEncoder as _;
    let dir = temp_dir("containers");
    let load = |name: &str, doc: Value| {
        let path = dir.join(name);
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        strata::load_scene(&path)
    };
    let texels_of = |scene: &strata::scene::Scene| {
        let image = &scene.images[scene.textures[0].image];
        assert_eq!((image.width, image.height), (2, 2));
        image.rgba8.clone()
    };
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png).write_image(&TEXELS, 2, 2, image::ExtendedColorType::Rgba8).unwrap();
    let twin = load("png.gltf", textured_triangle("EXT_texture_webp", data_uri("image/png", &png), None)).unwrap();
    assert_eq!(texels_of(&twin), TEXELS);
    let mut webp = Vec::new();
    image::codecs::webp::WebPEncoder::new_lossless(&mut webp)
        .write_image(&TEXELS, 2, 2, image::ExtendedColorType::Rgba8)
        .unwrap();
    let rgb: Vec<u8> = TEXELS.chunks(4).flat_map(|t| [t[0], t[1], t[2]]).collect();
    let opaque: Vec<u8> = TEXELS.chunks(4).flat_map(|t| [t[0], t[1], t[2], 255]).collect();
    let zstd = ruzstd::encoding::compress_to_vec(&TEXELS[..], ruzstd::encoding::CompressionLevel::Fastest);
    const R8G8B8A8_SRGB: u32 = 43;
    const R8G8B8_UNORM: u32 = 23;
    for (name, extension, uri, want) in [
        ("webp", "EXT_texture_webp", data_uri("image/webp", &webp), TEXELS.to_vec()),
        (
            "ktx2 raw",
            "KHR_texture_basisu",
            data_uri("image/ktx2", &ktx2(R8G8B8A8_SRGB, 0, &TEXELS, 16)),
            TEXELS.to_vec(),
        ),
        (
            "ktx2 zstd",
            "KHR_texture_basisu",
            data_uri("image/ktx2", &ktx2(R8G8B8A8_SRGB, 2, &zstd, 16)),
            TEXELS.to_vec(),
        ),
        ("ktx2 rgb", "KHR_texture_basisu", data_uri("image/ktx2", &ktx2(R8G8B8_UNORM, 0, &rgb, 12)), opaque),
    ] {
        let scene =
            load("alt.gltf", textured_triangle(extension, uri, None)).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        assert_eq!(texels_of(&scene), want, "{name}");
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
        // The same file as a .glb: its JSON chunk is rewritten, its binary chunk kept.
        let path = dir.join("alt.glb");
        std::fs::write(&path, glb(&textured_triangle(extension, data_uri("image/png", &png), None), &[1, 2, 3, 4]))
            .unwrap();
        assert_eq!(texels_of(&strata::load_scene(&path).unwrap_or_else(|e| panic!("{name} .glb: {e:#}"))), TEXELS);
    }
    let basis = data_uri("image/ktx2", &ktx2(0, 1, &[0; 16], 0));
    let error =
        format!("{:#}", load("basis.gltf", textured_triangle("KHR_texture_basisu", basis.clone(), None)).unwrap_err());
    assert!(error.contains("image 0") && error.contains("Basis Universal") && error.contains("basis.gltf"), "{error}");
    let with_png =
        load("fallback.gltf", textured_triangle("KHR_texture_basisu", basis, Some(data_uri("image/png", &png))))
            .unwrap();
    assert_eq!(texels_of(&with_png), TEXELS);
    assert!(
        with_png.warnings.iter().any(|w| w.contains("Basis Universal") && w.contains("fallback")),
        "{:?}",
        with_png.warnings
    );
}

/// A file of tests/data/basis/ (made by scripts/make-basis-textures.sh).
fn basis_file(name: &str) -> Vec<u8> {
    std::fs::read(common::cli::repo_file(&format!("tests/data/basis/{name}"))).unwrap()
}

/// A one-level, Zstandard-supercompressed KTX2 file (KTX 2.0 §3) rewritten with its level stored raw: the
/// scheme 0, the level's lengths its inflated size, its data at the next 16-byte boundary (without
/// supercompression a level is aligned to its texel block's size, 16 bytes for UASTC).
fn without_supercompression(ktx2: &[u8]) -> Vec<u8> {
    use std::io::Read as _;
    let u32_at = |at: usize| u32::from_le_bytes(ktx2[at..at + 4].try_into().unwrap());
    let u64_at = |at: usize| u64::from_le_bytes(ktx2[at..at + 8].try_into().unwrap()) as usize;
    assert_eq!((u32_at(40), u32_at(44)), (1, 2), "one level, Zstandard");
    let (offset, length) = (u64_at(80), u64_at(88));
    assert_eq!(offset + length, ktx2.len(), "the level's data ends the file");
    let mut level = Vec::new();
    ruzstd::decoding::StreamingDecoder::new(&ktx2[offset..]).unwrap().read_to_end(&mut level).unwrap();
    assert_eq!(level.len(), u64_at(96));
    let aligned = offset.next_multiple_of(16);
    let mut raw = ktx2[..offset].to_vec();
    raw.resize(aligned, 0);
    raw[44..48].copy_from_slice(&0u32.to_le_bytes());
    for (at, value) in [(80, aligned), (88, level.len()), (96, level.len())] {
        raw[at..at + 8].copy_from_slice(&(value as u64).to_le_bytes());
    }
    raw.extend(level);
    raw
}

/// RGBA8 texels of a PNG in tests/data/basis/.
fn basis_png(name: &str) -> (u32, u32, Vec<u8>) {
    let image = image::load_from_memory(&basis_file(name)).unwrap().to_rgba8();
    (image.width(), image.height(), image.into_raw())
}

/// KHR_texture_basisu with Basis Universal texels: an ETC1S (BasisLZ) and a UASTC (Zstandard) KTX2 file of one
/// 36x20 image each, and the UASTC one rewritten with its blocks stored raw, load with no warning, transcode to
/// exactly the bytes Binomial's reference transcoder gives, and stay near the image they encode: root-mean-square
/// channel error against source.png at most what the encoders left, measured (ETC1S 18.9: one hue per 4x4 block
/// cannot hold the yellow disc's edge on the blue ramp; UASTC 2.03; out of 255), rounded up. Every truncation of
/// each file fails with an error that names the file and the image; every byte corruption either loads or fails
/// so, never a panic or an abort (one flipped byte of UASTC's level index once made the transcoder allocate
/// 386 GB).
#[test]
fn basis_universal_ktx2_textures_transcode_to_the_reference_transcoders_texels() {
    let dir = temp_dir("basis");
    let load = |name: &str, ktx2: &[u8]| {
        let path = dir.join(name);
        let doc = textured_triangle("KHR_texture_basisu", data_uri("image/ktx2", ktx2), None);
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        strata::load_scene(&path)
    };
    let (width, height, source) = basis_png("source.png");
    let uastc_raw = without_supercompression(&basis_file("uastc.ktx2"));
    for (kind, ktx2, max_rmse) in [
        ("etc1s", basis_file("etc1s.ktx2"), 19.0),
        ("uastc", basis_file("uastc.ktx2"), 2.1),
        // The same UASTC blocks stored raw: Zstandard must change nothing.
        ("uastc", uastc_raw, 2.1),
    ] {
        let scene = load("basis.gltf", &ktx2).unwrap_or_else(|e| panic!("{kind}: {e:#}"));
        assert!(scene.warnings.is_empty(), "{kind}: {:?}", scene.warnings);
        let image = &scene.images[scene.textures[0].image];
        assert_eq!((image.width, image.height), (width, height), "{kind}");
        let (_, _, reference) = basis_png(&format!("{kind}.reference.png"));
        let differing = image.rgba8.iter().zip(&reference).filter(|(a, b)| a != b).count();
        assert!(image.rgba8 == reference, "{kind}: {differing} of {} bytes differ from the reference", reference.len());
        let squares: f64 = image.rgba8.iter().zip(&source).map(|(&a, &b)| (f64::from(a) - f64::from(b)).powi(2)).sum();
        let rmse = (squares / source.len() as f64).sqrt();
        assert!(rmse <= max_rmse, "{kind}: RMS channel error {rmse:.2} against source.png");

        for cut in 0..ktx2.len() {
            let Err(e) = load("cut.gltf", &ktx2[..cut]) else {
                panic!("{kind} cut to {cut} of {} bytes loads", ktx2.len())
            };
            let e = format!("{e:#}");
            assert!(e.contains("cut.gltf") && e.contains("image 0"), "{kind} cut to {cut} bytes: {e}");
        }
        for at in 0..ktx2.len() {
            let mut corrupt = ktx2.clone();
            corrupt[at] ^= 0x5A;
            if let Err(e) = load("corrupt.gltf", &corrupt) {
                let e = format!("{e:#}");
                assert!(e.contains("corrupt.gltf") && e.contains("image 0"), "{kind} byte {at}: {e}");
            }
        }
    }
}

/// KHR_materials_variants: a triangle whose default material is 0 and whose variants "red" and "blue" map it to
/// materials 1 and 2; `--variant` (LoadOptions::variant) or the scene file's `variant` picks one, the
/// command line's winning, and an unknown variant is an error listing the file's.
#[test]
fn material_variants_pick_each_primitives_material() {
    let dir = temp_dir("variants");
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_variants"],
        "extensions": {"KHR_materials_variants": {"variants": [{"name": "red"}, {"name": "blue"}]}},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0,
            "extensions": {"KHR_materials_variants": {"mappings": [
                {"material": 1, "variants": [0]}, {"material": 2, "variants": [1]}]}}}]}],
        "materials": [{"name": "grey"}, {"name": "red"}, {"name": "blue"}],
        "buffers": [{"byteLength": 36, "uri": data_uri("application/octet-stream",
            &bytes_f32(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]))}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}]
    });
    let file = dir.join("variants.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let material = |path: &std::path::Path, variant: Option<&str>| {
        let options = strata::LoadOptions { variant: variant.map(str::to_owned), ..Default::default() };
        strata::load(path, &options).map(|l| l.scene.meshes[0].primitives[0].material)
    };
    assert_eq!(material(&file, None).unwrap(), Some(0), "the default material without a variant");
    assert_eq!(material(&file, Some("red")).unwrap(), Some(1));
    assert_eq!(material(&file, Some("blue")).unwrap(), Some(2));
    let error = format!("{:#}", material(&file, Some("green")).unwrap_err());
    assert!(error.contains("no material variant \"green\" (red, blue)") && error.contains("variants.gltf"), "{error}");
    let toml = dir.join("variants.toml");
    std::fs::write(&toml, "gltf = \"variants.gltf\"\nvariant = \"blue\"\n").unwrap();
    assert_eq!(material(&toml, None).unwrap(), Some(2), "the scene file's variant");
    assert_eq!(material(&toml, Some("red")).unwrap(), Some(1), "the command line's wins");
    let mut bad = doc.clone();
    bad["meshes"][0]["primitives"][0]["extensions"]["KHR_materials_variants"]["mappings"][0]["material"] = json!(9);
    std::fs::write(&file, serde_json::to_vec(&bad).unwrap()).unwrap();
    let error = format!("{:#}", material(&file, None).unwrap_err());
    assert!(error.contains("KHR_materials_variants mapping") && error.contains("material 9"), "{error}");
}

/// A quad whose positions (EXPONENTIAL filter), normals (8-bit OCTAHEDRAL filter, KHR_mesh_quantization) and
/// indices (TRIANGLES) are `compressed` with EXT_meshopt_compression into a fallback buffer, or stored plain
/// (the twin) with the values the filters decode to, worked out by hand from the extension's formulas: mantissa ×
/// 2^exponent; an octahedral (x, y, 127) with z = 127 − |x| − |y| folded where negative, rescaled to length 127.
fn meshopt_quad(compressed: bool) -> (Value, Vec<u8>) {
    use meshopt_rs::index::buffer::{encode_index_buffer, encode_index_buffer_bound};
    use meshopt_rs::vertex::buffer::{encode_vertex_buffer, encode_vertex_buffer_bound};
    let exp = |mantissa: i32, exponent: i8| ((exponent as u8 as u32) << 24) | (mantissa as u32 & 0x00ff_ffff);
    // (0.5, −1.25, 3), (2, 0, −0.75), (−3, 1, 0.125), (0, 0, 6).
    let positions_exp: [[u32; 3]; 4] = [
        [exp(1, -1), exp(-5, -2), exp(3, 0)],
        [exp(1, 1), exp(0, 0), exp(-3, -2)],
        [exp(-3, 0), exp(1, 0), exp(1, -3)],
        [exp(0, 0), exp(0, 0), exp(3, 1)],
    ];
    let positions = [[0.5f32, -1.25, 3.0], [2.0, 0.0, -0.75], [-3.0, 1.0, 0.125], [0.0, 0.0, 6.0]];
    // +X, +Y, +Z and −Z in the octahedral encoding (the fourth byte is kept), then as decoded.
    let normals_oct: [[u8; 4]; 4] = [[127, 0, 127, 0], [0, 127, 127, 0], [0, 0, 127, 0], [127, 127, 127, 0]];
    let normals: [[i8; 4]; 4] = [[127, 0, 0, 0], [0, 127, 0, 0], [0, 0, 127, 0], [0, 0, -127, 0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let plain_positions = bytes_f32(&positions.concat());
    let plain_normals: Vec<u8> = normals.iter().flatten().map(|&v| v as u8).collect();
    let plain_indices: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scenes": [{"nodes": [0]}], "scene": 0,
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-3, -1.25, -0.75], "max": [2, 1, 6]},
            {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    });
    if !compressed {
        let mut bin = plain_positions;
        bin.extend(&plain_normals);
        bin.extend(&plain_indices);
        doc["bufferViews"] = json!([
            {"buffer": 0, "byteOffset": 0, "byteLength": 48, "byteStride": 12},
            {"buffer": 0, "byteOffset": 48, "byteLength": 16, "byteStride": 4},
            {"buffer": 0, "byteOffset": 64, "byteLength": 12},
        ]);
        doc["buffers"] = json!([{"byteLength": bin.len()}]);
        return (doc, bin);
    }
    let mut encoded = vec![0u8; encode_vertex_buffer_bound(4, 12)];
    let n = encode_vertex_buffer(&mut encoded, &positions_exp, Default::default()).unwrap();
    let mut bin = encoded[..n].to_vec();
    let positions_len = bin.len();
    let mut encoded = vec![0u8; encode_vertex_buffer_bound(4, 4)];
    let n = encode_vertex_buffer(&mut encoded, &normals_oct, Default::default()).unwrap();
    bin.extend(&encoded[..n]);
    let normals_len = bin.len() - positions_len;
    let mut encoded = vec![0u8; encode_index_buffer_bound(6, 4)];
    let as_u32: Vec<u32> = indices.iter().map(|&i| u32::from(i)).collect();
    let n = encode_index_buffer(&mut encoded, &as_u32, Default::default()).unwrap();
    bin.extend(&encoded[..n]);
    let indices_len = bin.len() - positions_len - normals_len;
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let ext = |offset: usize, length: usize, stride: usize, count: usize, mode: &str, filter: &str| {
        json!({"EXT_meshopt_compression": {"buffer": 0, "byteOffset": offset, "byteLength": length,
            "byteStride": stride, "count": count, "mode": mode, "filter": filter}})
    };
    doc["bufferViews"] = json!([
        {"buffer": 1, "byteOffset": 0, "byteLength": 48, "byteStride": 12,
         "extensions": ext(0, positions_len, 12, 4, "ATTRIBUTES", "EXPONENTIAL")},
        {"buffer": 1, "byteOffset": 48, "byteLength": 16, "byteStride": 4,
         "extensions": ext(positions_len, normals_len, 4, 4, "ATTRIBUTES", "OCTAHEDRAL")},
        {"buffer": 1, "byteOffset": 64, "byteLength": 12,
         "extensions": ext(positions_len + normals_len, indices_len, 2, 6, "TRIANGLES", "NONE")},
    ]);
    doc["buffers"] = json!([
        {"byteLength": bin.len()},
        {"byteLength": 76, "extensions": {"EXT_meshopt_compression": {"fallback": true}}},
    ]);
    doc["extensionsUsed"] = json!(["KHR_mesh_quantization", "EXT_meshopt_compression"]);
    doc["extensionsRequired"] = json!(["KHR_mesh_quantization", "EXT_meshopt_compression"]);
    (doc, bin)
}

/// EXT_meshopt_compression: the compressed quad loads as its plain twin, vertex for vertex and index for index,
/// with the values the extension's filters define (the quaternion filter's hand-worked cases are a unit test in
/// src/scene/gltf_meshopt.rs); an unknown filter and a fallback buffer too large to allocate are errors that name
/// the extension.
#[test]
fn a_meshopt_compressed_mesh_loads_as_its_plain_twin() {
    let dir = temp_dir("meshopt");
    let load = |name: &str, (doc, bin): (Value, Vec<u8>)| {
        let path = dir.join(name);
        std::fs::write(&path, glb(&doc, &bin)).unwrap();
        strata::load_scene(&path)
    };
    let compressed = load("compressed.glb", meshopt_quad(true)).expect("the compressed file loads");
    let twin = load("twin.glb", meshopt_quad(false)).expect("its plain twin loads");
    assert!(compressed.warnings.is_empty(), "{:?}", compressed.warnings);
    let (c, t) = (&compressed.meshes[0].primitives[0], &twin.meshes[0].primitives[0]);
    assert_eq!((&c.positions, &c.normals, &c.indices), (&t.positions, &t.normals, &t.indices));
    assert_eq!(c.positions[0], Vec3::new(0.5, -1.25, 3.0));
    assert_eq!(c.positions[3], Vec3::new(0.0, 0.0, 6.0));
    assert_eq!(c.normals, [Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_Z]);
    assert_eq!(c.indices, [0, 1, 2, 0, 2, 3]);

    let (mut doc, bin) = meshopt_quad(true);
    doc["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["filter"] = json!("SPLINE");
    let error = format!("{:#}", load("spline.glb", (doc, bin)).unwrap_err());
    assert!(error.contains("EXT_meshopt_compression") && error.contains("unknown filter \"SPLINE\""), "{error}");
    let (mut doc, bin) = meshopt_quad(true);
    doc["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["filter"] = json!("QUATERNION");
    let error = format!("{:#}", load("quaternion.glb", (doc, bin)).unwrap_err());
    assert!(error.contains("bufferView 1") && error.contains("byteStride of 8"), "{error}");
    let (mut doc, bin) = meshopt_quad(true);
    doc["buffers"][1]["byteLength"] = json!(1u64 << 40);
    let error = format!("{:#}", load("huge.glb", (doc, bin)).unwrap_err());
    assert!(error.contains("fallback") && error.contains("at most"), "{error}");
}

/// `tests/data/draco/BoxDraco.glb` is the Box sample compressed by Google's own Draco encoder (glTF-Transform's
/// `draco` command, draco3dgltf 1.5.7: Edgebreaker, positions quantized to 14 bits, normals to 10): the same 12
/// triangles, each facing the same way, every corner within the quantization step of the uncompressed file's.
#[test]
fn a_draco_compressed_box_from_the_reference_encoder_loads_as_the_box() {
    let plain = strata::load_scene(&common::cli::repo_file("tests/data/gltf-samples/Box.gltf")).unwrap();
    let draco = strata::load_scene(&common::cli::repo_file("tests/data/draco/BoxDraco.glb")).unwrap();
    assert!(draco.warnings.is_empty(), "{:?}", draco.warnings);
    let corners = |scene: &strata::scene::Scene| -> Vec<[(Vec3, Vec3); 3]> {
        let p = &scene.meshes[0].primitives[0];
        let corner = |i: u32| (p.positions[i as usize], p.normals[i as usize]);
        p.indices.chunks_exact(3).map(|t| [corner(t[0]), corner(t[1]), corner(t[2])]).collect()
    };
    let (a, b) = (corners(&plain), corners(&draco));
    assert_eq!((a.len(), b.len()), (12, 12));
    // The Box spans 1 m: 14 bits put a position within 1 / (2^14 - 1) / 2 of its value, 10-bit octahedral
    // normals within about 0.002 rad.
    let close = |x: &(Vec3, Vec3), y: &(Vec3, Vec3)| x.0.distance(y.0) < 1.0 / 16383.0 && x.1.dot(y.1) > 0.99999;
    for (i, triangle) in a.iter().enumerate() {
        let matches = b.iter().filter(|other| (0..3).any(|r| (0..3).all(|k| close(&triangle[k], &other[(k + r) % 3]))));
        assert_eq!(matches.count(), 1, "triangle {i} of Box.gltf ({triangle:?}) has no one twin in BoxDraco.glb");
    }
}
