//! glTF 2.0 import (`.gltf` with embedded or external data, and `.glb`): meshes with every vertex attribute
//! strata uses, materials and textures, the node hierarchy, cameras, `KHR_lights_punctual` lights and
//! animations. Every accessor is bounds-checked before it is read; every error names the file and the problem.
use super::animation::{vec4_from_xyz, Channel, Interpolation, Property};
use super::gltf_accessors::{attribute_formats, check_accessor, check_format, collect_exact};
use super::gltf_uri::{read_uri, UriPolicy};
use super::material::{AlphaMode, Material, MipFilter, Sampler, Texture, TextureImage, TextureRef, UvTransform, Wrap};
use super::surface::compute_surface_derivatives;
use super::{Animation, Camera, Instance, Light, LightShape, Mesh, Node, NodeTransform, Primitive, Projection, Scene};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::path::Path;

/// Extensions strata implements; a file that requires any other is refused.
pub const SUPPORTED_EXTENSIONS: [&str; 6] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_texture_transform",
];

/// Largest image side accepted (a corrupt header must not make strata allocate gigabytes).
const MAX_IMAGE_SIDE: u32 = 16384;

#[derive(Debug, Clone, Copy, Default)]
pub struct LoadOptions {
    pub uri_policy: UriPolicy,
}

/// Loads a `.gltf` or `.glb` file.
pub fn load_gltf(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!("{}: no such file", path.display()),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot read", path.display())),
    };
    let base = path.parent().unwrap_or(Path::new("."));
    load_gltf_bytes(&bytes, base, options).with_context(|| path.display().to_string()).map(|mut scene| {
        scene.source = path.to_path_buf();
        scene
    })
}

/// Loads glTF from memory; relative URIs resolve against `base_dir`. (The fuzz target's entry point.)
pub fn load_gltf_bytes(bytes: &[u8], base_dir: &Path, options: &LoadOptions) -> Result<Scene> {
    check_required_extensions(bytes)?;
    let gltf = parse_and_validate(bytes)?;
    let document = &gltf.document;
    let mut scene = Scene::default();
    for ext in document.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            scene.warnings.push(format!("optional extension {ext} is not supported; rendering without it"));
        }
    }
    let buffers = load_buffers(document, gltf.blob.as_deref(), base_dir, options.uri_policy)?;
    scene.images = load_images(document, &buffers, base_dir, options.uri_policy)?;
    scene.textures = document
        .textures()
        .map(|t| Texture {
            name: t.name().map(str::to_owned).unwrap_or_else(|| format!("texture {}", t.index())),
            image: t.source().index(),
            sampler: sampler(&t.sampler()),
            srgb: false,
        })
        .collect();
    scene.materials = document.materials().map(|m| material(m, document.as_json())).collect::<Result<Vec<_>>>()?;
    mark_color_textures(&mut scene);
    warn_about_unread_uv_sets(&mut scene);
    for mesh in document.meshes() {
        scene.meshes.push(import_mesh(&mesh, &buffers, mesh.weights().unwrap_or(&[]))?);
    }
    let node_meshes = meshes_at_node_weights(document, &buffers, &mut scene)?;
    import_nodes(document, &mut scene, &node_meshes)?;
    for animation in document.animations() {
        let a = import_animation(&animation, &buffers, &scene)
            .with_context(|| format!("animation {}", animation.index()))?;
        scene.animations.push(a);
    }
    let unsupported_channels: Vec<String> = document
        .animations()
        .flat_map(|a| a.channels())
        .filter(|c| c.target().property() == gltf::animation::Property::MorphTargetWeights)
        .map(|c| {
            format!(
                "animation channel on node {} animates morph weights, which strata does not support",
                c.target().node().index()
            )
        })
        .collect();
    scene.warnings.extend(unsupported_channels);
    for node in document.nodes().filter(|n| n.skin().is_some() && n.mesh().is_some()) {
        scene.warnings.push(format!(
            "node {} is skinned, which strata does not support: its mesh is drawn unskinned, as the node places it",
            node.index()
        ));
    }
    Ok(scene)
}

fn import_mesh(mesh: &gltf::Mesh<'_>, buffers: &[Vec<u8>], weights: &[f32]) -> Result<Mesh> {
    let name = mesh.name().map(str::to_owned).unwrap_or_else(|| format!("mesh {}", mesh.index()));
    let mut primitives = Vec::new();
    for (p_index, primitive) in mesh.primitives().enumerate() {
        let p = import_primitive(&primitive, buffers, weights)
            .with_context(|| format!("mesh \"{name}\", primitive {p_index}"))?;
        primitives.push(p);
    }
    Ok(Mesh { name, primitives })
}

/// The mesh each node draws: its glTF mesh, or, where the node gives morph target weights of its own (glTF 2.0
/// §3.7.2.2: they replace the mesh's), a copy of that mesh at those weights, one per distinct set.
fn meshes_at_node_weights(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    scene: &mut Scene,
) -> Result<Vec<Option<usize>>> {
    // (glTF mesh, its node's weights as bits, strata mesh) for each copy made so far.
    let mut copies: Vec<(usize, Vec<u32>, usize)> = Vec::new();
    let mut node_meshes = Vec::new();
    for node in document.nodes() {
        let index = match (node.mesh(), node.weights()) {
            (Some(mesh), Some(weights)) if weights != mesh.weights().unwrap_or(&[]) => {
                let bits: Vec<u32> = weights.iter().map(|w| w.to_bits()).collect();
                match copies.iter().find(|(m, b, _)| *m == mesh.index() && *b == bits) {
                    Some(&(_, _, copy)) => Some(copy),
                    None => {
                        let mut copy = import_mesh(&mesh, buffers, weights)
                            .with_context(|| format!("node {} (its own morph target weights)", node.index()))?;
                        copy.name = format!("{} (node {} weights)", copy.name, node.index());
                        scene.meshes.push(copy);
                        copies.push((mesh.index(), bits, scene.meshes.len() - 1));
                        Some(scene.meshes.len() - 1)
                    }
                }
            }
            (mesh, _) => mesh.map(|m| m.index()),
        };
        node_meshes.push(index);
    }
    Ok(node_meshes)
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
    match std::panic::catch_unwind(|| gltf::Gltf::from_slice(bytes)) {
        Ok(result) => result.map_err(|e| anyhow!("not a valid glTF file: {e}")),
        Err(_) => bail!("not a valid glTF file: the gltf parser failed on it (malformed input)"),
    }
}

/// Reads `extensionsRequired` from the raw JSON (of a `.gltf` or a `.glb`'s JSON chunk) before anything else,
/// so a file that needs an extension strata lacks gets an error that names it.
fn check_required_extensions(bytes: &[u8]) -> Result<()> {
    let json: &[u8] = if bytes.starts_with(b"glTF") {
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
            .ok_or_else(|| anyhow!("truncated .glb: JSON chunk overruns the file"))?
    } else {
        bytes
    };
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

fn load_images(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    base: &Path,
    policy: UriPolicy,
) -> Result<Vec<TextureImage>> {
    document
        .images()
        .map(|image| {
            let name = image.name().map(str::to_owned).unwrap_or_else(|| format!("image {}", image.index()));
            let (bytes, mime) = match image.source() {
                gltf::image::Source::View { view, mime_type } => {
                    let buffer = &buffers[view.buffer().index()];
                    let end = view.offset().checked_add(view.length()).filter(|&e| e <= buffer.len());
                    let end =
                        end.ok_or_else(|| anyhow!("{name}: its bufferView overruns buffer {}", view.buffer().index()))?;
                    (buffer[view.offset()..end].to_vec(), Some(mime_type))
                }
                gltf::image::Source::Uri { uri, mime_type } => {
                    (read_uri(uri, base, policy).with_context(|| name.clone())?, mime_type)
                }
            };
            decode_image(&name, &bytes, mime).with_context(|| format!("{name} does not decode"))
        })
        .collect()
}

fn decode_image(name: &str, bytes: &[u8], mime: Option<&str>) -> Result<TextureImage> {
    let format = match mime {
        Some("image/png") => image::ImageFormat::Png,
        Some("image/jpeg") => image::ImageFormat::Jpeg,
        _ => image::guess_format(bytes).context("unknown image format (strata reads PNG and JPEG)")?,
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

fn sampler(s: &gltf::texture::Sampler<'_>) -> Sampler {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    let wrap = |w: WrappingMode| match w {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let defaults = Sampler::default();
    let (min_linear, mipmaps) = match s.min_filter() {
        None => (defaults.min_linear, defaults.mipmaps),
        Some(MinFilter::Nearest) => (false, MipFilter::None),
        Some(MinFilter::Linear) => (true, MipFilter::None),
        Some(MinFilter::NearestMipmapNearest) => (false, MipFilter::Nearest),
        Some(MinFilter::LinearMipmapNearest) => (true, MipFilter::Nearest),
        Some(MinFilter::NearestMipmapLinear) => (false, MipFilter::Linear),
        Some(MinFilter::LinearMipmapLinear) => (true, MipFilter::Linear),
    };
    Sampler {
        mag_linear: s.mag_filter().map(|f| f == MagFilter::Linear).unwrap_or(defaults.mag_linear),
        min_linear,
        mipmaps,
        wrap_s: wrap(s.wrap_s()),
        wrap_t: wrap(s.wrap_t()),
    }
}

fn texture_ref(info: &gltf::texture::Info<'_>) -> TextureRef {
    let transform = info.texture_transform();
    TextureRef {
        texture: info.texture().index(),
        tex_coord: transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord()),
        transform: transform.map(|t| uv_transform(t.offset(), t.rotation(), t.scale())),
    }
}

/// A normal texture's KHR_texture_transform: the gltf crate reads the extension on textureInfo only, so it is
/// read here from the normalTextureInfo's raw extension object.
fn normal_texture_transform(
    m: &gltf::Material<'_>,
    name: &str,
    root: &gltf::json::Root,
) -> Result<Option<UvTransform>> {
    let raw = m
        .index()
        .and_then(|i| root.materials.get(i))
        .and_then(|json| json.normal_texture.as_ref())
        .and_then(|t| t.extensions.as_ref())
        .and_then(|e| e.others.get("KHR_texture_transform"));
    let Some(raw) = raw else { return Ok(None) };
    let t: gltf::json::extensions::texture::TextureTransform = serde_json::from_value(raw.clone())
        .map_err(|e| anyhow!("{name}: its normal texture's KHR_texture_transform is malformed: {e}"))?;
    Ok(Some(uv_transform(t.offset.0, t.rotation.0, t.scale.0)))
}

fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
    UvTransform { offset: Vec2::from_array(offset), rotation, scale: Vec2::from_array(scale) }
}

/// strata loads TEXCOORD_0 and TEXCOORD_1, and normal textures follow TEXCOORD_0 (their tangent frame is its
/// derivatives; README, known limits): say so where a material asks for another set.
fn warn_about_unread_uv_sets(scene: &mut Scene) {
    let mut warnings = Vec::new();
    for m in &scene.materials {
        let uses = [
            ("base colour", m.base_color_texture, 1),
            ("metallic-roughness", m.metallic_roughness_texture, 1),
            ("normal", m.normal_texture, 0),
            ("emissive", m.emissive_texture, 1),
            ("transmission", m.transmission_texture, 1),
            ("specular", m.specular_texture, 1),
            ("specular colour", m.specular_color_texture, 1),
        ];
        for (what, t, last_read) in uses {
            if let Some(t) = t.filter(|t| t.tex_coord > last_read) {
                warnings.push(format!(
                    "material \"{}\": its {what} texture uses TEXCOORD_{}; strata reads it with TEXCOORD_0",
                    m.name, t.tex_coord
                ));
            }
        }
    }
    scene.warnings.extend(warnings);
}

fn material(m: gltf::Material<'_>, root: &gltf::json::Root) -> Result<Material> {
    let pbr = m.pbr_metallic_roughness();
    let defaults = Material::default();
    let name = m.name().map(str::to_owned).unwrap_or_else(|| format!("material {}", m.index().unwrap_or(0)));
    let normal_transform = normal_texture_transform(&m, &name, root)?;
    Ok(Material {
        name,
        base_color: Vec4::from_array(pbr.base_color_factor()),
        base_color_texture: pbr.base_color_texture().as_ref().map(texture_ref),
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        metallic_roughness_texture: pbr.metallic_roughness_texture().as_ref().map(texture_ref),
        normal_texture: m.normal_texture().map(|n| TextureRef {
            texture: n.texture().index(),
            tex_coord: n.tex_coord(),
            transform: normal_transform,
        }),
        normal_scale: m.normal_texture().map(|n| n.scale()).unwrap_or(1.0),
        occlusion_texture: m.occlusion_texture().map(|o| TextureRef {
            texture: o.texture().index(),
            tex_coord: o.tex_coord(),
            transform: None,
        }),
        occlusion_strength: m.occlusion_texture().map(|o| o.strength()).unwrap_or(1.0),
        emissive: Vec3::from_array(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
        emissive_texture: m.emissive_texture().as_ref().map(texture_ref),
        alpha_mode: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        double_sided: m.double_sided(),
        transmission: m.transmission().map(|t| t.transmission_factor()).unwrap_or(0.0),
        transmission_texture: m.transmission().and_then(|t| t.transmission_texture()).as_ref().map(texture_ref),
        ior: m.ior().unwrap_or(defaults.ior),
        specular: m.specular().map(|s| s.specular_factor()).unwrap_or(defaults.specular),
        specular_texture: m.specular().and_then(|s| s.specular_texture()).as_ref().map(texture_ref),
        specular_color: m
            .specular()
            .map(|s| Vec3::from_array(s.specular_color_factor()))
            .unwrap_or(defaults.specular_color),
        specular_color_texture: m.specular().and_then(|s| s.specular_color_texture()).as_ref().map(texture_ref),
        bump: None,
    })
}

/// Base colour, emissive and specular colour textures hold sRGB-encoded colour; the rest hold linear data (glTF
/// 2.0 §3.9, KHR_materials_specular).
fn mark_color_textures(scene: &mut Scene) {
    for m in &scene.materials {
        for t in [m.base_color_texture, m.emissive_texture, m.specular_color_texture].into_iter().flatten() {
            if let Some(texture) = scene.textures.get_mut(t.texture) {
                texture.srgb = true;
            }
        }
    }
}

/// One primitive, its morph targets applied at `weights` (the mesh's or a node's).
fn import_primitive(primitive: &gltf::Primitive<'_>, buffers: &[Vec<u8>], weights: &[f32]) -> Result<Primitive> {
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        bail!("mode {:?} is not supported (only TRIANGLES)", primitive.mode());
    }
    for (semantic, accessor) in primitive.attributes() {
        let what = semantic.to_string();
        if let Some((dimensions, types)) = attribute_formats(&semantic) {
            check_format(&what, &accessor, dimensions, types)?;
        }
        check_accessor(&accessor, buffers).with_context(|| what.clone())?;
    }
    if let Some(indices) = primitive.indices() {
        use gltf::accessor::{DataType, Dimensions};
        let types = [(DataType::U8, false), (DataType::U16, false), (DataType::U32, false)];
        check_format("indices", &indices, &[Dimensions::Scalar], &types)?;
        check_accessor(&indices, buffers).context("indices")?;
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let position_accessor =
        primitive.get(&gltf::Semantic::Positions).ok_or_else(|| anyhow!("has no POSITION attribute"))?;
    let positions: Vec<Vec3> = collect_exact(
        "POSITION",
        &position_accessor,
        reader.read_positions().ok_or_else(|| anyhow!("POSITION cannot be read"))?.map(Vec3::from_array),
    )?;
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        bail!("POSITION {i} is not finite ({})", positions[i]);
    }
    let indices: Vec<u32> = match (reader.read_indices(), primitive.indices()) {
        (Some(indices), Some(accessor)) => collect_exact("indices", &accessor, indices.into_u32())?,
        _ => (0..positions.len() as u32).collect(),
    };
    if indices.len() % 3 != 0 {
        bail!("{} indices do not make whole triangles", indices.len());
    }
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        bail!("index {bad} is out of range ({} vertices)", positions.len());
    }
    let attribute = |semantic: gltf::Semantic| primitive.get(&semantic);
    let mut p = Primitive { positions, indices, material: primitive.material().index(), ..Default::default() };
    if let (Some(normals), Some(a)) = (reader.read_normals(), attribute(gltf::Semantic::Normals)) {
        p.normals = collect_exact("NORMAL", &a, normals.map(|v| Vec3::from_array(v).normalize_or_zero()))?;
        if p.normals.iter().any(|n| !n.is_finite()) {
            bail!("NORMAL holds non-finite values");
        }
    }
    if let (Some(tangents), Some(a)) = (reader.read_tangents(), attribute(gltf::Semantic::Tangents)) {
        p.tangents = collect_exact("TANGENT", &a, tangents.map(Vec4::from_array))?;
    }
    if let (Some(uv), Some(a)) = (reader.read_tex_coords(0), attribute(gltf::Semantic::TexCoords(0))) {
        p.uvs = collect_exact("TEXCOORD_0", &a, uv.into_f32().map(Vec2::from_array))?;
    }
    if let (Some(uv), Some(a)) = (reader.read_tex_coords(1), attribute(gltf::Semantic::TexCoords(1))) {
        p.uvs1 = collect_exact("TEXCOORD_1", &a, uv.into_f32().map(Vec2::from_array))?;
    }
    if let (Some(colors), Some(a)) = (reader.read_colors(0), attribute(gltf::Semantic::Colors(0))) {
        p.colors = collect_exact("COLOR_0", &a, colors.into_rgba_f32().map(Vec4::from_array))?;
    }
    for (name, len) in [
        ("NORMAL", p.normals.len()),
        ("TANGENT", p.tangents.len()),
        ("TEXCOORD_0", p.uvs.len()),
        ("TEXCOORD_1", p.uvs1.len()),
        ("COLOR_0", p.colors.len()),
    ] {
        if len != 0 && len != p.positions.len() {
            bail!("{name} has {len} entries for {} vertices", p.positions.len());
        }
    }
    if p.uvs.iter().chain(&p.uvs1).any(|uv| !uv.is_finite()) {
        bail!("texture coordinates hold non-finite values");
    }
    apply_morph_targets(primitive, buffers, weights, &mut p)?;
    if p.normals.is_empty() {
        flatten_with_face_normals(&mut p);
    }
    compute_surface_derivatives(&mut p);
    Ok(p)
}

/// Adds each morph target's displacements of POSITION, NORMAL and TANGENT, times its weight, to the base
/// attributes (glTF 2.0 §3.7.2.2); normals are renormalized. Weights past the list count as 0.
fn apply_morph_targets(
    primitive: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    weights: &[f32],
    p: &mut Primitive,
) -> Result<()> {
    use gltf::accessor::{DataType, Dimensions};
    let weight = |t: usize| weights.get(t).copied().unwrap_or(0.0);
    if let Some(t) = (0..weights.len()).find(|&t| !weight(t).is_finite()) {
        bail!("morph target {t}: weight {} is not finite", weight(t));
    }
    if (0..primitive.morph_targets().len()).all(|t| weight(t) == 0.0) {
        return Ok(());
    }
    // Every target's accessors are checked before the reader touches any: it slices buffers unchecked.
    for (t, target) in primitive.morph_targets().enumerate() {
        for (name, accessor) in
            [("POSITION", target.positions()), ("NORMAL", target.normals()), ("TANGENT", target.tangents())]
        {
            let Some(accessor) = accessor else { continue };
            let what = format!("morph target {t} {name}");
            check_format(&what, &accessor, &[Dimensions::Vec3], &[(DataType::F32, false)])?;
            check_accessor(&accessor, buffers).with_context(|| what.clone())?;
            if accessor.count() != p.positions.len() {
                bail!("{what} has {} entries for {} vertices", accessor.count(), p.positions.len());
            }
        }
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    for (t, (positions, normals, tangents)) in reader.read_morph_targets().enumerate() {
        let w = weight(t);
        if w == 0.0 {
            continue;
        }
        let deltas = |values: Option<gltf::accessor::Iter<'_, [f32; 3]>>| -> Vec<Vec3> {
            values.map(|i| i.map(|d| w * Vec3::from_array(d)).collect()).unwrap_or_default()
        };
        for (v, d) in p.positions.iter_mut().zip(deltas(positions)) {
            *v += d;
        }
        for (n, d) in p.normals.iter_mut().zip(deltas(normals)) {
            *n += d;
        }
        for (tangent, d) in p.tangents.iter_mut().zip(deltas(tangents)) {
            *tangent += d.extend(0.0);
        }
    }
    if p.positions.iter().chain(&p.normals).any(|v| !v.is_finite()) || p.tangents.iter().any(|t| !t.is_finite()) {
        bail!("morph targets move vertex attributes to non-finite values");
    }
    for n in &mut p.normals {
        *n = n.normalize_or_zero();
    }
    Ok(())
}

/// Without NORMAL, glTF asks for flat normals (§3.7.2.1): give every triangle its own three vertices.
fn flatten_with_face_normals(p: &mut Primitive) {
    fn gather<T: Copy>(values: &[T], indices: &[u32]) -> Vec<T> {
        if values.is_empty() {
            Vec::new()
        } else {
            indices.iter().map(|&i| values[i as usize]).collect()
        }
    }
    let normals = p
        .indices
        .chunks_exact(3)
        .flat_map(|tri| {
            let [a, b, c] = [0, 1, 2].map(|k| p.positions[tri[k] as usize]);
            // Zero-area triangles get a zero normal rather than NaN.
            let n = (b - a).cross(c - a).normalize_or_zero();
            [n, n, n]
        })
        .collect();
    p.positions = gather(&p.positions, &p.indices);
    p.tangents = gather(&p.tangents, &p.indices);
    p.uvs = gather(&p.uvs, &p.indices);
    p.uvs1 = gather(&p.uvs1, &p.indices);
    p.colors = gather(&p.colors, &p.indices);
    p.normals = normals;
    p.indices = (0..p.positions.len() as u32).collect();
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

/// `node_meshes`: the mesh each node draws (meshes_at_node_weights).
fn import_nodes(document: &gltf::Document, scene: &mut Scene, node_meshes: &[Option<usize>]) -> Result<()> {
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
        })
        .collect();
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
    let chosen = document.default_scene().or_else(|| document.scenes().next());
    scene.roots = match chosen {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => Vec::new(),
    };
    for &root in &scene.roots {
        if let Some(parent) = scene.nodes[root].parent {
            bail!("scene root node {root} is also a child of node {parent}");
        }
    }
    let world = scene.node_world_transforms(None);
    let gltf_nodes: Vec<gltf::Node<'_>> = document.nodes().collect();
    // Depth-first from the roots, in document order: instances, cameras and lights of the rendered scene.
    let mut stack: Vec<usize> = scene.roots.iter().rev().copied().collect();
    while let Some(i) = stack.pop() {
        let gltf_node = &gltf_nodes[i];
        let name = scene.nodes[i].name.clone();
        if let Some(mesh) = scene.nodes[i].mesh {
            scene.instances.push(Instance { name: name.clone(), mesh, node: Some(i), world_from_object: world[i] });
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
            gltf::animation::Property::MorphTargetWeights => continue,
        };
        if matches!(scene.nodes[node].transform, NodeTransform::Matrix(_)) {
            bail!("channel targets node {node}, which has a matrix; only TRS nodes can be animated (§3.11)");
        }
        let sampler = channel.sampler();
        {
            use gltf::accessor::{DataType::*, Dimensions::*};
            check_format("sampler input", &sampler.input(), &[Scalar], &[(F32, false)])?;
            let rotation_types = [(F32, false), (I8, true), (U8, true), (I16, true), (U16, true)];
            match property {
                Property::Rotation => check_format("sampler output", &sampler.output(), &[Vec4], &rotation_types)?,
                _ => check_format("sampler output", &sampler.output(), &[Vec3], &[(F32, false)])?,
            }
        }
        check_accessor(&sampler.input(), buffers).context("sampler input")?;
        check_accessor(&sampler.output(), buffers).context("sampler output")?;
        let reader = channel.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let times: Vec<f32> = reader.read_inputs().ok_or_else(|| anyhow!("sampler input cannot be read"))?.collect();
        use gltf::animation::util::ReadOutputs;
        let values: Vec<Vec4> = match reader.read_outputs().ok_or_else(|| anyhow!("sampler output cannot be read"))? {
            ReadOutputs::Translations(t) => t.map(vec4_from_xyz).collect(),
            ReadOutputs::Scales(s) => s.map(vec4_from_xyz).collect(),
            ReadOutputs::Rotations(r) => r.into_f32().map(Vec4::from_array).collect(),
            ReadOutputs::MorphTargetWeights(_) => continue,
        };
        let interpolation = match sampler.interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
        };
        channels.push(
            Channel::new(node, property, interpolation, times, values)
                .with_context(|| format!("channel {} ({property:?} of node {node})", channel.index()))?,
        );
    }
    Ok(Animation {
        name: animation.name().map(str::to_owned).unwrap_or_else(|| format!("animation {}", animation.index())),
        channels,
    })
}
