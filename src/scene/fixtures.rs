//! Scenes built in code for benchmarks and tests where no file of the project has what they need.
use super::animation::{Animation, Channel, Interpolation, Property};
use super::library::place;
use super::skin::{JointInfluences, Skin};
use super::{Node, NodeTransform, Primitive, Scene};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

/// A tube of radius 0.2 m from y = 0 to 2 with `rings` × `segments` quads (2·rings·segments triangles), skinned to two
/// joints: the base (at the origin) and the elbow (at y = 1), each vertex weighted by its height (y / 2 on the
/// elbow). The elbow turns by 90° about z over the first second: a bending arm, for the cost of skinning.
pub fn skinned_tube(rings: u32, segments: u32) -> Scene {
    let mut p = Primitive::default();
    let mut weights = Vec::new();
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        for s in 0..=segments {
            let u = s as f32 / segments as f32;
            let (sin, cos) = (u * std::f32::consts::TAU).sin_cos();
            p.positions.push(Vec3::new(0.2 * cos, 2.0 * v, 0.2 * sin));
            p.normals.push(Vec3::new(cos, 0.0, sin));
            p.uvs.push(Vec2::new(u, v));
            weights.push(Vec4::new(1.0 - v, v, 0.0, 0.0));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, r * row + s + 1);
            let (c, d) = (a + row, b + row);
            p.indices.extend([a, c, b, b, c, d]);
        }
    }
    let joints = vec![[0u16, 1, 0, 0]; p.positions.len()];
    p.skin_influences = vec![JointInfluences { joints, weights }];
    let mut scene = Scene::default();
    let mesh_node = place(&mut scene, "skinned tube", p, Mat4::IDENTITY);
    scene.nodes[mesh_node].skin = Some(0);
    scene.instances[0].world_from_object = Mat4::IDENTITY;
    let (base, elbow) = (scene.nodes.len(), scene.nodes.len() + 1);
    let joint = |name: &str, parent: Option<usize>, children: Vec<usize>, y: f32| Node {
        name: name.into(),
        parent,
        children,
        transform: NodeTransform::Trs { translation: Vec3::Y * y, rotation: Quat::IDENTITY, scale: Vec3::ONE },
        mesh: None,
        camera: None,
        light: None,
        category: None,
        skin: None,
    };
    scene.nodes.push(joint("base", None, vec![elbow], 0.0));
    scene.nodes.push(joint("elbow", Some(base), Vec::new(), 1.0));
    scene.roots.push(base);
    scene.skins.push(Skin {
        name: "arm".into(),
        joints: vec![base, elbow],
        inverse_bind: vec![Mat4::IDENTITY, Mat4::from_translation(-Vec3::Y)],
    });
    let turn = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let keys = vec![Vec4::from(Quat::IDENTITY), Vec4::from(turn)];
    let channel = Channel::new(elbow, Property::Rotation, Interpolation::Linear, vec![0.0, 1.0], keys)
        .expect("two increasing keys with one value each");
    scene.animations.push(Animation { name: "bend".into(), channels: vec![channel] });
    scene
}

/// `scene` with every deformed instance frozen at time `t`: its mesh holds the deformed vertices, its skin and the
/// clip's weights are gone. The same triangles as the animated scene at `t`, for the cost of deformation by
/// difference.
pub fn frozen_at(scene: &Scene, t: f32) -> Scene {
    let mut frozen = scene.clone();
    let node_world = scene.node_world_transforms(Some(t));
    for instance in scene.deformed_instances() {
        let Some(deformed) = scene.deform_instance(instance, &node_world, Some(t)) else { continue };
        let mesh = scene.instances[instance].mesh;
        let skinned = scene.instance_skin(instance).is_some();
        for (p, d) in frozen.meshes[mesh].primitives.iter_mut().zip(deformed) {
            (p.positions, p.normals, p.dpdu, p.dpdv) = (d.positions, d.normals, d.dpdu, d.dpdv);
            p.morph = None;
        }
        if let (true, Some(node)) = (skinned, scene.instances[instance].node) {
            // Skinned vertices are in the world already.
            frozen.nodes[node].skin = None;
            frozen.nodes[node].transform = NodeTransform::Matrix(Mat4::IDENTITY);
            frozen.instances[instance].world_from_object = Mat4::IDENTITY;
        }
    }
    for animation in &mut frozen.animations {
        animation.channels.retain(|c| c.property != Property::Weights);
    }
    frozen
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tube_bends_at_its_elbow_and_freezes_as_it_was() {
        let tube = skinned_tube(4, 8);
        assert_eq!(tube.triangle_count(), 64);
        let at = |t: f32| tube.deform_instance(0, &tube.node_world_transforms(Some(t)), Some(t)).unwrap();
        // The tip ring rides the elbow alone: (0.2, 2, 0) turns 90° about z around (0, 1, 0) to (−1, 1.2, 0).
        let tip = at(1.0)[0].positions[(4 * 9) as usize];
        assert!((tip - Vec3::new(-1.0, 1.2, 0.0)).length() < 1e-5, "{tip}");
        // At rest the joints undo their bind pose: the tube as built.
        assert_eq!(at(0.0)[0].positions, tube.meshes[0].primitives[0].positions);
        let frozen = frozen_at(&tube, 1.0);
        assert!(frozen.deformed_instances().is_empty());
        assert_eq!(frozen.meshes[0].primitives[0].positions, at(1.0)[0].positions);
        assert_eq!(frozen.instance_transforms_at(0.3)[0], Mat4::IDENTITY);
    }
}
