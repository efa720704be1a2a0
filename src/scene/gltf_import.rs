//! glTF 2.0 import (`.gltf` with embedded or external data, and `.glb`): parsing and validation, buffers, the
//! node hierarchy, cameras, `KHR_lights_punctual` lights and animations; meshes (gltf_mesh) and materials and
//! textures (gltf_material) have files of their own. Every accessor is bounds-checked before it is read; every
//! error names the file and the problem.
use super::animation::{vec4_from_xyz, Channel, Interpolation, Property};
use super::gltf_accessors::{check_accessor, check_format};
use super::gltf_material::{load_images, mark_color_textures, material, textures, warn_about_unread_uv_sets};
use super::gltf_mesh::{import_mesh, meshes_at_node_weights, uses_quantization};
use super::gltf_uri::{read_uri, UriPolicy};
use super::{Animation, Camera, Instance, Light, LightShape, Node, NodeTransform, Projection, Scene};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{Mat4, Quat, Vec3, Vec4};
use std::path::Path;

/// Extensions strata implements; a file that requires any other is refused.
pub const SUPPORTED_EXTENSIONS: [&str; 21] = [
    "EXT_mesh_gpu_instancing",
    "EXT_meshopt_compression",
    "EXT_texture_webp",
    "KHR_draco_mesh_compression",
    "KHR_lights_punctual",
    "KHR_materials_anisotropy",
    "KHR_materials_clearcoat",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_dispersion",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_iridescence",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_variants",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_texture_basisu",
    "KHR_texture_transform",
];

#[derive(Debug, Clone, Copy, Default)]
pub struct LoadOptions {
    pub uri_policy: UriPolicy,
}

/// The largest glTF file read: a `.glb`'s header counts its length in 32 bits.
pub const MAX_GLTF_BYTES: u64 = u32::MAX as u64;

/// Loads a `.gltf` or `.glb` file.
pub fn load_gltf(path: &Path, options: &LoadOptions) -> Result<Scene> {
    // A regular file, at most what a .glb's 32-bit length can say: not a FIFO, a directory or /dev/zero.
    let bytes = crate::input::read_bounded(path, MAX_GLTF_BYTES, "a glTF file")?;
    let base = path.parent().unwrap_or(Path::new("."));
    load_gltf_bytes(&bytes, base, options).with_context(|| path.display().to_string()).map(|mut scene| {
        scene.source = path.to_path_buf();
        scene
    })
}

/// Loads glTF from memory; relative URIs resolve against `base_dir`. (The fuzz target's entry point.)
pub fn load_gltf_bytes(bytes: &[u8], base_dir: &Path, options: &LoadOptions) -> Result<Scene> {
    check_required_extensions(bytes)?;
    let patched = with_texture_sources(bytes)?;
    let bytes = patched.as_deref().unwrap_or(bytes);
    let gltf = parse_and_validate(bytes)?;
    let mut buffers = load_buffers(&gltf.document, gltf.blob.as_deref(), base_dir, options.uri_policy)?;
    super::gltf_meshopt::decode_views(&gltf.document, &mut buffers)?;
    // Draco-compressed primitives: their accessors now read decoded data, in a buffer appended to `buffers`.
    let draco = gltf.document.extensions_used().any(|e| e == super::gltf_draco::EXTENSION);
    let gltf = match draco
        .then(|| super::gltf_draco::decode_primitives(&gltf.document, json_of(bytes)?, &mut buffers))
        .transpose()?
    {
        Some(Some(json)) => parse_and_validate(&json)?,
        _ => gltf,
    };
    let document = &gltf.document;
    let mut scene = Scene::default();
    for ext in document.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            scene.warnings.push(format!("optional extension {ext} is not supported; rendering without it"));
        }
    }
    let images = load_images(document, &buffers, base_dir, options.uri_policy);
    (scene.textures, scene.images) = textures(document, images, &mut scene.warnings)?;
    scene.materials = document.materials().map(|m| material(m, document.as_json())).collect::<Result<Vec<_>>>()?;
    mark_color_textures(&mut scene);
    warn_about_unread_uv_sets(&mut scene);
    scene.variants = variant_names(document);
    let quantized = uses_quantization(document);
    for mesh in document.meshes() {
        scene.meshes.push(import_mesh(&mesh, &buffers, mesh.weights().unwrap_or(&[]), quantized)?);
    }
    let node_meshes = meshes_at_node_weights(document, &buffers, &mut scene)?;
    check_variant_mappings(&scene)?;
    scene.skins = super::gltf_skin::import_skins(document, &buffers)?;
    import_nodes(document, &buffers, &mut scene, &node_meshes)?;
    super::gltf_skin::check_skinned_meshes(&scene)?;
    for animation in document.animations() {
        let a = import_animation(&animation, &buffers, &scene)
            .with_context(|| format!("animation {}", animation.index()))?;
        scene.animations.push(a);
    }
    Ok(scene)
}

/// Parses and validates with the gltf crate, guarding against its validation code panicking on malformed input.
fn parse_and_validate(bytes: &[u8]) -> Result<gltf::Gltf> {
    let unvalidated =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| anyhow!("not a valid glTF file: {e}"))?;
    // gltf-json 1.4.1 indexes a primitive's POSITION accessor before checking the index is in range
    // (mesh.rs, primitive_validate_hook); found by the fuzz target. Check every attribute index first.
    let root = unvalidated.document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let targets =
                primitive.targets.iter().flatten().flat_map(|t| [t.positions, t.normals, t.tangents]).flatten();
            for index in primitive.attributes.values().copied().chain(primitive.indices).chain(targets) {
                if index.value() >= root.accessors.len() {
                    bail!(
                        "not a valid glTF file: mesh {m} primitive {p} refers to accessor {} ({} accessors)",
                        index.value(),
                        root.accessors.len()
                    );
                }
            }
        }
    }
    // gltf-json 1.4.1 validates an animation's samplers but not its channels' targets; gltf's
    // Channel::target() then unwraps a missing node or an unknown path (both found by the fuzz target).
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            if let gltf::json::validation::Checked::Invalid = channel.target.path {
                bail!("not a valid glTF file: animation {a} channel {c} has an unknown target path");
            }
            if channel.target.node.value() >= root.nodes.len() {
                bail!(
                    "not a valid glTF file: animation {a} channel {c} targets node {} ({} nodes)",
                    channel.target.node.value(),
                    root.nodes.len()
                );
            }
        }
    }
    // Images need a uri or a bufferView, and a bufferView needs a mimeType (glTF 2.0 §5.17); gltf's
    // Image::source() unwraps both (fuzz finding).
    for (i, image) in root.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (_, Some(_), None) => bail!("not a valid glTF file: image {i} has a bufferView but no mimeType"),
            (None, None, _) => bail!("not a valid glTF file: image {i} has neither a uri nor a bufferView"),
            _ => {}
        }
    }
    // Any other panic in third-party validation becomes an error rather than taking the process down.
    match std::panic::catch_unwind(|| validated(gltf::Gltf::from_slice_without_validation(bytes)?)) {
        Ok(result) => result.map_err(|e| anyhow!("not a valid glTF file: {e}")),
        Err(_) => bail!("not a valid glTF file: the gltf parser failed on it (malformed input)"),
    }
}

/// The gltf crate's validation (`Gltf::from_slice`'s), except that an extension it has no feature for but strata
/// implements (`KHR_mesh_quantization`, read in gltf_accessors) may be required: check_required_extensions has
/// already refused those strata lacks. And the accessors of a Draco-compressed primitive may have no data: the
/// decoder fills them (gltf_draco).
fn validated(gltf: gltf::Gltf) -> std::result::Result<gltf::Gltf, gltf::Error> {
    use gltf::json::validation::{Error, Validate};
    let root = gltf.document.as_json();
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| errors.push((path(), error)));
    let decoded_later: Vec<String> = root
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .filter(|p| p.extensions.as_ref().is_some_and(|e| e.others.contains_key(super::gltf_draco::EXTENSION)))
        .flat_map(|p| p.attributes.values().copied().chain(p.indices))
        .map(|a| format!("accessors[{}].bufferView", a.value()))
        .collect();
    errors.retain(|(path, error)| !(*error == Error::Missing && decoded_later.contains(&path.as_str().to_string())));
    errors.retain(|(path, error)| {
        // The path reads `extensionsRequired[i] = "NAME"`.
        let required = path.as_str().strip_prefix("extensionsRequired[").and_then(|rest| rest.split(']').next());
        let implemented = required
            .and_then(|i| i.parse::<usize>().ok())
            .and_then(|i| root.extensions_required.get(i))
            .is_some_and(|e| SUPPORTED_EXTENSIONS.contains(&e.as_str()));
        !(*error == Error::Unsupported && implemented)
    });
    if errors.is_empty() {
        Ok(gltf)
    } else {
        Err(gltf::Error::Validation(errors))
    }
}

/// The JSON of a `.gltf`, or of a `.glb`'s JSON chunk.
fn json_of(bytes: &[u8]) -> Result<&[u8]> {
    if !bytes.starts_with(b"glTF") {
        return Ok(bytes);
    }
    // GLB: 12-byte header, then the JSON chunk (length, type "JSON", data); glTF 2.0 §4.4.
    if bytes.len() < 20 {
        bail!("truncated .glb: {} bytes is shorter than its header", bytes.len());
    }
    let chunk_len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
    if &bytes[16..20] != b"JSON" {
        bail!(".glb: the first chunk is not JSON");
    }
    bytes
        .get(20..20usize.saturating_add(chunk_len))
        .ok_or_else(|| anyhow!("truncated .glb: JSON chunk overruns the file"))
}

/// A texture whose only image is a KTX2 or WebP one (KHR_texture_basisu, EXT_texture_webp with no fallback
/// `source`) is valid glTF, but the gltf crate needs a `source`: the file with each such texture's extension
/// image copied into its `source` (None when no texture lacks one). A `.glb` keeps its other chunks as they are.
fn with_texture_sources(bytes: &[u8]) -> Result<Option<Vec<u8>>> {
    let Ok(mut root) = serde_json::from_slice::<serde_json::Value>(json_of(bytes)?) else { return Ok(None) };
    let mut changed = false;
    for texture in root.get_mut("textures").and_then(|t| t.as_array_mut()).into_iter().flatten() {
        if texture.get("source").is_some() {
            continue;
        }
        let source = super::gltf_material::IMAGE_EXTENSIONS
            .iter()
            .find_map(|ext| texture.get("extensions")?.get(ext)?.get("source").cloned());
        if let (Some(source), Some(object)) = (source, texture.as_object_mut()) {
            object.insert("source".into(), source);
            changed = true;
        }
    }
    if !changed {
        return Ok(None);
    }
    let mut json = serde_json::to_vec(&root)?;
    if !bytes.starts_with(b"glTF") {
        return Ok(Some(json));
    }
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let old_chunk_end = 20 + json_of(bytes)?.len();
    let rest = &bytes[old_chunk_end..];
    let total = 20 + json.len() + rest.len();
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(&bytes[..8]);
    glb.extend(u32::try_from(total).context(".glb grows past 4 GiB")?.to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend(json);
    glb.extend_from_slice(rest);
    Ok(Some(glb))
}

/// Reads `extensionsRequired` from the raw JSON (of a `.gltf` or a `.glb`'s JSON chunk) before anything else,
/// so a file that needs an extension strata lacks gets an error that names it.
fn check_required_extensions(bytes: &[u8]) -> Result<()> {
    let json = json_of(bytes)?;
    #[derive(serde::Deserialize)]
    struct Root {
        #[serde(default, rename = "extensionsRequired")]
        extensions_required: Vec<String>,
    }
    // A malformed document is reported by the full parser below; only a well-formed list is checked here.
    if let Ok(root) = serde_json::from_slice::<Root>(json) {
        let missing: Vec<&str> =
            root.extensions_required.iter().map(String::as_str).filter(|e| !SUPPORTED_EXTENSIONS.contains(e)).collect();
        if !missing.is_empty() {
            bail!(
                "requires extension(s) strata does not implement: {} (supported: {})",
                missing.join(", "),
                SUPPORTED_EXTENSIONS.join(", ")
            );
        }
    }
    Ok(())
}

fn load_buffers(
    document: &gltf::Document,
    blob: Option<&[u8]>,
    base: &Path,
    policy: UriPolicy,
) -> Result<Vec<Vec<u8>>> {
    document
        .buffers()
        .map(|buffer| {
            // EXT_meshopt_compression's fallback buffer holds only what compressed views decode into.
            if let Some(bytes) = super::gltf_meshopt::fallback_bytes(&buffer) {
                return bytes;
            }
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob.map(<[u8]>::to_vec).ok_or_else(|| {
                    anyhow!("buffer {} refers to the .glb binary chunk, which is missing", buffer.index())
                })?,
                gltf::buffer::Source::Uri(uri) => {
                    read_uri(uri, base, policy).with_context(|| format!("buffer {}", buffer.index()))?
                }
            };
            if data.len() < buffer.length() {
                bail!(
                    "buffer {} holds {} bytes but declares byteLength {}",
                    buffer.index(),
                    data.len(),
                    buffer.length()
                );
            }
            Ok(data)
        })
        .collect()
}

fn node_transform(node: &gltf::Node<'_>) -> NodeTransform {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => NodeTransform::Matrix(Mat4::from_cols_array_2d(&matrix)),
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => NodeTransform::Trs {
            translation: Vec3::from_array(translation),
            rotation: Quat::from_array(rotation),
            scale: Vec3::from_array(scale),
        },
    }
}

/// Every KHR_materials_variants mapping names a variant and a material the file has.
fn check_variant_mappings(scene: &Scene) -> Result<()> {
    for mesh in &scene.meshes {
        for &(variant, material) in mesh.primitives.iter().flat_map(|p| &p.variant_materials) {
            if variant >= scene.variants.len() || material >= scene.materials.len() {
                bail!(
                    "mesh \"{}\": a KHR_materials_variants mapping names variant {variant} and material {material} \
                     ({} variants, {} materials)",
                    mesh.name,
                    scene.variants.len(),
                    scene.materials.len()
                );
            }
        }
    }
    Ok(())
}

/// `KHR_materials_variants`' variant names.
fn variant_names(document: &gltf::Document) -> Vec<String> {
    let variants =
        document.extension_value("KHR_materials_variants").and_then(|e| e.get("variants")?.as_array().cloned());
    variants
        .into_iter()
        .flatten()
        .enumerate()
        .map(|(i, v)| v.get("name").and_then(|n| n.as_str()).map_or_else(|| format!("variant {i}"), str::to_owned))
        .collect()
}

/// A node's semantic class from its `extras.category_id` (the name BOP and BlenderProc give it): a whole number
/// from 0 up, else none.
fn category_of(node: &gltf::Node<'_>) -> Option<u32> {
    let extras: serde_json::Value = serde_json::from_str(node.extras().as_ref()?.get()).ok()?;
    extras.get("category_id")?.as_u64().and_then(|c| u32::try_from(c).ok())
}

/// `node_meshes`: the mesh each node draws (meshes_at_node_weights).
fn import_nodes(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    scene: &mut Scene,
    node_meshes: &[Option<usize>],
) -> Result<()> {
    scene.nodes = document
        .nodes()
        .map(|n| Node {
            name: n.name().map(str::to_owned).unwrap_or_else(|| format!("node {}", n.index())),
            parent: None,
            children: n.children().map(|c| c.index()).collect(),
            transform: node_transform(&n),
            mesh: node_meshes.get(n.index()).copied().flatten(),
            camera: None,
            light: None,
            category: category_of(&n),
            skin: n.skin().filter(|_| n.mesh().is_some()).map(|s| s.index()),
        })
        .collect();
    link_parents(scene)?;
    scene.roots = scene_roots(document, scene);
    let world = scene.node_world_transforms(None);
    let gltf_nodes: Vec<gltf::Node<'_>> = document.nodes().collect();
    // Depth-first from the roots, in document order: instances, cameras and lights of the rendered scene.
    let mut stack: Vec<usize> = scene.roots.iter().rev().copied().collect();
    while let Some(i) = stack.pop() {
        let gltf_node = &gltf_nodes[i];
        let name = scene.nodes[i].name.clone();
        if let Some(mesh) = scene.nodes[i].mesh {
            let copies = super::gltf_instancing::node_instances(document, gltf_node, buffers)
                .with_context(|| format!("node \"{name}\": EXT_mesh_gpu_instancing"))?;
            for (k, node_from_object) in copies.iter().enumerate() {
                let name = if copies.len() == 1 { name.clone() } else { format!("{name} #{k}") };
                // A skinned mesh is placed by its joints, not its node (§3.7.3.3).
                let skinned = scene.nodes[i].skin.is_some();
                let world_from_object = if skinned { Mat4::IDENTITY } else { world[i] * *node_from_object };
                scene.instances.push(Instance {
                    name,
                    mesh,
                    node: Some(i),
                    world_from_object,
                    node_from_object: *node_from_object,
                });
            }
        }
        if let Some(camera) = gltf_node.camera() {
            let projection = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    Projection::Perspective { yfov: p.yfov(), znear: p.znear(), zfar: p.zfar() }
                }
                gltf::camera::Projection::Orthographic(o) => {
                    Projection::Orthographic { xmag: o.xmag(), ymag: o.ymag(), znear: o.znear(), zfar: o.zfar() }
                }
            };
            check_projection(&projection).with_context(|| format!("camera on node \"{name}\""))?;
            // Cameras must not be scaled (§3.10.1); keep the view rigid whatever the file says.
            let (_, rotation, translation) = world[i].to_scale_rotation_translation();
            scene.nodes[i].camera = Some(scene.cameras.len());
            scene.cameras.push(Camera {
                name: camera.name().map(str::to_owned).unwrap_or_else(|| name.clone()),
                world_from_camera: Mat4::from_rotation_translation(rotation, translation),
                projection,
                lens: super::camera::Lens::PINHOLE,
            });
        }
        if let Some(light) = gltf_node.light() {
            let shape = match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => LightShape::Point { radius: 0.0 },
                gltf::khr_lights_punctual::Kind::Directional => LightShape::Directional,
                gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                    LightShape::Spot { inner_cone: inner_cone_angle, outer_cone: outer_cone_angle, radius: 0.0 }
                }
            };
            let emission = Vec3::from_array(light.color()) * light.intensity();
            if !emission.is_finite() || emission.min_element() < 0.0 {
                bail!("light on node \"{name}\": colour × intensity must be finite and non-negative");
            }
            scene.nodes[i].light = Some(scene.lights.len());
            scene.lights.push(Light {
                name: light.name().map(str::to_owned).unwrap_or_else(|| name.clone()),
                shape,
                emission,
                world_from_light: world[i],
                node: Some(i),
                range: light.range().unwrap_or(0.0),
            });
        }
        stack.extend(scene.nodes[i].children.iter().rev());
    }
    scene.camera = scene.cameras.first().cloned();
    Ok(())
}

/// Each node's parent from the children lists, refusing non-finite transforms, a node with two parents and
/// cycles (glTF 2.0 §3.5.1: node hierarchies are disjoint trees).
fn link_parents(scene: &mut Scene) -> Result<()> {
    for i in 0..scene.nodes.len() {
        if !scene.nodes[i].transform.matrix().is_finite() {
            bail!("node \"{}\": transform is not finite", scene.nodes[i].name);
        }
        for c in scene.nodes[i].children.clone() {
            if let Some(p) = scene.nodes[c].parent {
                bail!("node {c} has two parents ({p} and {i}); glTF node hierarchies are trees (§3.5.1)");
            }
            scene.nodes[c].parent = Some(i);
        }
    }
    // A cycle leaves nodes that never reach a root.
    for start in 0..scene.nodes.len() {
        let mut at = start;
        for _ in 0..=scene.nodes.len() {
            match scene.nodes[at].parent {
                Some(p) => at = p,
                None => break,
            }
        }
        if scene.nodes[at].parent.is_some() {
            bail!("node {start} is part of a cycle in the node hierarchy");
        }
    }
    Ok(())
}

/// The chosen scene's root nodes (the default scene, else the first).
fn scene_roots(document: &gltf::Document, scene: &mut Scene) -> Vec<usize> {
    let chosen = document.default_scene().or_else(|| document.scenes().next());
    let listed: Vec<usize> = match chosen {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => Vec::new(),
    };
    // glTF §3.5.2 says a scene's nodes must be roots; widely used exporters (Kenney's models among them) also list
    // children there, and every viewer draws such a file. Keep the hierarchy: draw each node once, as a child,
    // from its topmost ancestor, with a warning.
    let mut roots: Vec<usize> = Vec::with_capacity(listed.len());
    for listed in listed {
        let mut top = listed;
        while let Some(parent) = scene.nodes[top].parent {
            top = parent;
        }
        if top != listed {
            scene.warnings.push(format!(
                "scene node {listed} (\"{}\") is listed as a root but is a child of node {}; drawing it once, as a \
                 child (glTF 2.0 §3.5.2)",
                scene.nodes[listed].name,
                scene.nodes[listed].parent.unwrap_or(top)
            ));
        }
        if !roots.contains(&top) {
            roots.push(top);
        }
    }
    roots
}

fn check_projection(p: &Projection) -> Result<()> {
    match *p {
        Projection::Perspective { yfov, znear, zfar } => {
            if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                bail!("yfov {yfov} must be in (0, π)");
            }
            if !(znear > 0.0 && znear.is_finite()) || zfar.is_some_and(|f| !(f > znear && f.is_finite())) {
                bail!("znear {znear} / zfar {zfar:?} must satisfy 0 < znear < zfar");
            }
        }
        Projection::Orthographic { xmag, ymag, znear, zfar } => {
            if xmag == 0.0 || ymag == 0.0 || !(zfar > znear && znear >= 0.0) || !(xmag.is_finite() && ymag.is_finite())
            {
                bail!("orthographic xmag {xmag}, ymag {ymag}, znear {znear}, zfar {zfar} are invalid");
            }
        }
    }
    Ok(())
}

fn import_animation(animation: &gltf::Animation<'_>, buffers: &[Vec<u8>], scene: &Scene) -> Result<Animation> {
    let mut channels = Vec::new();
    for channel in animation.channels() {
        let target = channel.target();
        let node = target.node().index();
        let property = match target.property() {
            gltf::animation::Property::Translation => Property::Translation,
            gltf::animation::Property::Rotation => Property::Rotation,
            gltf::animation::Property::Scale => Property::Scale,
            gltf::animation::Property::MorphTargetWeights => Property::Weights,
        };
        if property != Property::Weights && matches!(scene.nodes[node].transform, NodeTransform::Matrix(_)) {
            bail!("channel targets node {node}, which has a matrix; only TRS nodes can be animated (§3.11)");
        }
        let sampler = channel.sampler();
        {
            use gltf::accessor::{DataType::*, Dimensions::*};
            check_format("sampler input", &sampler.input(), &[Scalar], &[(F32, false)])?;
            let rotation_types = [(F32, false), (I8, true), (U8, true), (I16, true), (U16, true)];
            match property {
                Property::Rotation => check_format("sampler output", &sampler.output(), &[Vec4], &rotation_types)?,
                Property::Weights => check_format("sampler output", &sampler.output(), &[Scalar], &rotation_types)?,
                _ => check_format("sampler output", &sampler.output(), &[Vec3], &[(F32, false)])?,
            }
        }
        check_accessor(&sampler.input(), buffers).context("sampler input")?;
        check_accessor(&sampler.output(), buffers).context("sampler output")?;
        let reader = channel.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let times: Vec<f32> = reader.read_inputs().ok_or_else(|| anyhow!("sampler input cannot be read"))?.collect();
        use gltf::animation::util::ReadOutputs;
        let interpolation = match sampler.interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
        };
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let channel_name = || format!("channel {} ({property:?} of node {node})", channel.index());
        let made = match reader.read_outputs().ok_or_else(|| anyhow!("sampler output cannot be read"))? {
            ReadOutputs::Translations(t) => {
                Channel::new(node, property, interpolation, times, t.map(vec4_from_xyz).collect())
            }
            ReadOutputs::Scales(s) => {
                Channel::new(node, property, interpolation, times, s.map(vec4_from_xyz).collect())
            }
            ReadOutputs::Rotations(r) => {
                Channel::new(node, property, interpolation, times, r.into_f32().map(Vec4::from_array).collect())
            }
            ReadOutputs::MorphTargetWeights(w) => {
                let weights: Vec<f32> = w.into_f32().collect();
                // §3.11: one weight per morph target per key (three per key for CUBICSPLINE).
                let targets = weights.len() / (times.len() * per_key).max(1);
                Channel::weights(node, interpolation, times, &weights, targets)
            }
        };
        channels.push(made.with_context(channel_name)?);
    }
    Ok(Animation {
        name: animation.name().map(str::to_owned).unwrap_or_else(|| format!("animation {}", animation.index())),
        channels,
    })
}
