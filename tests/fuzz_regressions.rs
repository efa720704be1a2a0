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

/// A file of this test's own holding `bytes`, named `name`.
fn as_file(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("strata-fuzz-regressions-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn part_file_regressions_do_not_panic() {
    let mut read = 0;
    for path in inputs("part_file") {
        let file = as_file("part.exr", &std::fs::read(&path).unwrap());
        let result = std::panic::catch_unwind(|| strata::partial::file::read_part(&file));
        match result {
            Err(_) => panic!("{} panicked the part reader", path.display()),
            Ok(Ok(_)) => read += 1,
            Ok(Err(e)) => {
                assert!(format!("{e:#}").contains("part.exr"), "{}: the error names no file: {e:#}", path.display())
            }
        }
    }
    assert!(read >= 1, "the valid seed part no longer reads");
}

#[test]
fn environment_regressions_do_not_panic() {
    let mut read = 0;
    for path in inputs("environment") {
        let data = std::fs::read(&path).unwrap();
        let Some((&kind, bytes)) = data.split_first() else { continue };
        // As the fuzz target: the first byte chooses the format.
        let file = as_file(if kind & 1 == 0 { "environment.exr" } else { "environment.hdr" }, bytes);
        match std::panic::catch_unwind(|| strata::scene::environment::Environment::load(&file)) {
            Err(_) => panic!("{} panicked the environment loader", path.display()),
            Ok(Ok(_)) => read += 1,
            Ok(Err(e)) => {
                assert!(format!("{e:#}").contains("environment."), "{}: the error names no file: {e:#}", path.display())
            }
        }
    }
    assert!(read >= 2, "the valid seed environments no longer load");
}
