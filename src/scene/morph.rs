//! Morph targets (glTF 2.0 §3.7.2.2): a primitive's attributes plus each target's displacements times its weight.
//! Applied once at load at the mesh's or a node's weights, and again at every sample's time where a clip animates
//! the weights (then through the same code from the same unmorphed attributes, so a key's weights give the bits
//! static weights would).
use super::surface::{compute_surface_derivatives, flatten_with_face_normals};
use super::Primitive;
use anyhow::{bail, Result};
use glam::Vec3;

/// One target's displacements of POSITION, NORMAL and TANGENT (each empty, or one per vertex).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MorphTarget {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub tangents: Vec<Vec3>,
}

/// What animated weights morph from: the primitive as read, before any weights, flat normals or derivatives.
#[derive(Debug, Clone, Default)]
pub struct MorphSource {
    pub unmorphed: Primitive,
    pub targets: Vec<MorphTarget>,
    /// The file gives no normals: flat ones are made after morphing.
    pub flat: bool,
}

/// Adds each target's displacements times its weight to `p` (weights past the list count as 0; a target of
/// weight 0 is skipped), then renormalizes the normals. Non-finite weights or results are an error.
pub fn apply_weights(p: &mut Primitive, targets: &[MorphTarget], weights: &[f32]) -> Result<()> {
    let weight = |t: usize| weights.get(t).copied().unwrap_or(0.0);
    if let Some(t) = (0..weights.len()).find(|&t| !weight(t).is_finite()) {
        bail!("morph target {t}: weight {} is not finite", weight(t));
    }
    if (0..targets.len()).all(|t| weight(t) == 0.0) {
        return Ok(());
    }
    for (t, target) in targets.iter().enumerate() {
        let w = weight(t);
        if w == 0.0 {
            continue;
        }
        for (v, d) in p.positions.iter_mut().zip(&target.positions) {
            *v += w * *d;
        }
        for (n, d) in p.normals.iter_mut().zip(&target.normals) {
            *n += w * *d;
        }
        for (tangent, d) in p.tangents.iter_mut().zip(&target.tangents) {
            *tangent += (w * *d).extend(0.0);
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

/// The primitive at `weights`, finished as the loader finishes one: flat normals where the file has none, surface
/// derivatives. The source keeps its targets for the next time.
pub fn morphed(source: &MorphSource, weights: &[f32]) -> Result<Primitive> {
    let mut p = source.unmorphed.clone();
    apply_weights(&mut p, &source.targets, weights)?;
    finish(&mut p, source.flat);
    Ok(p)
}

/// What the loader does after morphing: flat normals where the file has none (`flat`), then surface derivatives.
pub fn finish(p: &mut Primitive, flat: bool) {
    if flat {
        flatten_with_face_normals(p);
    }
    compute_surface_derivatives(p);
}
