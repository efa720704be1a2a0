//! glTF skins (§3.7.3): each skin's joints and inverse bind matrices, bounds-checked, and the check that every
//! skinned node's mesh names only joints its skin has.
use super::gltf_accessors::{check_accessor, check_format};
use super::skin::Skin;
use super::Scene;
use anyhow::{bail, Context as _, Result};
use glam::Mat4;

/// Every skin of the file, in its order.
pub(super) fn import_skins(document: &gltf::Document, buffers: &[Vec<u8>]) -> Result<Vec<Skin>> {
    document
        .skins()
        .map(|skin| {
            let name = skin.name().map(str::to_owned).unwrap_or_else(|| format!("skin {}", skin.index()));
            import_skin(&skin, buffers, name.clone()).with_context(|| format!("skin \"{name}\""))
        })
        .collect()
}

fn import_skin(skin: &gltf::Skin<'_>, buffers: &[Vec<u8>], name: String) -> Result<Skin> {
    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    if joints.is_empty() {
        bail!("has no joints");
    }
    if joints.len() > usize::from(u16::MAX) + 1 {
        bail!("has {} joints; JOINTS_n can name at most 65536", joints.len());
    }
    let inverse_bind = match skin.inverse_bind_matrices() {
        None => vec![Mat4::IDENTITY; joints.len()],
        Some(accessor) => {
            use gltf::accessor::{DataType::F32, Dimensions::Mat4 as Mat4Type};
            check_format("inverseBindMatrices", &accessor, &[Mat4Type], &[(F32, false)])?;
            check_accessor(&accessor, buffers).context("inverseBindMatrices")?;
            let reader = skin.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let matrices: Vec<Mat4> = reader
                .read_inverse_bind_matrices()
                .context("inverseBindMatrices cannot be read")?
                .map(|m| Mat4::from_cols_array_2d(&m))
                .collect();
            if matrices.len() < joints.len() {
                bail!("inverseBindMatrices has {} matrices for {} joints", matrices.len(), joints.len());
            }
            if let Some(i) = matrices.iter().position(|m| !m.is_finite()) {
                bail!("inverse bind matrix {i} is not finite");
            }
            matrices[..joints.len()].to_vec()
        }
    };
    Ok(Skin { name, joints, inverse_bind })
}

/// Every primitive of every skinned node's mesh carries joint influences, and names only joints its skin has.
pub(super) fn check_skinned_meshes(scene: &Scene) -> Result<()> {
    for node in &scene.nodes {
        let (Some(skin), Some(mesh)) = (node.skin, node.mesh) else { continue };
        let (skin, mesh) = (&scene.skins[skin], &scene.meshes[mesh]);
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let what =
                || format!("node \"{}\" (skin \"{}\"), mesh \"{}\", primitive {p}", node.name, skin.name, mesh.name);
            if primitive.skin_influences.is_empty() {
                bail!("{}: a skinned mesh needs JOINTS_0 and WEIGHTS_0 (glTF 2.0 §3.7.3.2)", what());
            }
            let joints = primitive.skin_influences.iter().flat_map(|set| set.joints.iter().zip(&set.weights));
            for (j, w) in joints {
                if let Some(k) = (0..4).find(|&k| w[k] != 0.0 && usize::from(j[k]) >= skin.joints.len()) {
                    bail!("{}: a vertex names joint {}, but the skin has {}", what(), j[k], skin.joints.len());
                }
            }
        }
    }
    Ok(())
}
