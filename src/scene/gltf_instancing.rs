//! `EXT_mesh_gpu_instancing`: a node that draws its mesh many times, each copy placed in the node's space by a
//! translation, rotation and scale read from accessors (one element per copy). strata makes one instance per
//! copy; the node's transform and animation move them all.
use super::gltf_accessors::{check_accessor, check_format, read_floats};
use anyhow::{bail, Context as _, Result};
use glam::{Mat4, Quat, Vec3};

const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// The transforms in its node's space of each copy `node` draws: its instancing attributes' T·R·S, or one
/// identity when it has none.
pub fn node_instances(document: &gltf::Document, node: &gltf::Node<'_>, buffers: &[Vec<u8>]) -> Result<Vec<Mat4>> {
    let Some(extension) = node.extension_value(EXTENSION) else { return Ok(vec![Mat4::IDENTITY]) };
    let attributes = extension.get("attributes").and_then(|a| a.as_object()).context("has no \"attributes\" object")?;
    let accessor = |name: &str| -> Result<Option<gltf::Accessor<'_>>> {
        let Some(index) = attributes.get(name) else { return Ok(None) };
        let index = index.as_u64().with_context(|| format!("{name} is not an accessor index"))? as usize;
        let accessor = document.accessors().nth(index).with_context(|| format!("{name}: no accessor {index}"))?;
        Ok(Some(accessor))
    };
    use gltf::accessor::{DataType::*, Dimensions};
    let read3 = |name: &str| -> Result<Option<Vec<Vec3>>> {
        let Some(a) = accessor(name)? else { return Ok(None) };
        check_format(name, &a, &[Dimensions::Vec3], &[(F32, false)])?;
        check_accessor(&a, buffers).with_context(|| name.to_string())?;
        Ok(Some(read_floats::<3>(name, &a, buffers)?.into_iter().map(Vec3::from_array).collect()))
    };
    let translations = read3("TRANSLATION")?;
    let scales = read3("SCALE")?;
    let rotations = match accessor("ROTATION")? {
        Some(a) => {
            check_format("ROTATION", &a, &[Dimensions::Vec4], &[(F32, false), (I8, true), (I16, true)])?;
            check_accessor(&a, buffers).context("ROTATION")?;
            let quats: Vec<Quat> =
                read_floats::<4>("ROTATION", &a, buffers)?.into_iter().map(Quat::from_array).collect();
            Some(quats)
        }
        None => None,
    };
    let counts: Vec<(&str, usize)> = [
        ("TRANSLATION", translations.as_ref().map(Vec::len)),
        ("ROTATION", rotations.as_ref().map(Vec::len)),
        ("SCALE", scales.as_ref().map(Vec::len)),
    ]
    .into_iter()
    .filter_map(|(name, count)| count.map(|c| (name, c)))
    .collect();
    let Some(&(_, count)) = counts.first() else { bail!("has none of TRANSLATION, ROTATION and SCALE") };
    if let Some((name, other)) = counts.iter().find(|(_, c)| *c != count) {
        bail!("{name} has {other} elements where {} has {count}: every attribute needs one per copy", counts[0].0);
    }
    (0..count)
        .map(|k| {
            let t = translations.as_ref().map_or(Vec3::ZERO, |v| v[k]);
            let s = scales.as_ref().map_or(Vec3::ONE, |v| v[k]);
            let r = rotations.as_ref().map_or(Quat::IDENTITY, |v| v[k]);
            if !t.is_finite() || !s.is_finite() || !r.is_finite() || r.length() < 1e-6 {
                bail!("copy {k}: translation {t}, rotation {r}, scale {s} is not a transform");
            }
            Ok(Mat4::from_scale_rotation_translation(s, r.normalize(), t))
        })
        .collect()
}
