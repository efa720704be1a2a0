//! What a run will write, read and delete, decided before any work (docs/architecture.md, "Inputs and
//! outputs"). Paths are compared as files, not as strings: `./out.exr`, `out.exr`, an absolute path, a symlinked
//! directory and a hard link all name the same file. A collision (the checkpoint on the output, a merge's output
//! on one of its parts, two scenes of a batch on one file), a destination that cannot be written (a missing or
//! read-only directory, a directory, a device, a FIFO or a symbolic link where the file would go, a name too long
//! for the file system) is an error naming both paths, before a single sample is rendered.
use anyhow::{bail, Result};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// What a run does with a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Use {
    /// Written (atomically, replacing a regular file that is there).
    Writes,
    /// Read, and left as it is.
    Reads,
    /// Written as the run goes and removed at its end (a checkpoint), or read and then removed (parts with
    /// `--remove-parts`).
    Consumes,
}

/// One file of the plan: what it is called in messages (`-o`, `--exr`, `part`), and where it is.
#[derive(Debug, Clone)]
struct Entry {
    role: String,
    path: PathBuf,
    usage: Use,
}

/// A file's identity: its directory resolved, plus its name; and the device and inode where it exists.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
enum FileKey {
    Path(PathBuf),
    Inode(u64, u64),
}

/// The longest file name Linux file systems take (NAME_MAX).
pub const MAX_FILE_NAME_BYTES: usize = 255;

#[derive(Debug, Default)]
pub struct WritePlan {
    entries: Vec<Entry>,
    /// Directories already resolved (and, for written ones, found writable): a sequence writes many files into one.
    directories: HashMap<PathBuf, PathBuf>,
    writable: HashSet<PathBuf>,
}

impl WritePlan {
    pub fn new() -> Self {
        Self::default()
    }

    /// A file the run writes: its directory must exist and take new files, and nothing but a regular file may
    /// be in its place.
    pub fn writes(&mut self, role: &str, path: &Path) -> Result<()> {
        self.destination(role, path, Use::Writes)
    }

    /// A file the run reads and must not change (an input: a part, `--resume`, an environment).
    pub fn reads(&mut self, role: &str, path: &Path) {
        self.push(role, path, Use::Reads);
    }

    /// A file the run writes as it goes and removes at the end (a checkpoint), checked as a destination.
    pub fn writes_then_removes(&mut self, role: &str, path: &Path) -> Result<()> {
        self.destination(role, path, Use::Consumes)
    }

    /// A file the run reads and then removes (`strata merge --remove-parts`).
    pub fn reads_then_removes(&mut self, role: &str, path: &Path) {
        self.push(role, path, Use::Consumes);
    }

    /// A file the run writes: checked as a destination, then planned.
    fn destination(&mut self, role: &str, path: &Path, usage: Use) -> Result<()> {
        self.check_destination(role, path)?;
        self.push(role, path, usage);
        Ok(())
    }

    fn push(&mut self, role: &str, path: &Path, usage: Use) {
        self.entries.push(Entry { role: role.to_string(), path: path.to_path_buf(), usage });
    }

    /// An error when two entries name one file, unless `allowed` says that pair may share it (a checkpoint
    /// that `--resume` names too). Linear in the number of files.
    pub fn check(&mut self, allowed: &dyn Fn(&str, &str) -> bool) -> Result<()> {
        let mut seen: HashMap<FileKey, usize> = HashMap::new();
        for i in 0..self.entries.len() {
            for key in self.keys(i) {
                match seen.get(&key) {
                    Some(&j) if j != i => {
                        let (a, b) = (&self.entries[j], &self.entries[i]);
                        if allowed(&a.role, &b.role) {
                            continue;
                        }
                        bail!("{}", collision(a, b));
                    }
                    Some(_) => {}
                    None => {
                        seen.insert(key, i);
                    }
                }
            }
        }
        Ok(())
    }

    /// The identities of entry `i`: its resolved path, and its inode when it exists (hard links).
    fn keys(&mut self, i: usize) -> Vec<FileKey> {
        let path = self.entries[i].path.clone();
        let mut keys = Vec::with_capacity(2);
        if let Some(resolved) = self.resolve(&path) {
            keys.push(FileKey::Path(resolved));
        } else {
            keys.push(FileKey::Path(path.clone()));
        }
        // An existing file, links followed: a symlink to the output, or a hard link of it, is the same file.
        if let Ok(meta) = std::fs::metadata(&path) {
            use std::os::unix::fs::MetadataExt as _;
            keys.push(FileKey::Inode(meta.dev(), meta.ino()));
        }
        keys
    }

    /// The path with its directory resolved (symlinks, `..`, relative to absolute); the file itself resolved
    /// too when it is a symbolic link.
    fn resolve(&mut self, path: &Path) -> Option<PathBuf> {
        if let Ok(meta) = std::fs::symlink_metadata(path) {
            if meta.file_type().is_symlink() {
                return std::fs::canonicalize(path).ok();
            }
        }
        let name = path.file_name()?;
        let dir = directory_of(path);
        let resolved = match self.directories.get(&dir) {
            Some(r) => r.clone(),
            None => {
                let r = std::fs::canonicalize(&dir).ok()?;
                self.directories.insert(dir, r.clone());
                r
            }
        };
        Some(resolved.join(name))
    }

    fn check_destination(&mut self, role: &str, path: &Path) -> Result<()> {
        let shown = path.display();
        let Some(name) = path.file_name().filter(|_| !path.as_os_str().as_encoded_bytes().ends_with(b"/")) else {
            bail!("{role} {shown}: not a file name (it ends in .. or /)");
        };
        if name.len() > MAX_FILE_NAME_BYTES {
            bail!("{role} {shown}: the file name is {} bytes, file systems take {MAX_FILE_NAME_BYTES}", name.len());
        }
        let dir = directory_of(path);
        match std::fs::metadata(&dir) {
            Ok(meta) if meta.is_dir() => {}
            Ok(_) => bail!("{role} {shown}: {} is not a directory", dir.display()),
            Err(_) => bail!("{role} {shown}: the directory {} does not exist", dir.display()),
        }
        match std::fs::symlink_metadata(path) {
            Ok(meta) if meta.is_file() => {}
            Ok(meta) if meta.is_dir() => bail!("{role} {shown}: a directory is there; name a file"),
            Ok(meta) if meta.file_type().is_symlink() => bail!(
                "{role} {shown}: a symbolic link is there; strata replaces files, not links (name the file it \
                 points to, or remove the link)"
            ),
            Ok(_) => bail!(
                "{role} {shown}: a device, FIFO or socket is there, not a regular file; strata will not replace it"
            ),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => bail!("{role} {shown}: cannot be checked: {e}"),
        }
        if !self.writable.contains(&dir) {
            probe_writable(&dir)
                .map_err(|e| anyhow::anyhow!("{role} {shown}: cannot write in {}: {e}", dir.display()))?;
            self.writable.insert(dir);
        }
        Ok(())
    }
}

/// The directory a path's file is in (`.` for a bare name).
pub fn directory_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Whether a new file can be made in `dir`: by making one (and removing it), the only test that sees
/// read-only mounts, permissions, ACLs and quotas alike.
fn probe_writable(dir: &Path) -> std::io::Result<()> {
    let probe = crate::output::temporary_name(dir);
    std::fs::OpenOptions::new().write(true).create_new(true).open(&probe)?;
    std::fs::remove_file(&probe)
}

/// The message for two entries on one file, saying what would be lost.
fn collision(a: &Entry, b: &Entry) -> String {
    let both = if a.path == b.path {
        format!("{} is both {} and {}", a.path.display(), a.role, b.role)
    } else {
        format!("{} {} and {} {} are the same file", a.role, a.path.display(), b.role, b.path.display())
    };
    let consequence = match (a.usage, b.usage) {
        (Use::Writes, Use::Writes) => "one would overwrite the other",
        (Use::Reads, _) | (_, Use::Reads) => "the run would overwrite or delete what it reads",
        _ => "the run would delete what it writes",
    };
    format!("{both}: {consequence}; give each its own file")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scratch_dir as scratch;

    fn never(_: &str, _: &str) -> bool {
        false
    }

    #[test]
    fn spellings_of_one_file_collide() {
        let dir = scratch("spellings");
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("out.exr"), b"x").unwrap();
        std::fs::hard_link(dir.join("out.exr"), dir.join("hard.exr")).unwrap();
        std::os::unix::fs::symlink(&dir, dir.join("sub/up")).unwrap();
        for other in
            [dir.join("./out.exr"), dir.join("sub/../out.exr"), dir.join("sub/up/out.exr"), dir.join("hard.exr")]
        {
            let mut plan = WritePlan::new();
            plan.writes("-o", &dir.join("out.exr")).unwrap();
            plan.writes_then_removes("--checkpoint", &other).unwrap();
            let err = plan.check(&never).unwrap_err().to_string();
            // As two spellings ("-o X and --checkpoint Y are the same file"), or one ("X is both -o and ...").
            assert!(
                (err.contains("same file") || err.contains(" is both ")) && err.contains("--checkpoint"),
                "{other:?}: {err}"
            );
        }
        let mut plan = WritePlan::new();
        plan.writes("-o", &dir.join("out.exr")).unwrap();
        plan.writes("--exr", &dir.join("other.exr")).unwrap();
        plan.check(&never).unwrap();
    }

    #[test]
    fn destinations_that_cannot_take_a_file_are_refused() {
        let dir = scratch("destinations");
        let mut plan = WritePlan::new();
        let err = |plan: &mut WritePlan, p: &Path| plan.writes("-o", p).unwrap_err().to_string();
        assert!(err(&mut plan, &dir.join("none/out.png")).contains("does not exist"));
        std::fs::create_dir_all(dir.join("d.png")).unwrap();
        assert!(err(&mut plan, &dir.join("d.png")).contains("a directory is there"));
        std::os::unix::fs::symlink("/etc/hostname", dir.join("l.png")).unwrap();
        assert!(err(&mut plan, &dir.join("l.png")).contains("symbolic link"));
        assert!(err(&mut plan, Path::new("/dev/null")).contains("device, FIFO or socket"));
        assert!(err(&mut plan, &dir.join("new.exr/")).contains("ends in .. or /"));
        let long = dir.join(format!("{}.png", "n".repeat(256)));
        assert!(err(&mut plan, &long).contains("file systems take 255"));
        plan.writes("-o", &dir.join(format!("{}.png", "n".repeat(251)))).unwrap();
    }
}
