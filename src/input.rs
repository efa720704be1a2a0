//! Reading files that strata did not write itself (parts, checkpoints, environments, expectations): only
//! regular files, with bounded reads, and memory for what a header claims asked for before it is used, so that
//! a directory, a FIFO, `/dev/zero`, a symlink loop or a 300-byte file claiming a 100000×100000 image ends in
//! an error naming the file instead of a hang or an abort (docs/architecture.md, "Inputs and outputs").
use anyhow::{bail, Context as _, Result};
use std::io::Read as _;
use std::path::Path;

/// What kind of thing is at a path that is not a regular file, in words.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_symlink() {
        "a symbolic link"
    } else {
        "not a regular file"
    }
}

/// Why `path` cannot be opened for reading, in words (no file name: callers add it).
fn open_error(e: &std::io::Error) -> String {
    match (e.kind(), e.raw_os_error()) {
        (std::io::ErrorKind::NotFound, _) => "no such file".into(),
        (_, Some(libc::ELOOP)) => "a loop of symbolic links".into(),
        (std::io::ErrorKind::PermissionDenied, _) => "cannot be read (permission denied)".into(),
        _ => format!("cannot be opened: {e}"),
    }
}

/// Opens `path` for reading if it is a regular file (symbolic links followed); the error says what it is
/// otherwise. Opened without blocking, so a FIFO never hangs the open.
pub fn open_regular(path: &Path) -> Result<(std::fs::File, u64)> {
    use std::os::unix::fs::OpenOptionsExt as _;
    let name = path.display();
    // The type first: opening a FIFO for reading blocks until a writer comes, a directory opens "fine".
    let meta = std::fs::metadata(path).map_err(|e| anyhow::anyhow!("{name}: {}", open_error(&e)))?;
    if !meta.is_file() {
        bail!("{name}: {}, not a file", kind_of(&meta));
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| anyhow::anyhow!("{name}: {}", open_error(&e)))?;
    // Checked again on what was opened, in case the path changed in between.
    let meta = file.metadata().with_context(|| format!("{name}: cannot be read"))?;
    if !meta.is_file() {
        bail!("{name}: {}, not a file", kind_of(&meta));
    }
    Ok((file, meta.len()))
}

/// The whole of a regular file of at most `limit` bytes.
pub fn read_bounded(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>> {
    let (file, len) = open_regular(path)?;
    if len > limit {
        bail!("{}: {len} bytes is more than {what} may hold ({limit} bytes at most)", path.display());
    }
    let mut bytes = Vec::with_capacity(len as usize);
    // The length can grow while reading: read one byte past the limit to see it.
    file.take(limit + 1).read_to_end(&mut bytes).with_context(|| format!("{}: cannot be read", path.display()))?;
    if bytes.len() as u64 > limit {
        bail!("{}: more than {what} may hold ({limit} bytes at most)", path.display());
    }
    Ok(bytes)
}

/// A text file of at most `limit` bytes, as UTF-8.
pub fn read_text_bounded(path: &Path, limit: u64, what: &str) -> Result<String> {
    let bytes = read_bounded(path, limit, what)?;
    String::from_utf8(bytes)
        .map_err(|e| anyhow::anyhow!("{}: not UTF-8 text (byte {})", path.display(), e.utf8_error().valid_up_to()))
}

/// An error unless `bytes` of memory can be had now: asked for (and given back) before a decoder that would
/// abort the process on a failed allocation is trusted with a size read from a file.
pub fn ensure_memory(bytes: u64, path: &Path, what: &str) -> Result<()> {
    let mut probe: Vec<u8> = Vec::new();
    let fits = usize::try_from(bytes).ok().is_some_and(|n| probe.try_reserve_exact(n).is_ok());
    if !fits {
        bail!("{}: {what} needs {} of memory, more than this process can have", path.display(), human_bytes(bytes));
    }
    Ok(())
}

/// The first layer's header of an OpenEXR file, checked before any pixel is read: a flat (not deep) image of
/// at most `max_side` pixels a side, whose chunk offset table fits in the file (a file of a few hundred bytes
/// cannot hold a 100000×100000 image, whatever its header says). Returns the open file, rewound, with its header.
pub fn exr_header(path: &Path, max_side: usize, what: &str) -> Result<(std::fs::File, exr::meta::header::Header)> {
    use std::io::Seek as _;
    let name = path.display();
    let (mut file, len) = open_regular(path)?;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(&mut file), false)
        .map_err(|e| anyhow::anyhow!("{name}: not an OpenEXR file: {e}"))?;
    let Some(header) = meta.headers.first() else { bail!("{name}: an OpenEXR file without a layer") };
    if header.deep {
        bail!("{name}: a deep OpenEXR image; {what} is a flat one");
    }
    let (w, h) = (header.layer_size.0, header.layer_size.1);
    if w == 0 || h == 0 || w > max_side || h > max_side {
        bail!("{name}: its header claims a {w}x{h} image; {what} is at most {max_side}x{max_side} pixels");
    }
    // Each chunk has an 8-byte entry in the offset table that follows the headers.
    let table: u64 = meta.headers.iter().map(|h| h.chunk_count as u64 * 8).sum();
    if table > len {
        bail!(
            "{name}: its header claims a {w}x{h} image in {} chunks, but the file holds only {len} bytes (cut short, \
             or not what the header says)",
            meta.headers.iter().map(|h| h.chunk_count).sum::<usize>()
        );
    }
    let bytes_per_pixel: u64 = header.channels.list.iter().map(|c| c.sample_type.bytes_per_sample() as u64).sum();
    check_packing(path, w as u64 * h as u64 * bytes_per_pixel, len)?;
    let header = header.clone();
    file.rewind().with_context(|| format!("{name}: cannot be read"))?;
    Ok((file, header))
}

/// The most uncompressed bytes of pixels an image file may claim per byte it holds. Deflate (OpenEXR's ZIP and
/// PXR24) packs at most about 1032:1, RLE 64:1, PIZ and B44 less, Radiance's run-length scanlines about 190:1:
/// a file claiming more is cut short or lying, and is refused before anything is allocated for it.
pub const MAX_PACKING: u64 = 4096;

/// An error when a header claims more pixel bytes than `len` bytes of file can hold ([`MAX_PACKING`]).
pub fn check_packing(path: &Path, claimed: u64, len: u64) -> Result<()> {
    if claimed > len.saturating_mul(MAX_PACKING) {
        bail!(
            "{}: its header claims {} of pixels, but the file holds only {len} bytes (no compression packs more \
             than {MAX_PACKING}:1; the file is cut short or not what its header says)",
            path.display(),
            human_bytes(claimed)
        );
    }
    Ok(())
}

/// `1.5 GiB`, `320 MiB`, `12 KiB`, `7 bytes`.
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [(&str, u64); 4] = [("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    for (unit, size) in UNITS {
        if bytes >= size {
            return format!("{:.1} {unit}", bytes as f64 / size as f64);
        }
    }
    format!("{bytes} bytes")
}

/// A long text shortened for a message: its start, and how long it was.
pub fn excerpt(text: &str, keep: usize) -> String {
    if text.chars().count() <= keep {
        return text.to_string();
    }
    let start: String = text.chars().take(keep).collect();
    format!("{start}… ({} bytes in all)", text.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scratch_dir as scratch;

    #[test]
    fn what_is_not_a_regular_file_is_named() {
        let dir = scratch("kinds");
        let message = |p: &Path| format!("{:#}", open_regular(p).unwrap_err());
        assert!(message(&dir.join("none")).contains("no such file"));
        assert!(message(&dir).contains("a directory"), "{}", message(&dir));
        assert!(message(Path::new("/dev/zero")).contains("a device"));
        let fifo = dir.join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        assert!(message(&fifo).contains("a FIFO"), "{}", message(&fifo));
        let (a, b) = (dir.join("a"), dir.join("b"));
        std::os::unix::fs::symlink(&b, &a).unwrap();
        std::os::unix::fs::symlink(&a, &b).unwrap();
        assert!(message(&a).contains("a loop of symbolic links"), "{}", message(&a));
    }

    #[test]
    fn reads_stop_at_the_limit() {
        let dir = scratch("bounded");
        let path = dir.join("f.txt");
        std::fs::write(&path, "0123456789").unwrap();
        assert_eq!(read_bounded(&path, 10, "a test file").unwrap().len(), 10);
        let err = format!("{:#}", read_bounded(&path, 9, "a test file").unwrap_err());
        assert!(err.contains("f.txt") && err.contains("9 bytes at most"), "{err}");
    }

    #[test]
    fn an_impossible_amount_of_memory_is_an_error() {
        assert!(ensure_memory(1 << 20, Path::new("x"), "it").is_ok());
        let err = format!("{:#}", ensure_memory(u64::MAX / 2, Path::new("big.exr"), "its image").unwrap_err());
        assert!(err.contains("big.exr") && err.contains("of memory"), "{err}");
    }

    #[test]
    fn excerpts_say_how_long_the_text_was() {
        assert_eq!(excerpt("short", 10), "short");
        let long = "a".repeat(1000);
        assert_eq!(excerpt(&long, 3), "aaa… (1000 bytes in all)");
    }
}
