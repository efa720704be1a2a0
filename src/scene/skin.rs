//! Deformation: morph weights a clip animates (§3.7.2.2, `morph`) and skins (glTF 2.0 §3.7.3): joints, their inverse bind matrices, and each vertex's joints and weights. A skinned
//! vertex is Σ wᵢ·Jᵢ·p with joint matrix Jᵢ = (joint i's world transform) · (its inverse bind matrix), which puts it
//! in the world directly: the transform of the node that holds the mesh is not applied (§3.7.3.3), so a skinned
//! instance's transform is the identity (`Scene::instance_transforms_from`). Each sample's deformation at its
//! shutter time: morphs on the host, skins on the GPU (`render::skinning`, whose twin `skin_vertices` is;
//! docs/architecture.md, "Deformed meshes").
use super::{Primitive, Property, Scene};
use glam::{Mat3, Mat4, Vec3, Vec4};

#[derive(Debug, Clone, PartialEq)]
pub struct Skin {
    pub name: String,
    /// Node indices, in the order `JOINTS_n` refers to them.
    pub joints: Vec<usize>,
    /// One per joint; the identity where the file gives none.
    pub inverse_bind: Vec<Mat4>,
}

/// One `JOINTS_n`/`WEIGHTS_n` pair: four joints (indices into the skin's `joints`) and their weights per vertex.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointInfluences {
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<Vec4>,
}

/// A primitive's vertex streams after deformation, in the world: what the G-buffer pass and the BLAS read in place
/// of the mesh's own positions, normals and surface derivatives.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DeformedVertices {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub dpdu: Vec<Vec3>,
    pub dpdv: Vec<Vec3>,
}

impl Skin {
    /// Each joint's matrix given every node's world transform: Jᵢ = world(jointᵢ) · inverse_bindᵢ.
    pub fn joint_matrices(&self, node_world: &[Mat4]) -> Vec<Mat4> {
        self.joints
            .iter()
            .zip(&self.inverse_bind)
            .map(|(&joint, inverse_bind)| node_world.get(joint).copied().unwrap_or(Mat4::ZERO) * *inverse_bind)
            .collect()
    }
}

/// `primitive`'s vertices skinned by `joint_matrices`. Every influence set adds to one blended matrix per vertex,
/// S = Σ wᵢ·Jᵢ: positions go through S, surface derivatives (tangent vectors) through its linear part, normals
/// through that part's cofactor matrix (the inverse transpose up to a positive factor where S keeps
/// orientation). A joint index beyond the skin reads a zero matrix (the loader rejects such files).
pub fn skin_vertices(primitive: &Primitive, joint_matrices: &[Mat4]) -> DeformedVertices {
    let n = primitive.positions.len();
    let mut out = DeformedVertices {
        positions: Vec::with_capacity(n),
        normals: Vec::with_capacity(primitive.normals.len()),
        dpdu: Vec::with_capacity(primitive.dpdu.len()),
        dpdv: Vec::with_capacity(primitive.dpdv.len()),
    };
    for v in 0..n {
        let mut blended = Mat4::ZERO;
        for set in &primitive.skin_influences {
            let (joints, weights) = (set.joints[v], set.weights[v].to_array());
            for (joint, weight) in joints.iter().zip(weights) {
                if weight != 0.0 {
                    blended += joint_matrices.get(usize::from(*joint)).copied().unwrap_or(Mat4::ZERO) * weight;
                }
            }
        }
        let linear = Mat3::from_mat4(blended);
        out.positions.push(blended.transform_point3(primitive.positions[v]));
        if let Some(&normal) = primitive.normals.get(v) {
            out.normals.push(cofactor(linear) * normal);
        }
        if let (Some(&du), Some(&dv)) = (primitive.dpdu.get(v), primitive.dpdv.get(v)) {
            out.dpdu.push(linear * du);
            out.dpdv.push(linear * dv);
        }
    }
    out
}

/// The cofactor matrix of `m`: det(m)·m⁻ᵀ, defined (and finite) even where m is singular. Normals transform by it;
/// their length does not matter (the shaders normalize), their direction stays right for any scale.
fn cofactor(m: Mat3) -> Mat3 {
    Mat3::from_cols(m.y_axis.cross(m.z_axis), m.z_axis.cross(m.x_axis), m.x_axis.cross(m.y_axis))
}

impl Scene {
    /// The skin that deforms instance `instance` (its node's), if any.
    pub fn instance_skin(&self, instance: usize) -> Option<&Skin> {
        let node = self.instances.get(instance)?.node?;
        self.skins.get(self.nodes.get(node)?.skin?)
    }

    /// Whether instance `instance`'s morph weights are animated: its node has a weights channel in the clip and
    /// its mesh has morph targets.
    pub fn has_animated_weights(&self, instance: usize) -> bool {
        let Some(i) = self.instances.get(instance) else { return false };
        let animated = i.node.is_some_and(|node| {
            self.animations.iter().flat_map(|a| &a.channels).any(|c| c.node == node && c.property == Property::Weights)
        });
        animated && self.meshes[i.mesh].primitives.iter().any(|p| p.morph.is_some())
    }

    /// Instances whose vertices move with time (skinned, or with animated morph weights), in scene order: each
    /// gets vertex streams of its own per sample.
    pub fn deformed_instances(&self) -> Vec<usize> {
        (0..self.instances.len()).filter(|&i| self.instance_skin(i).is_some() || self.has_animated_weights(i)).collect()
    }

    /// Instance `instance`'s primitives morphed at time `t`'s weights where the clip animates them (None: the
    /// rest pose), in mesh order: each the primitive morphed (glTF 2.0 §3.7.2.2) and finished as the loader
    /// finishes one, or None where it keeps its loaded attributes (no animated weights, no targets, or weights
    /// that do not morph: not finite, or moving a vertex to infinity).
    pub fn morph_instance(&self, instance: usize, t: Option<f32>) -> Vec<Option<Primitive>> {
        let Some(i) = self.instances.get(instance) else { return Vec::new() };
        let weights = t
            .filter(|_| self.has_animated_weights(instance))
            .and_then(|t| self.animations.iter().find_map(|a| a.weights_at(i.node?, t)));
        let mesh = &self.meshes[i.mesh];
        mesh.primitives
            .iter()
            .map(|p| match (&weights, &p.morph) {
                (Some(w), Some(source)) => super::morph::morphed(source, w).ok(),
                _ => None,
            })
            .collect()
    }

    /// Instance `instance`'s primitives deformed at time `t` (None: the rest pose), given every node's world
    /// transform then (`node_world`): morphed at the clip's weights, then skinned (glTF 2.0 §3.7.2.2 before
    /// §3.7.3). Skinned vertices are in the world, the others in the instance's object space. `None` for an
    /// instance that does not deform. The renderer skins on the GPU (`render::skinning`); this is its twin, and
    /// what the motion pass and the light set deform with.
    pub fn deform_instance(
        &self,
        instance: usize,
        node_world: &[Mat4],
        t: Option<f32>,
    ) -> Option<Vec<DeformedVertices>> {
        let skin = self.instance_skin(instance);
        if skin.is_none() && !self.has_animated_weights(instance) {
            return None;
        }
        let joints = skin.map(|s| s.joint_matrices(node_world));
        let mesh = &self.meshes[self.instances[instance].mesh];
        let morphed = self.morph_instance(instance, t);
        let deformed = mesh.primitives.iter().zip(morphed).map(|(p, morphed)| {
            let p = morphed.as_ref().unwrap_or(p);
            match &joints {
                Some(joints) => skin_vertices(p, joints),
                None => DeformedVertices {
                    positions: p.positions.clone(),
                    normals: p.normals.clone(),
                    dpdu: p.dpdu.clone(),
                    dpdv: p.dpdv.clone(),
                },
            }
        });
        Some(deformed.collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_joint_vertex(w: f32) -> Primitive {
        Primitive {
            positions: vec![Vec3::new(1.0, 2.0, 3.0)],
            normals: vec![Vec3::Y],
            dpdu: vec![Vec3::X],
            dpdv: vec![Vec3::Z],
            indices: vec![0, 0, 0],
            skin_influences: vec![JointInfluences {
                joints: vec![[0, 1, 0, 0]],
                weights: vec![Vec4::new(1.0 - w, w, 0.0, 0.0)],
            }],
            ..Default::default()
        }
    }

    #[test]
    fn identity_joints_leave_every_stream_exactly_as_it_was() {
        let p = two_joint_vertex(0.25);
        let out = skin_vertices(&p, &[Mat4::IDENTITY, Mat4::IDENTITY]);
        assert_eq!(out.positions, p.positions);
        assert_eq!(out.normals, p.normals);
        assert_eq!((out.dpdu, out.dpdv), (p.dpdu, p.dpdv));
    }

    #[test]
    fn weights_blend_the_joint_matrices_linearly() {
        let p = two_joint_vertex(0.25);
        let moved = Mat4::from_translation(Vec3::new(4.0, 0.0, 0.0));
        let out = skin_vertices(&p, &[Mat4::IDENTITY, moved]);
        assert_eq!(out.positions[0], Vec3::new(2.0, 2.0, 3.0));
        // A scale along x alone: tangents along x stretch, the normal (along y) keeps its direction.
        let stretched = Mat4::from_scale(Vec3::new(3.0, 1.0, 1.0));
        let out = skin_vertices(&two_joint_vertex(1.0), &[Mat4::IDENTITY, stretched]);
        assert_eq!(out.dpdu[0], Vec3::new(3.0, 0.0, 0.0));
        assert_eq!(out.normals[0].normalize(), Vec3::Y);
    }

    #[test]
    fn normals_stay_perpendicular_to_the_skinned_tangents_under_shear() {
        let shear =
            Mat4::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.7, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
        let mut p = two_joint_vertex(1.0);
        p.normals = vec![Vec3::Z];
        p.dpdu = vec![Vec3::X];
        p.dpdv = vec![Vec3::Y];
        let out = skin_vertices(&p, &[Mat4::IDENTITY, shear]);
        assert!(out.normals[0].dot(out.dpdu[0]).abs() < 1e-6);
        assert!(out.normals[0].dot(out.dpdv[0]).abs() < 1e-6);
        assert!(out.normals[0].dot(out.dpdu[0].cross(out.dpdv[0])) > 0.0, "the normal keeps its side");
    }
}
