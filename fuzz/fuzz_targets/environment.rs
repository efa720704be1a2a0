//! Feeds arbitrary bytes, as a file, to the environment loader (`--environment`, `[environment]`): the first
//! byte chooses the format (even: OpenEXR `.exr`, odd: Radiance `.hdr`), the rest is the file. It may refuse
//! them, never panic, abort, or allocate what a header only claims.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static PATHS: OnceLock<[std::path::PathBuf; 2]> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let Some((&kind, file)) = data.split_first() else { return };
    let paths = PATHS.get_or_init(|| [scratch("environment.exr"), scratch("environment.hdr")]);
    let path = &paths[usize::from(kind & 1)];
    std::fs::write(path, file).expect("write the input");
    let _ = strata::scene::environment::Environment::load(path);
});

/// A file of this process's own in memory-backed storage where there is one.
fn scratch(name: &str) -> std::path::PathBuf {
    let shm = std::path::Path::new("/dev/shm");
    let dir = if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() };
    dir.join(format!("strata-fuzz-{}-{name}", std::process::id()))
}
