//! Feeds arbitrary bytes to the glTF/GLB loader. It may refuse them, never panic or hang.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // An empty, fixed directory: relative URIs resolve to nothing, so the loader sees only these bytes.
    let base = std::path::Path::new("/nonexistent-strata-fuzz-dir");
    let _ = strata::scene::gltf_import::load_gltf_bytes(data, base, &Default::default());
});
