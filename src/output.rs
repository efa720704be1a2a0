//! Writing frames: PNG (8-bit sRGB) and OpenEXR (32-bit float linear RGBA, plus named layers), chosen by the
//! file extension. Every write is atomic: a temporary file in the destination directory, then a rename, so a
//! failed or interrupted render never leaves a partial file at the destination.
use anyhow::{anyhow, bail, Context as _, Result};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A linear-light RGBA float picture, row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl Frame {
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 4]>) -> Result<Self> {
        if pixels.len() != width as usize * height as usize {
            bail!("frame of {width}x{height} needs {} pixels, got {}", width as usize * height as usize, pixels.len());
        }
        Ok(Self { width, height, pixels })
    }

    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[y as usize * self.width as usize + x as usize]
    }
}

/// The formats strata writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputFormat {
    Png,
    Exr,
}

impl OutputFormat {
    /// The format the path's extension names; anything else is an error that says what is accepted.
    pub fn from_path(path: &Path) -> Result<Self> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            Some(other) => bail!("{}: unknown output extension \".{other}\" (use .png or .exr)", path.display()),
            None => bail!("{}: output file has no extension (use .png or .exr)", path.display()),
        }
    }
}

/// sRGB encoding of a linear value in [0, 1] (IEC 61966-2-1).
pub fn linear_to_srgb(linear: f32) -> f32 {
    let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`linear_to_srgb`].
pub fn srgb_to_linear(encoded: f32) -> f32 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// The display image the resolve pass makes (shaders/resolve.comp), made on the host from a linear frame that
/// did not come from the sums (a denoised one): exposure 2^stops, the tone map (clamp or Narkowicz's ACES fit),
/// sRGB; with `transparent`, straight alpha from coverage.
pub fn display_rgba8(frame: &Frame, exposure_stops: f32, filmic: bool, transparent: bool) -> Vec<u8> {
    let scale = exposure_stops.exp2();
    let aces = |x: f32| ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
    let q = |v: f32| (v * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8;
    frame
        .pixels
        .iter()
        .flat_map(|p| {
            let alpha = if transparent { p[3].clamp(0.0, 1.0) } else { 1.0 };
            let unpremultiply = if transparent {
                if p[3] > 0.0 {
                    1.0 / p[3]
                } else {
                    0.0
                }
            } else {
                1.0
            };
            let c = |v: f32| {
                let x = (v * unpremultiply * scale).max(0.0);
                q(linear_to_srgb(if filmic { aces(x) } else { x.clamp(0.0, 1.0) }))
            };
            [c(p[0]), c(p[1]), c(p[2]), q(alpha)]
        })
        .collect()
}

/// 8-bit sRGB RGBA bytes of a linear frame (colour clamped to [0, 1] and encoded; alpha linear).
pub fn to_srgb8(frame: &Frame) -> Vec<u8> {
    frame
        .pixels
        .iter()
        .flat_map(|p| {
            let q = |v: f32| (v * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8;
            [q(linear_to_srgb(p[0])), q(linear_to_srgb(p[1])), q(linear_to_srgb(p[2])), q(p[3].clamp(0.0, 1.0))]
        })
        .collect()
}

/// Writes a data image (normals, depth, ...) as an 8-bit PNG: values in [0, 1] quantized directly, without
/// the sRGB curve, atomically.
pub fn write_data_png(path: &Path, frame: &Frame) -> Result<()> {
    stage_data_png(path, frame)?.commit()
}

/// [`write_data_png`], staged (see [`Staged`]).
pub fn stage_data_png(path: &Path, frame: &Frame) -> Result<Staged> {
    if OutputFormat::from_path(path)? != OutputFormat::Png {
        bail!("{}: data images are written as .png", path.display());
    }
    let bytes: Vec<u8> = frame
        .pixels
        .iter()
        .flat_map(|p| p.map(|v| (if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) } * 255.0 + 0.5).floor() as u8))
        .collect();
    stage(path, |file| {
        let encoder = image::codecs::png::PngEncoder::new(std::io::BufWriter::new(file));
        image::ImageEncoder::write_image(encoder, &bytes, frame.width, frame.height, image::ExtendedColorType::Rgba8)
            .context("encoding PNG")
    })
}

/// Writes `frame` to `path` in the format its extension names, atomically.
pub fn write_frame(path: &Path, frame: &Frame) -> Result<()> {
    write_frame_with_layers(path, frame, &[])
}

/// Like [`write_frame`], with extra named RGBA layers (AOVs) for EXR; PNG output refuses layers.
pub fn write_frame_with_layers(path: &Path, frame: &Frame, layers: &[(&str, &Frame)]) -> Result<()> {
    stage_frame_with_layers(path, frame, layers)?.commit()
}

/// [`write_frame_with_layers`], staged (see [`Staged`]).
pub fn stage_frame_with_layers(path: &Path, frame: &Frame, layers: &[(&str, &Frame)]) -> Result<Staged> {
    match OutputFormat::from_path(path)? {
        OutputFormat::Png => {
            if !layers.is_empty() {
                bail!("{}: PNG cannot hold extra layers; write an .exr", path.display());
            }
            stage_png_rgba8(path, frame.width, frame.height, &to_srgb8(frame))
        }
        OutputFormat::Exr => stage(path, |file| write_exr(file, frame, layers)),
    }
}

/// Writes 8-bit RGBA bytes that are already display-encoded (the resolve pass's sRGB output) as a PNG,
/// atomically.
pub fn write_png_rgba8(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    stage_png_rgba8(path, width, height, rgba)?.commit()
}

/// [`write_png_rgba8`], staged (see [`Staged`]).
pub fn stage_png_rgba8(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<Staged> {
    if OutputFormat::from_path(path)? != OutputFormat::Png {
        bail!("{}: 8-bit display images are written as .png", path.display());
    }
    if rgba.len() != width as usize * height as usize * 4 {
        bail!("{}: {} bytes is not a {width}x{height} RGBA image", path.display(), rgba.len());
    }
    stage(path, |file| {
        let encoder = image::codecs::png::PngEncoder::new(std::io::BufWriter::new(file));
        image::ImageEncoder::write_image(encoder, rgba, width, height, image::ExtendedColorType::Rgba8)
            .context("encoding PNG")
    })
}

/// One EXR part: the beauty as `R,G,B,A`, each extra layer as `name.R, name.G, name.B, name.A` (the OpenEXR
/// naming convention for layers within a part), all 32-bit float.
fn write_exr(file: &mut std::fs::File, frame: &Frame, layers: &[(&str, &Frame)]) -> Result<()> {
    use exr::prelude::*;
    let size = Vec2(frame.width as usize, frame.height as usize);
    let mut channels = Vec::with_capacity(4 * (1 + layers.len()));
    let mut add = |prefix: &str, f: &Frame| -> anyhow::Result<()> {
        if f.width != frame.width || f.height != frame.height {
            bail!("layer \"{prefix}\" is {}x{}, the frame is {}x{}", f.width, f.height, frame.width, frame.height);
        }
        if !prefix.is_empty() && (prefix.contains('.') || !prefix.is_ascii()) {
            bail!("layer name \"{prefix}\" must be ASCII without dots");
        }
        for (i, c) in ["R", "G", "B", "A"].into_iter().enumerate() {
            let name = if prefix.is_empty() { c.to_string() } else { format!("{prefix}.{c}") };
            let text = Text::new_or_none(name.as_str()).ok_or_else(|| anyhow!("bad channel name {name:?}"))?;
            channels.push(AnyChannel::new(text, FlatSamples::F32(f.pixels.iter().map(|p| p[i]).collect())));
        }
        Ok(())
    };
    add("", frame)?;
    for (name, layer) in layers {
        if name.is_empty() {
            bail!("an extra layer needs a name");
        }
        add(name, layer)?;
    }
    // exr requires channels sorted by name.
    let channels = AnyChannels::sort(SmallVec::from_vec(channels));
    let layer = Layer::new(size, LayerAttributes::default(), Encoding::SMALL_LOSSLESS, channels);
    let image = Image::from_layer(layer);
    // The exr error already says its cause (an I/O error's text): "{e}" keeps it from being said twice.
    image.write().to_buffered(std::io::BufWriter::new(file)).map_err(|e| anyhow!("{e}")).context("encoding EXR")
}

/// The directory `path` will be written into; an error if it does not exist (checked before long work).
pub fn check_output_directory(path: &Path) -> Result<PathBuf> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        bail!("{}: the output directory {} does not exist", path.display(), dir.display());
    }
    Ok(dir)
}

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// A fresh hidden name in `dir` for a file being written: short and independent of the final name, so that a
/// destination whose name is as long as the file system allows still gets one.
pub fn temporary_name(dir: &Path) -> PathBuf {
    dir.join(format!(".strata-{}-{}.tmp", std::process::id(), TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)))
}

/// A file written in full beside its destination, not yet in its place: [`Staged::commit`] renames it there;
/// dropped uncommitted, it is removed. Several staged files committed together make the outputs of one frame
/// appear all or none (a failed `--exr` leaves no PNG behind).
pub struct Staged {
    temp: PathBuf,
    path: PathBuf,
    committed: bool,
}

impl Staged {
    /// Renames the file into place. Refuses to replace anything but a regular file (a directory, a device, a
    /// symbolic link that appeared since the run was planned).
    pub fn commit(mut self) -> Result<()> {
        if let Ok(meta) = std::fs::symlink_metadata(&self.path) {
            if !meta.is_file() {
                bail!("{}: no longer a regular file (something else is there now); not replaced", self.path.display());
            }
        }
        std::fs::rename(&self.temp, &self.path)
            .with_context(|| format!("cannot move {} to {}", self.temp.display(), self.path.display()))
            .with_context(|| format!("writing {}", self.path.display()))?;
        self.committed = true;
        Ok(())
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// Writes `path`'s contents to a temporary file beside it, flushed to disk; nothing is at `path` yet.
pub fn stage(path: &Path, write: impl FnOnce(&mut std::fs::File) -> Result<()>) -> Result<Staged> {
    let dir = check_output_directory(path)?;
    if path.file_name().is_none() {
        bail!("{}: not a file path", path.display());
    }
    let temp = temporary_name(&dir);
    let staged = Staged { temp: temp.clone(), path: path.to_path_buf(), committed: false };
    let result = (|| {
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)
            .with_context(|| format!("cannot create {}", temp.display()))?;
        write(&mut file)?;
        file.flush()?;
        file.sync_all().with_context(|| format!("cannot flush {}", temp.display()))
    })();
    match result {
        Ok(()) => Ok(staged),
        Err(e) => Err(e.context(format!("writing {}", path.display()))),
    }
}

/// Commits staged files in order; all were written in full before the first is renamed.
pub fn commit_all(staged: Vec<Staged>) -> Result<()> {
    for file in staged {
        file.commit()?;
    }
    Ok(())
}

/// Writes a file atomically: `write` fills a temporary file next to `path`; only when it succeeds and the data
/// is flushed to disk is the file renamed onto `path`. On any error the temporary file is removed and `path` is
/// untouched.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut std::fs::File) -> Result<()>) -> Result<()> {
    stage(path, write)?.commit()
}
