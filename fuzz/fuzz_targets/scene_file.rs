//! Feeds arbitrary text to the scene-file parser, applied to the showcase scene. It may refuse it, never panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static SCENE: OnceLock<strata::scene::Scene> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let base = SCENE.get_or_init(strata::scene::library::showcase);
    let mut scene = base.clone();
    let _ = strata::scene::scene_file::apply_scene_text(std::path::Path::new("fuzz.toml"), text, &mut scene);
});
