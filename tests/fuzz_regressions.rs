//! Inputs the fuzz targets (`fuzz/`) found or that seed them, kept as regression tests: each must be refused
//! or loaded, never panic.
use std::path::Path;

fn inputs(target: &str) -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions").join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    assert!(!files.is_empty(), "no regression inputs in {}", dir.display());
    files
}

#[test]
fn gltf_loader_regressions_do_not_panic() {
    for path in inputs("gltf_loader") {
        let data = std::fs::read(&path).unwrap();
        let result = std::panic::catch_unwind(|| {
            strata::scene::gltf_import::load_gltf_bytes(&data, Path::new("/nonexistent"), &Default::default())
                .map(|_| ())
        });
        assert!(result.is_ok(), "{} panicked the glTF loader", path.display());
    }
}

#[test]
fn scene_file_regressions_do_not_panic() {
    let base = strata::scene::library::showcase();
    for path in inputs("scene_file") {
        let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
        let result = std::panic::catch_unwind(|| {
            let mut scene = base.clone();
            strata::scene::scene_file::apply_scene_text(Path::new("fuzz.toml"), &text, &mut scene).map(|_| ())
        });
        assert!(result.is_ok(), "{} panicked the scene-file parser", path.display());
    }
}
