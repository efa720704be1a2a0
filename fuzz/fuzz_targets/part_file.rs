//! Feeds arbitrary bytes, as a file, to the part reader (`strata merge`, `--resume`, checkpoints). It may refuse
//! them, never panic, abort, or allocate what a header only claims (libFuzzer's malloc limit catches that).
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

static PATH: OnceLock<std::path::PathBuf> = OnceLock::new();

fuzz_target!(|data: &[u8]| {
    let path = PATH.get_or_init(|| scratch("part.exr"));
    std::fs::write(path, data).expect("write the input");
    let _ = strata::partial::file::read_part(path);
});

/// A file of this process's own in memory-backed storage where there is one.
fn scratch(name: &str) -> std::path::PathBuf {
    let shm = std::path::Path::new("/dev/shm");
    let dir = if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() };
    dir.join(format!("strata-fuzz-{}-{name}", std::process::id()))
}
