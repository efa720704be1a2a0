//! glTF meshes: each primitive's attributes, bounds-checked before they are read, with morph targets applied
//! at the mesh's or a node's weights, flat normals where the file has none, and the surface derivatives bump
//! mapping needs.
use super::gltf_accessors::{attribute_formats, check_accessor, check_format, collect_exact, read_floats};
use super::morph::{apply_weights, finish, MorphSource, MorphTarget};
use super::skin::JointInfluences;
use super::{Mesh, Primitive, Scene};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{Vec2, Vec3, Vec4};

/// Whether `document` uses `KHR_mesh_quantization`, which lets vertex attributes hold integers.
pub(super) fn uses_quantization(document: &gltf::Document) -> bool {
    document.extensions_used().any(|e| e == QUANTIZATION)
}

const QUANTIZATION: &str = "KHR_mesh_quantization";

/// A mesh's primitives at `weights`; `quantized`: the file uses `KHR_mesh_quantization`.
pub(super) fn import_mesh(
    mesh: &gltf::Mesh<'_>,
    buffers: &[Vec<u8>],
    weights: &[f32],
    quantized: bool,
) -> Result<Mesh> {
    let name = mesh.name().map(str::to_owned).unwrap_or_else(|| format!("mesh {}", mesh.index()));
    let mut primitives = Vec::new();
    for (p_index, primitive) in mesh.primitives().enumerate() {
        let p = import_primitive(&primitive, buffers, weights, quantized)
            .with_context(|| format!("mesh \"{name}\", primitive {p_index}"))?;
        primitives.push(p);
    }
    Ok(Mesh { name, primitives })
}

/// The mesh each node draws: its glTF mesh, or, where the node gives morph target weights of its own (glTF 2.0
/// §3.7.2.2: they replace the mesh's), a copy of that mesh at those weights, one per distinct set.
pub(super) fn meshes_at_node_weights(
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
                        let mut copy = import_mesh(&mesh, buffers, weights, uses_quantization(document))
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

/// One primitive, its morph targets applied at `weights` (the mesh's or a node's).
fn import_primitive(
    primitive: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    weights: &[f32],
    quantized: bool,
) -> Result<Primitive> {
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        bail!("mode {:?} is not supported (only TRIANGLES)", primitive.mode());
    }
    for (semantic, accessor) in primitive.attributes() {
        let what = semantic.to_string();
        if let Some((dimensions, types)) = attribute_formats(&semantic, quantized) {
            let checked = check_format(&what, &accessor, dimensions, types);
            // A quantized attribute in a file that does not say so: name the extension it needs.
            if let (Err(e), false, Some((dimensions, types))) =
                (&checked, quantized, attribute_formats(&semantic, true))
            {
                if check_format(&what, &accessor, dimensions, types).is_ok() {
                    bail!("{e:#} (KHR_mesh_quantization allows it, but the file does not list it in extensionsUsed)");
                }
            }
            checked?;
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
    let positions: Vec<Vec3> =
        read_floats::<3>("POSITION", &position_accessor, buffers)?.into_iter().map(Vec3::from_array).collect();
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
    let variant_materials = variant_mappings(primitive)?;
    let mut p = Primitive {
        positions,
        indices,
        material: primitive.material().index(),
        variant_materials,
        ..Default::default()
    };
    if let Some(a) = attribute(gltf::Semantic::Normals) {
        let normals = read_floats::<3>("NORMAL", &a, buffers)?;
        p.normals = normals.into_iter().map(|v| Vec3::from_array(v).normalize_or_zero()).collect();
        if p.normals.iter().any(|n| !n.is_finite()) {
            bail!("NORMAL holds non-finite values");
        }
    }
    if let Some(a) = attribute(gltf::Semantic::Tangents) {
        p.tangents = read_floats::<4>("TANGENT", &a, buffers)?.into_iter().map(Vec4::from_array).collect();
    }
    if let Some(a) = attribute(gltf::Semantic::TexCoords(0)) {
        p.uvs = read_floats::<2>("TEXCOORD_0", &a, buffers)?.into_iter().map(Vec2::from_array).collect();
    }
    if let Some(a) = attribute(gltf::Semantic::TexCoords(1)) {
        p.uvs1 = read_floats::<2>("TEXCOORD_1", &a, buffers)?.into_iter().map(Vec2::from_array).collect();
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
    p.skin_influences = joint_influences(primitive, buffers, p.positions.len())?;
    let targets = morph_targets(primitive, buffers, quantized, p.positions.len())?;
    let flat = p.normals.is_empty();
    // Kept unmorphed for clips that animate the weights (Scene::deform_instance).
    let unmorphed = (!targets.is_empty()).then(|| p.clone());
    apply_weights(&mut p, &targets, weights)?;
    finish(&mut p, flat);
    p.morph = unmorphed.map(|unmorphed| Box::new(MorphSource { unmorphed, targets, flat }));
    Ok(p)
}

/// Every `JOINTS_n`/`WEIGHTS_n` pair of the primitive (§3.7.3.2), from set 0 up to the first missing one; a set
/// with one half and not the other is an error, as are weights that are negative or not finite.
fn joint_influences(
    primitive: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    vertices: usize,
) -> Result<Vec<JointInfluences>> {
    let mut sets = Vec::new();
    for set in 0.. {
        let joints = primitive.get(&gltf::Semantic::Joints(set));
        let weights = primitive.get(&gltf::Semantic::Weights(set));
        let (joints, weights) = match (joints, weights) {
            (None, None) => break,
            (Some(j), Some(w)) => (j, w),
            (Some(_), None) => bail!("JOINTS_{set} has no WEIGHTS_{set}"),
            (None, Some(_)) => bail!("WEIGHTS_{set} has no JOINTS_{set}"),
        };
        let joints = read_floats::<4>(&format!("JOINTS_{set}"), &joints, buffers)?;
        let weights = read_floats::<4>(&format!("WEIGHTS_{set}"), &weights, buffers)?;
        if joints.len() != vertices || weights.len() != vertices {
            bail!("JOINTS_{set}/WEIGHTS_{set} have {}/{} entries for {vertices} vertices", joints.len(), weights.len());
        }
        if let Some(v) = weights.iter().position(|w| w.iter().any(|x| !x.is_finite() || *x < 0.0)) {
            bail!("WEIGHTS_{set} of vertex {v} is negative or not finite ({:?})", weights[v]);
        }
        sets.push(JointInfluences {
            // Read as floats from U8/U16 components (check_format allows no other), so each converts exactly.
            joints: joints.into_iter().map(|j| j.map(|x| x as u16)).collect(),
            weights: weights.into_iter().map(Vec4::from_array).collect(),
        });
    }
    Ok(sets)
}

/// Each morph target's displacements of POSITION, NORMAL and TANGENT (glTF 2.0 §3.7.2.2), every accessor checked
/// before any is read (the reader slices buffers unchecked).
fn morph_targets(
    primitive: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    quantized: bool,
    vertices: usize,
) -> Result<Vec<MorphTarget>> {
    use super::gltf_accessors::{QUANTIZED_DIRECTION, QUANTIZED_DISPLACEMENT};
    use gltf::accessor::{DataType, Dimensions};
    for (t, target) in primitive.morph_targets().enumerate() {
        for (name, accessor) in
            [("POSITION", target.positions()), ("NORMAL", target.normals()), ("TANGENT", target.tangents())]
        {
            let Some(accessor) = accessor else { continue };
            let what = format!("morph target {t} {name}");
            let types = match (quantized, name) {
                (false, _) => &[(DataType::F32, false)][..],
                (true, "POSITION") => QUANTIZED_DISPLACEMENT,
                (true, _) => QUANTIZED_DIRECTION,
            };
            check_format(&what, &accessor, &[Dimensions::Vec3], types)?;
            check_accessor(&accessor, buffers).with_context(|| what.clone())?;
            if accessor.count() != vertices {
                bail!("{what} has {} entries for {vertices} vertices", accessor.count());
            }
        }
    }
    primitive
        .morph_targets()
        .enumerate()
        .map(|(t, target)| {
            let deltas = |name: &str, accessor: Option<gltf::Accessor<'_>>| -> Result<Vec<Vec3>> {
                let Some(accessor) = accessor else { return Ok(Vec::new()) };
                let values = read_floats::<3>(&format!("morph target {t} {name}"), &accessor, buffers)?;
                Ok(values.into_iter().map(Vec3::from_array).collect())
            };
            Ok(MorphTarget {
                positions: deltas("POSITION", target.positions())?,
                normals: deltas("NORMAL", target.normals())?,
                tangents: deltas("TANGENT", target.tangents())?,
            })
        })
        .collect()
}

/// A primitive's `KHR_materials_variants` mappings: (variant, material) for each variant a mapping lists.
fn variant_mappings(primitive: &gltf::Primitive<'_>) -> Result<Vec<(usize, usize)>> {
    let Some(extension) = primitive.extension_value("KHR_materials_variants") else { return Ok(Vec::new()) };
    let mut pairs = Vec::new();
    for mapping in extension.get("mappings").and_then(|m| m.as_array()).into_iter().flatten() {
        let material = mapping
            .get("material")
            .and_then(|m| m.as_u64())
            .context("KHR_materials_variants: a mapping has no material")?;
        for variant in mapping.get("variants").and_then(|v| v.as_array()).into_iter().flatten() {
            let variant = variant.as_u64().context("KHR_materials_variants: a variant is not an index")?;
            pairs.push((variant as usize, material as usize));
        }
    }
    Ok(pairs)
}
