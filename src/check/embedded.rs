//! The files `strata check` carries inside the binary (build.rs embeds them): the project's scenes, which its
//! golden cases render and its reports' commands reproduce, and the goldens, so a check runs with nothing beside
//! the binary.
use anyhow::{Context as _, Result};
use std::path::{Path, PathBuf};

include!(concat!(env!("OUT_DIR"), "/check_files.rs"));

/// A golden file's bytes by name, from the embedded copy.
pub fn golden_file(name: &str) -> Option<&'static [u8]> {
    GOLDEN_FILES.iter().find(|(n, _)| *n == name).map(|(_, bytes)| *bytes)
}

/// Writes the embedded scenes into `dir` (created if needed) and returns the path of `name.toml` there.
pub fn write_scene(dir: &Path, name: &str) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (file, bytes) in SCENE_FILES {
        let stem = file.split('.').next().unwrap_or_default();
        if stem == name {
            let path = dir.join(file);
            crate::output::write_atomic(&path, |f| {
                use std::io::Write as _;
                f.write_all(bytes).map_err(Into::into)
            })?;
        }
    }
    let toml = dir.join(format!("{name}.toml"));
    anyhow::ensure!(toml.is_file(), "strata carries no scene named {name}");
    Ok(toml)
}
