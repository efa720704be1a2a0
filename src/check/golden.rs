//! Goldens: the committed references of the golden, AOV and canary cases, and the two tiers that compare a render
//! with them.
//!
//! A golden is a file per case in the goldens directory (`golden-cornell.png`, `aov-cornell-normal.exr`) and an
//! entry in its `goldens.toml`: the device that made it, the perceptual thresholds, and the hashes other devices
//! blessed. The *exact* tier asks for bit-identical output: the golden's own pixels on the device that made it, or
//! the hash a device blessed for itself. Where neither applies or they differ, the *perceptual* tier compares with
//! ꟻLIP (Andersson et al., "FLIP: A Difference Evaluator for Alternating Images", HPG 2020; NVIDIA's reference
//! code through the `nv-flip` crate): its mean and 99th weighted percentile against thresholds that know the
//! case's Monte Carlo noise (`strata check --calibrate` proposes them from the spread over seeds).
use anyhow::{anyhow, bail, Context as _, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The metadata file in a goldens directory.
pub const META_FILE: &str = "goldens.toml";

/// ꟻLIP thresholds a golden case uses until `--calibrate` measures its own.
pub const DEFAULT_FLIP_MEAN: f64 = 0.05;
pub const DEFAULT_FLIP_P99: f64 = 0.5;

/// What `goldens.toml` says of one case.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoldenEntry {
    /// The device (name / driver info) that rendered the golden file: on it the exact tier compares pixels.
    pub device: String,
    /// Perceptual thresholds: ꟻLIP mean and 99th weighted percentile (golden image cases).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip_mean: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip_p99: Option<f64>,
    /// Hashes of other devices' bit-exact output (device → `fnv1a64:…`), blessed on each.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub hashes: BTreeMap<String, String>,
}

impl GoldenEntry {
    pub fn thresholds(&self) -> (f64, f64) {
        (self.flip_mean.unwrap_or(DEFAULT_FLIP_MEAN), self.flip_p99.unwrap_or(DEFAULT_FLIP_P99))
    }
}

/// Where goldens are read from: a directory (the repository's `check/goldens`, or `--goldens DIR`), or the copy
/// compiled into the binary, so that `strata check` runs with nothing beside it.
#[derive(Debug, Clone)]
pub enum GoldenSource {
    Dir(PathBuf),
    Embedded,
}

/// The goldens of one run.
#[derive(Debug, Clone)]
pub struct Goldens {
    pub source: GoldenSource,
    pub entries: BTreeMap<String, GoldenEntry>,
}

/// The file name of a case's golden: its name with `/` as `-`, and the extension.
pub fn file_name(case: &str, extension: &str) -> String {
    format!("{}.{extension}", case.replace('/', "-"))
}

impl Goldens {
    /// The goldens in `dir`, or where none is given, the repository's `check/goldens` when this binary was built
    /// in a checkout that still has it, else the embedded copy.
    pub fn open(dir: Option<&Path>) -> Result<Self> {
        let source = match dir {
            Some(d) => GoldenSource::Dir(d.to_path_buf()),
            None => {
                let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("check/goldens");
                if repo.join(META_FILE).is_file() {
                    GoldenSource::Dir(repo)
                } else {
                    GoldenSource::Embedded
                }
            }
        };
        let entries = match &source {
            GoldenSource::Dir(d) => {
                let path = d.join(META_FILE);
                match std::fs::read_to_string(&path) {
                    Ok(text) => parse_meta(&text).with_context(|| format!("{}", path.display()))?,
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => BTreeMap::new(),
                    Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
                }
            }
            GoldenSource::Embedded => match super::embedded::golden_file(META_FILE) {
                Some(bytes) => parse_meta(std::str::from_utf8(bytes)?).context("the embedded goldens.toml")?,
                None => BTreeMap::new(),
            },
        };
        Ok(Self { source, entries })
    }

    /// Where the goldens come from, for the report.
    pub fn describe(&self) -> String {
        match &self.source {
            GoldenSource::Dir(d) => d.display().to_string(),
            GoldenSource::Embedded => "embedded in this strata binary".into(),
        }
    }

    /// A golden file's bytes, or None when it is not there.
    pub fn read(&self, name: &str) -> Result<Option<Vec<u8>>> {
        match &self.source {
            GoldenSource::Dir(d) => match std::fs::read(d.join(name)) {
                Ok(bytes) => Ok(Some(bytes)),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
                Err(e) => Err(e).with_context(|| format!("reading {}", d.join(name).display())),
            },
            GoldenSource::Embedded => Ok(super::embedded::golden_file(name).map(<[u8]>::to_vec)),
        }
    }

    /// The directory blessing writes into; the embedded copy cannot be blessed.
    pub fn writable_dir(&self) -> Result<&Path> {
        match &self.source {
            GoldenSource::Dir(d) => Ok(d),
            GoldenSource::Embedded => {
                bail!("the goldens are the copy embedded in this binary; name a directory to bless with --goldens DIR")
            }
        }
    }

    /// Makes `bytes` the golden file `name` of `case`, rendered on `device`: the old file is kept as `name.old`,
    /// the case's entry names the device and records its hash. Thresholds stay. Call [`Goldens::save`] after.
    pub fn bless(&mut self, case: &str, name: &str, bytes: &[u8], device: &str, hash: Option<String>) -> Result<()> {
        let dir = self.writable_dir()?.to_path_buf();
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = dir.join(name);
        if path.is_file() {
            let old = dir.join(format!("{name}.old"));
            std::fs::rename(&path, &old).with_context(|| format!("keeping the old golden as {}", old.display()))?;
        }
        crate::output::write_atomic(&path, |file| {
            use std::io::Write as _;
            file.write_all(bytes).map_err(Into::into)
        })?;
        let entry = self.entries.entry(case.to_string()).or_default();
        entry.device = device.to_string();
        if let Some(hash) = hash {
            entry.hashes.insert(device.to_string(), hash);
        }
        Ok(())
    }

    /// Writes `goldens.toml` (atomically).
    pub fn save(&self) -> Result<()> {
        let dir = self.writable_dir()?;
        let mut text = String::from(
            "# strata check goldens: per case, the device that rendered its file, its perceptual thresholds\n\
             # (strata check --calibrate) and other devices' blessed hashes. Written by strata check --bless.\n",
        );
        text.push_str(&toml::to_string(&self.entries).context("writing goldens.toml")?);
        crate::output::write_atomic(&dir.join(META_FILE), |file| {
            use std::io::Write as _;
            file.write_all(text.as_bytes()).map_err(Into::into)
        })
    }
}

fn parse_meta(text: &str) -> Result<BTreeMap<String, GoldenEntry>> {
    toml::from_str(text).map_err(|e| anyhow!("{e}"))
}

/// FNV-1a (64-bit) of an image's size and bytes: the exact tier's fingerprint.
pub fn hash_image(width: u32, height: u32, bytes: &[u8]) -> String {
    let mut h = crate::hash::Fnv1a::default();
    h.update(&width.to_le_bytes());
    h.update(&height.to_le_bytes());
    h.update(bytes);
    h.text()
}

/// An 8-bit RGBA image.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgba8 {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u8>,
}

impl Rgba8 {
    pub fn decode_png(bytes: &[u8]) -> Result<Self> {
        let image = image::load_from_memory_with_format(bytes, image::ImageFormat::Png).context("decoding PNG")?;
        let rgba = image.to_rgba8();
        Ok(Self { width: rgba.width(), height: rgba.height(), pixels: rgba.into_raw() })
    }

    pub fn hash(&self) -> String {
        hash_image(self.width, self.height, &self.pixels)
    }

    fn rgb(&self) -> Vec<u8> {
        self.pixels.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect()
    }
}

/// What the perceptual tier found.
#[derive(Debug, Clone)]
pub struct FlipResult {
    pub mean: f64,
    pub p99: f64,
    /// The error map through the magma colour map, for the report.
    pub heat_map: Rgba8,
}

/// ꟻLIP between a reference and a test image of the same size (sRGB, 8-bit), at the default viewing conditions
/// (0.7 m from a 0.7 m wide 4K monitor: 67 pixels per degree).
pub fn flip(reference: &Rgba8, test: &Rgba8) -> Result<FlipResult> {
    if (reference.width, reference.height) != (test.width, test.height) {
        bail!(
            "the images differ in size: {}x{} against {}x{}",
            reference.width,
            reference.height,
            test.width,
            test.height
        );
    }
    let r = nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &reference.rgb());
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &test.rgb());
    let error = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mut pool = nv_flip::FlipPool::from_image(&error);
    let heat = error.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let heat_map = Rgba8 {
        width: test.width,
        height: test.height,
        pixels: heat.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect(),
    };
    Ok(FlipResult { mean: f64::from(pool.mean()), p99: f64::from(pool.get_percentile(0.99, true)), heat_map })
}

/// Reads the RGBA layer of an EXR (what the AOV goldens are).
pub fn decode_exr(bytes: &[u8]) -> Result<crate::output::Frame> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| (size.width(), vec![[0f32; 4]; size.width() * size.height()]),
            |(width, pixels): &mut (usize, Vec<[f32; 4]>), position, (r, g, b, a): (f32, f32, f32, f32)| {
                pixels[position.y() * *width + position.x()] = [r, g, b, a];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| anyhow!("decoding EXR: {e}"))?;
    let layer = image.layer_data;
    crate::output::Frame::new(layer.size.width() as u32, layer.size.height() as u32, layer.channel_data.pixels.1)
}

/// Encodes a frame as an EXR in memory (through a temporary file: the writer is file-based).
pub fn encode_exr(frame: &crate::output::Frame, scratch: &Path) -> Result<Vec<u8>> {
    crate::output::write_frame(scratch, frame)?;
    let bytes = std::fs::read(scratch).with_context(|| format!("reading {}", scratch.display()))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hash_sees_one_changed_byte_and_the_size() {
        let a = hash_image(2, 1, &[0; 8]);
        assert_eq!(a, hash_image(2, 1, &[0; 8]));
        assert_ne!(a, hash_image(2, 1, &[0, 0, 0, 0, 0, 0, 0, 1]));
        assert_ne!(a, hash_image(1, 2, &[0; 8]));
    }

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_a_difference() {
        let grey = Rgba8 { width: 16, height: 16, pixels: vec![128; 16 * 16 * 4] };
        assert_eq!(flip(&grey, &grey).unwrap().mean, 0.0);
        let mut changed = grey.clone();
        changed.pixels[..16 * 4 * 8].fill(250);
        let half = flip(&grey, &changed).unwrap();
        assert!(half.mean > 0.1 && half.p99 > 0.3, "{} {}", half.mean, half.p99);
    }

    #[test]
    fn meta_round_trips_and_refuses_unknown_keys() {
        let mut entries = BTreeMap::new();
        let mut e = GoldenEntry { device: "llvmpipe / Mesa".into(), flip_mean: Some(0.01), ..Default::default() };
        e.hashes.insert("NVIDIA H200 / 580".into(), "fnv1a64:0123456789abcdef".into());
        entries.insert("golden/cornell".to_string(), e);
        let text = toml::to_string(&entries).unwrap();
        assert_eq!(parse_meta(&text).unwrap(), entries);
        assert!(parse_meta("[\"golden/x\"]\ndevice = \"a\"\nflip_men = 0.1\n").is_err());
    }
}
