//! Resolving glTF URIs (buffers and images) under a safety policy: `data:` URIs and relative paths that stay
//! inside the glTF file's directory are allowed; absolute paths, `..` escapes and network URIs are refused unless
//! the user passes an explicit option (`--allow-any-uri`).
use anyhow::{anyhow, bail, Context as _, Result};
use base64::Engine as _;
use std::path::{Component, Path, PathBuf};

/// How far a glTF file may reach for its buffers and images.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum UriPolicy {
    /// `data:` URIs and relative paths inside the glTF's directory.
    #[default]
    InsideDirectory,
    /// Any local path (absolute paths and `..` too). Network URIs are never fetched.
    AnyLocalPath,
}

/// The bytes behind `uri`, as seen from a glTF file in `base_dir`.
pub fn read_uri(uri: &str, base_dir: &Path, policy: UriPolicy) -> Result<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        return decode_data_uri(rest);
    }
    if let Some((scheme, _)) = uri.split_once("://") {
        bail!("URI \"{uri}\": {scheme}:// URIs are not fetched; strata reads only local files");
    }
    let decoded = percent_decode(uri)?;
    let relative = Path::new(&decoded);
    if policy == UriPolicy::InsideDirectory {
        if relative.is_absolute() || decoded.starts_with('/') || decoded.starts_with('\\') {
            bail!("URI \"{uri}\": absolute paths are refused (pass --allow-any-uri to allow them)");
        }
        if relative.components().any(|c| matches!(c, Component::ParentDir | Component::Prefix(_))) {
            bail!(
                "URI \"{uri}\": paths that leave the glTF's directory are refused (pass --allow-any-uri to allow them)"
            );
        }
    }
    let path: PathBuf = if relative.is_absolute() { relative.to_path_buf() } else { base_dir.join(relative) };
    std::fs::read(&path).with_context(|| format!("URI \"{uri}\": cannot read {}", path.display()))
}

fn decode_data_uri(rest: &str) -> Result<Vec<u8>> {
    let (header, payload) = rest.split_once(',').ok_or_else(|| anyhow!("data: URI has no ',' before its data"))?;
    if header.split(';').any(|p| p == "base64") {
        base64::engine::general_purpose::STANDARD
            .decode(payload.trim())
            .map_err(|e| anyhow!("data: URI is not valid base64: {e}"))
    } else {
        Ok(percent_decode(payload)?.into_bytes())
    }
}

/// glTF URIs are RFC 3986: `%20` and friends must be decoded to find the file.
fn percent_decode(text: &str) -> Result<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = text.get(i + 1..i + 3).ok_or_else(|| anyhow!("URI \"{text}\": truncated %-escape"))?;
            out.push(u8::from_str_radix(hex, 16).map_err(|_| anyhow!("URI \"{text}\": bad %-escape %{hex}"))?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| anyhow!("URI \"{text}\" is not UTF-8 after %-decoding"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_uris_decode() {
        assert_eq!(
            read_uri("data:application/octet-stream;base64,AAEC", Path::new("."), UriPolicy::default()).unwrap(),
            [0, 1, 2]
        );
        assert!(read_uri("data:application/octet-stream;base64,@@@", Path::new("."), UriPolicy::default()).is_err());
    }

    #[test]
    fn escapes_and_network_uris_are_refused() {
        let dir = Path::new("/tmp");
        for uri in ["../secret.bin", "a/../../b.bin", "/etc/passwd", "https://example.invalid/x.bin", "%2E%2E/x.bin"] {
            let err = read_uri(uri, dir, UriPolicy::default()).unwrap_err().to_string();
            assert!(err.contains("refused") || err.contains("not fetched"), "{uri}: {err}");
        }
        let err = read_uri("https://example.invalid/x.bin", dir, UriPolicy::AnyLocalPath).unwrap_err().to_string();
        assert!(err.contains("not fetched"), "{err}");
    }
}
