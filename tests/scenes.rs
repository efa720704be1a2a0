//! The committed scenes in `scenes/` are exactly what the generator (`strata::scene::library`) writes, and they
//! load back into the same geometry.
use std::path::Path;

#[test]
fn committed_scenes_match_the_generator() {
    let scenes_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for (name, scene) in strata::scene::library::all() {
        let bin_name = format!("{name}.bin");
        let (json, bin) = strata::scene::gltf_export::to_gltf(&scene, &bin_name).unwrap();
        let committed_json = std::fs::read_to_string(scenes_dir.join(format!("{name}.gltf")))
            .unwrap_or_else(|e| panic!("scenes/{name}.gltf: {e}; run `cargo run --example make_scenes`"));
        let committed_bin = std::fs::read(scenes_dir.join(&bin_name)).unwrap();
        assert!(
            committed_json == json && committed_bin == bin,
            "scenes/{name}.gltf differs from the generator; run `cargo run --example make_scenes` and commit"
        );
    }
}

#[test]
fn generated_scenes_load_back_unchanged() {
    let scenes_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for (name, scene) in strata::scene::library::all() {
        let loaded = strata::load_scene(&scenes_dir.join(format!("{name}.gltf"))).unwrap();
        assert_eq!(loaded.meshes.len(), scene.meshes.len(), "{name}");
        assert_eq!(loaded.instances.len(), scene.instances.len(), "{name}");
        assert_eq!(loaded.triangle_count(), scene.triangle_count(), "{name}");
        for (a, b) in loaded.instances.iter().zip(&scene.instances) {
            assert!(a.world_from_object.abs_diff_eq(b.world_from_object, 1e-6), "{name}: {}", a.name);
        }
        for (a, b) in loaded.meshes.iter().zip(&scene.meshes) {
            assert_eq!(a.primitives[0].positions, b.primitives[0].positions, "{name}: {}", a.name);
            assert_eq!(a.primitives[0].uvs, b.primitives[0].uvs, "{name}: {}", a.name);
        }
        let (lc, sc) = (loaded.camera.unwrap(), scene.camera.clone().unwrap());
        assert!(lc.world_from_camera.abs_diff_eq(sc.world_from_camera, 1e-5), "{name}: camera");
    }
}
