//! The shared glTF sample models (`tests/data/gltf-samples`, a copy of the team's shared samples; see its README for the counts and sources) load with
//! the expected counts, their transforms and animations come out as the file says, and textures keep their
//! orientation.
use glam::{Mat4, Quat, Vec3};
use std::path::{Path, PathBuf};
use strata::scene::Scene;

fn samples_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf-samples");
    // Absent samples are a failure, never a skip: these checks would pass by not running.
    assert!(
        dir.is_dir(),
        "the shared glTF samples are missing at {}: they ship in the repository under tests/data/gltf-samples",
        dir.display()
    );
    dir
}

fn load(name: &str) -> Scene {
    let path = samples_dir().join(name);
    strata::load_scene(&path).unwrap_or_else(|e| panic!("{name}: {e:#}"))
}

#[test]
fn every_sample_loads_with_the_expected_counts() {
    // (file, triangles, animations, cameras, materials, textures, nodes, meshes, primitives) from the README.
    type Row = (&'static str, usize, usize, usize, usize, usize, usize, usize, usize);
    let table: [Row; 11] = [
        ("TriangleWithoutIndices.gltf", 1, 0, 0, 0, 0, 1, 1, 1),
        ("Triangle.gltf", 1, 0, 0, 0, 0, 1, 1, 1),
        ("SimpleMeshes.gltf", 2, 0, 0, 0, 0, 2, 1, 1),
        ("Cameras.gltf", 2, 0, 2, 0, 0, 3, 1, 1),
        ("Box.gltf", 12, 0, 0, 1, 0, 2, 1, 1),
        ("BoxTextured.gltf", 12, 0, 0, 1, 1, 2, 1, 1),
        ("BoxVertexColors.gltf", 12, 0, 0, 0, 0, 1, 1, 1),
        ("AnimatedTriangle.gltf", 1, 1, 0, 0, 0, 1, 1, 1),
        ("BoxAnimated.gltf", 254, 1, 0, 2, 0, 4, 2, 2),
        ("TextureCoordinateTest.gltf", 10, 0, 0, 5, 1, 5, 5, 5),
        ("OrientationTest.gltf", 524, 0, 0, 7, 0, 13, 13, 13),
    ];
    for (file, tris, anims, cams, mats, texs, nodes, meshes, prims) in table {
        let s = load(file);
        let primitives: usize = s.meshes.iter().map(|m| m.primitives.len()).sum();
        assert_eq!(
            (s.triangle_count(), s.animations.len(), s.cameras.len(), s.materials.len(), s.textures.len()),
            (tris, anims, cams, mats, texs),
            "{file}: (triangles, animations, cameras, materials, textures)"
        );
        assert_eq!(
            (s.nodes.len(), s.meshes.len(), primitives),
            (nodes, meshes, prims),
            "{file}: (nodes, meshes, primitives)"
        );
        assert!(s.warnings.is_empty(), "{file}: {:?}", s.warnings);
        for m in &s.meshes {
            for p in &m.primitives {
                assert!(
                    p.positions.iter().chain(&p.normals).chain(&p.dpdu).chain(&p.dpdv).all(|v| v.is_finite()),
                    "{file}"
                );
            }
        }
    }
}

#[test]
fn cameras_sample_has_both_projections_where_the_readme_says() {
    let s = load("Cameras.gltf");
    use strata::scene::Projection;
    assert!(matches!(s.cameras[0].projection, Projection::Perspective { yfov, znear, zfar: Some(zfar) }
        if (yfov - 0.7).abs() < 1e-6 && (znear - 0.01).abs() < 1e-6 && (zfar - 100.0).abs() < 1e-4));
    assert!(
        matches!(s.cameras[1].projection, Projection::Orthographic { xmag, ymag, .. } if xmag == 1.0 && ymag == 1.0)
    );
    for c in &s.cameras {
        let eye = c.world_from_camera.transform_point3(Vec3::ZERO);
        assert!((eye - Vec3::new(0.5, 0.5, 3.0)).length() < 1e-5, "{}: eye {eye}", c.name);
    }
    assert_eq!(s.camera.as_ref().unwrap().name, s.cameras[0].name);
}

#[test]
fn simple_meshes_places_one_mesh_twice() {
    let s = load("SimpleMeshes.gltf");
    assert_eq!(s.instances.len(), 2);
    assert_eq!(s.instances[0].mesh, s.instances[1].mesh);
    let offset =
        s.instances[1].world_from_object.w_axis.truncate() - s.instances[0].world_from_object.w_axis.truncate();
    assert!((offset - Vec3::X).length() < 1e-6, "{offset}");
}

/// The arrow's tip: its vertex farthest from the arrow node's origin, in world space.
fn arrow_tip(s: &Scene, arrow: &str) -> Vec3 {
    let instance = s.instances.iter().find(|i| i.name == arrow).unwrap();
    let mesh = &s.meshes[instance.mesh];
    let tip = mesh.primitives[0].positions.iter().copied().max_by(|a, b| a.length().total_cmp(&b.length())).unwrap();
    instance.world_from_object.transform_point3(tip)
}

fn target_bounds(s: &Scene, target: &str) -> (Vec3, Vec3) {
    let instance = s.instances.iter().find(|i| i.name == target).unwrap();
    let positions = &s.meshes[instance.mesh].primitives[0].positions;
    positions
        .iter()
        .map(|&p| instance.world_from_object.transform_point3(p))
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

#[test]
fn orientation_test_arrows_point_at_their_targets() {
    let s = load("OrientationTest.gltf");
    for axis in ["X1", "X2", "Y1", "Y2", "Z1", "Z2"] {
        let tip = arrow_tip(&s, &format!("Arrow{axis}"));
        let (lo, hi) = target_bounds(&s, &format!("Target{axis}"));
        let centre = (lo + hi) * 0.5;
        let reach = (hi - lo).length() * 0.5;
        // The tip lands on (inside, or touching) the target's box; a transposed matrix or a wrong quaternion
        // convention sends it metres away.
        let distance = (tip - centre).length();
        assert!(
            distance <= reach + 0.05,
            "Arrow{axis}: tip {tip} is {distance} from target centre {centre} (radius {reach})"
        );
        for other in ["X1", "X2", "Y1", "Y2", "Z1", "Z2"].iter().filter(|o| **o != axis) {
            let (olo, ohi) = target_bounds(&s, &format!("Target{other}"));
            assert!((tip - (olo + ohi) * 0.5).length() > reach, "Arrow{axis} also reaches Target{other}");
        }
    }
}

fn close(a: Mat4, b: Mat4) -> bool {
    a.abs_diff_eq(b, 1e-4)
}

#[test]
fn animated_triangle_rotation_matches_hand_computed_slerp() {
    let s = load("AnimatedTriangle.gltf");
    // Keys at 0, .25, .5, .75, 1 s: rotation about Z by 0°, 90°, 180°, 270°, 360° (quaternions in the file).
    let channel = &s.animations[0].channels[0];
    assert_eq!(channel.times, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    for (t, degrees) in [(0.0f32, 0.0f32), (0.125, 45.0), (0.25, 90.0), (0.6, 216.0), (1.0, 360.0), (7.0, 360.0)] {
        let want = Mat4::from_quat(Quat::from_rotation_z(degrees.to_radians()));
        let got = s.instance_transforms_at(t)[0];
        assert!(close(got, want), "t = {t}: got {got}, want rotation {degrees}° about Z");
    }
}

#[test]
fn box_animated_parent_translation_and_child_rotation_compose() {
    let s = load("BoxAnimated.gltf");
    // The README: translation of the parent (4 keys, 0–3.708 s), rotation of the inner box (2 keys, 1.25–2.5 s).
    let animation = &s.animations[0];
    let translation = animation.channels.iter().find(|c| c.property == strata::scene::Property::Translation).unwrap();
    let rotation = animation.channels.iter().find(|c| c.property == strata::scene::Property::Rotation).unwrap();
    for t in [0.0f32, 0.5, 1.3, 2.0, 3.0, 3.708, 5.0] {
        let world = s.node_world_transforms(Some(t));
        // Hand computation: lerp the parent's translation keys, slerp the child's rotation keys, compose.
        let k = translation.times.partition_point(|&x| x <= t).clamp(1, translation.times.len() - 1) - 1;
        let (t0, t1) = (translation.times[k], translation.times[k + 1]);
        let f = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
        let want_translation = translation.values[k].truncate().lerp(translation.values[k + 1].truncate(), f);
        let parent = translation.node;
        let got_translation = world[parent].w_axis.truncate();
        let grand = s.nodes[parent].parent.map(|p| world[p]).unwrap_or(Mat4::IDENTITY);
        let want_parent_world = grand * Mat4::from_translation(want_translation);
        assert!(
            (got_translation - want_parent_world.w_axis.truncate()).length() < 1e-4,
            "t = {t}: parent at {got_translation}, want {}",
            want_parent_world.w_axis.truncate()
        );
        let (r0, r1) = (rotation.times[0], rotation.times[1]);
        let g = ((t - r0) / (r1 - r0)).clamp(0.0, 1.0);
        let q0 = Quat::from_vec4(rotation.values[0]).normalize();
        let q1 = Quat::from_vec4(rotation.values[1]).normalize();
        let want_q = q0.slerp(q1, g);
        let child = rotation.node;
        let (_, got_q, _) = world[child].to_scale_rotation_translation();
        let (_, parent_q, _) = world[s.nodes[child].parent.unwrap()].to_scale_rotation_translation();
        let want_world_q = parent_q * want_q;
        assert!(got_q.dot(want_world_q).abs() > 1.0 - 1e-5, "t = {t}: child rotation {got_q} want {want_world_q}");
    }
}

#[test]
fn texture_samples_keep_uvs_and_colour_spaces() {
    let s = load("BoxTextured.gltf");
    let m = &s.materials[0];
    let t = m.base_color_texture.expect("BoxTextured has a base colour texture");
    assert!(s.textures[t.texture].srgb, "a base colour texture is sRGB");
    let image = &s.images[s.textures[t.texture].image];
    assert_eq!((image.width, image.height), (256, 256));
    assert_eq!(s.textures[t.texture].sampler.wrap_s, strata::scene::Wrap::Repeat);
    // TEXCOORD_0 runs from 0 to 6 in U (the README): it relies on REPEAT.
    let max_u = s.meshes[0].primitives[0].uvs.iter().map(|uv| uv.x).fold(0.0, f32::max);
    assert!((max_u - 6.0).abs() < 1e-4, "max u {max_u}");
    let v = load("BoxVertexColors.gltf");
    assert_eq!(v.meshes[0].primitives[0].colors.len(), v.meshes[0].primitives[0].positions.len());
}
