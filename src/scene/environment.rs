//! Environment lighting: radiance arriving from infinitely far away, as an equirectangular (latitude-longitude)
//! image, what headless capture tools light glTF assets with (a studio or sky `.hdr`). Loaded from Radiance
//! `.hdr` or OpenEXR files, or made in code (uniform, one bright texel, a procedural studio).
//!
//! Directions map to the image as: θ = acos(y) from +Y (the top row) down to −Y (the bottom row), φ = atan2(x, −z);
//! u = ½ + φ/2π, v = θ/π. The image's centre faces −Z (what a default glTF camera looks at) and +X is a quarter
//! of the width to its right, as a panorama looks from inside. `rotation_degrees` turns the environment about +Y
//! (counter-clockwise seen from above), `intensity` scales its radiance.
use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use std::f32::consts::PI;
use std::path::Path;

#[derive(Debug, Clone, PartialEq)]
pub struct Environment {
    /// Where it came from (a file name, or what made it), for messages.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Linear radiance, row-major, top row (+Y) first.
    pub texels: Vec<Vec3>,
    pub rotation_degrees: f32,
    pub intensity: f32,
}

/// The largest environment image accepted, per side.
pub const MAX_SIDE: u32 = 16384;

impl Environment {
    /// An environment from its texels (checked: `width × height` finite, non-negative values).
    pub fn new(name: &str, width: u32, height: u32, texels: Vec<Vec3>) -> Result<Self> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            bail!("{name}: an environment of {width}x{height} texels (each side 1 to {MAX_SIDE})");
        }
        if texels.len() != width as usize * height as usize {
            bail!("{name}: {} texels for {width}x{height}", texels.len());
        }
        if let Some(i) = texels.iter().position(|t| !t.is_finite() || t.min_element() < 0.0) {
            bail!(
                "{name}: texel ({}, {}) is {} (radiance must be finite and not negative)",
                i as u32 % width,
                i as u32 / width,
                texels[i]
            );
        }
        Ok(Self { name: name.into(), width, height, texels, rotation_degrees: 0.0, intensity: 1.0 })
    }

    /// The same radiance from every direction.
    pub fn uniform(radiance: Vec3) -> Self {
        Self {
            name: format!("uniform {radiance}"),
            width: 4,
            height: 2,
            texels: vec![radiance; 8],
            rotation_degrees: 0.0,
            intensity: 1.0,
        }
    }

    /// Black but for one texel of radiance `radiance`, at `(column, row)` of a `width × height` image.
    pub fn one_texel(width: u32, height: u32, column: u32, row: u32, radiance: Vec3) -> Self {
        let mut texels = vec![Vec3::ZERO; width as usize * height as usize];
        texels[(row * width + column) as usize] = radiance;
        Self {
            name: format!("one texel ({column}, {row}) of {width}x{height}"),
            width,
            height,
            texels,
            rotation_degrees: 0.0,
            intensity: 1.0,
        }
    }

    /// The environment a user names: `studio` (the procedural one), else an image file ([`Environment::load`]).
    pub fn named(name: &Path) -> Result<Self> {
        if name.as_os_str() == "studio" {
            Ok(Self::studio(512, 256))
        } else {
            Self::load(name)
        }
    }

    /// A procedural studio: a soft grey dome brightening towards the zenith, a warm key panel high on one side
    /// and a cooler, dimmer fill opposite, over a dark floor. For scenes and tests that need no file.
    pub fn studio(width: u32, height: u32) -> Self {
        let mut texels = Vec::with_capacity(width as usize * height as usize);
        let key = Vec3::new(-0.5, 0.6, 0.62).normalize();
        let fill = Vec3::new(0.8, 0.3, 0.5).normalize();
        for row in 0..height {
            for column in 0..width {
                let d = uv_to_direction((column as f32 + 0.5) / width as f32, (row as f32 + 0.5) / height as f32);
                let up = d.y.max(0.0);
                let mut l = if d.y >= 0.0 { Vec3::splat(0.25 + 0.55 * up) } else { Vec3::splat(0.06) };
                if d.dot(key) > 0.97 {
                    l += Vec3::new(12.0, 11.0, 9.5);
                }
                if d.dot(fill) > 0.95 {
                    l += Vec3::new(2.0, 2.4, 3.0);
                }
                texels.push(l);
            }
        }
        Self { name: format!("studio {width}x{height}"), width, height, texels, rotation_degrees: 0.0, intensity: 1.0 }
    }

    /// Reads an equirectangular image: Radiance `.hdr` or OpenEXR `.exr` (its RGB layer), chosen by extension.
    /// Only a regular file; its header is checked against [`MAX_SIDE`] and the file's length, and the memory
    /// for its texels asked for, before any texel is decoded.
    pub fn load(path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        // Each loader opens only a regular file; elsewhere what is there is said first (/dev/zero is a device
        // before it is a name without an extension).
        let (width, height, texels) = match ext.as_deref() {
            Some("hdr") => load_hdr(path)?,
            Some("exr") => load_exr(path)?,
            Some(other) => {
                crate::input::open_regular(path)?;
                bail!("{name}: unknown environment extension \".{other}\" (use .hdr or .exr)")
            }
            None => {
                crate::input::open_regular(path)?;
                bail!("{name}: environment file has no extension (use .hdr or .exr)")
            }
        };
        Self::new(&name, width, height, texels)
    }

    /// The radiance arriving from world direction `dir` (unit): the texel it falls in, times the intensity
    /// (piecewise constant: exactly the function the sampling distribution follows).
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let (u, v) = direction_to_uv(self.to_local(dir));
        self.texel_at(u, v) * self.intensity
    }

    fn texel_at(&self, u: f32, v: f32) -> Vec3 {
        let x = ((u * self.width as f32) as u32).min(self.width - 1);
        let y = ((v * self.height as f32) as u32).min(self.height - 1);
        self.texels[(y * self.width + x) as usize]
    }

    /// A world direction in the image's frame (the rotation undone).
    pub fn to_local(&self, dir: Vec3) -> Vec3 {
        let (s, c) = (-self.rotation_degrees.to_radians()).sin_cos();
        Vec3::new(c * dir.x + s * dir.z, dir.y, -s * dir.x + c * dir.z)
    }

    /// A direction of the image's frame in the world (the rotation applied).
    pub fn to_world(&self, local: Vec3) -> Vec3 {
        let (s, c) = self.rotation_degrees.to_radians().sin_cos();
        Vec3::new(c * local.x + s * local.z, local.y, -s * local.x + c * local.z)
    }

    /// The mean radiance over the sphere (texels weighted by their solid angle), times the intensity.
    pub fn mean_radiance(&self) -> Vec3 {
        let mut sum = Vec3::ZERO;
        let mut weight = 0.0f32;
        for row in 0..self.height {
            let w = ((row as f32 + 0.5) / self.height as f32 * PI).sin();
            for column in 0..self.width {
                sum += self.texels[(row * self.width + column) as usize] * w;
                weight += w;
            }
        }
        sum / weight.max(1e-30) * self.intensity
    }
}

/// The bytes of linear RGB texels an environment of `width × height` holds.
fn texel_bytes(width: u64, height: u64) -> u64 {
    width * height * std::mem::size_of::<Vec3>() as u64
}

fn check_side(path: &Path, width: u64, height: u64) -> Result<()> {
    if width == 0 || height == 0 || width > u64::from(MAX_SIDE) || height > u64::from(MAX_SIDE) {
        bail!(
            "{}: its header claims {width}x{height} texels; an environment is 1 to {MAX_SIDE} texels a side",
            path.display()
        );
    }
    Ok(())
}

/// A Radiance `.hdr`: the header first, then the texels decoded straight into the environment's own storage.
fn load_hdr(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    use image::ImageDecoder as _;
    let name = path.display();
    let (file, len) = crate::input::open_regular(path)?;
    let decoder = image::codecs::hdr::HdrDecoder::new(std::io::BufReader::new(file))
        .map_err(|e| anyhow!("{name}: not a Radiance HDR image: {e}"))?;
    let (w, h) = decoder.dimensions();
    check_side(path, w.into(), h.into())?;
    // Every scanline, however well compressed, takes at least 4 bytes; and no run-length coding packs a file
    // past the bound of every image strata reads.
    if len < 4 * u64::from(h) {
        bail!("{name}: its header claims {w}x{h} texels, but the file holds only {len} bytes (cut short?)");
    }
    crate::input::check_packing(path, u64::from(w) * u64::from(h) * 4, len)?;
    let bytes = texel_bytes(w.into(), h.into());
    crate::input::ensure_memory(bytes, path, "its texels")?;
    let mut texels = vec![Vec3::ZERO; w as usize * h as usize];
    decoder
        .read_image(bytemuck::cast_slice_mut(&mut texels))
        .map_err(|e| anyhow!("{name}: the Radiance HDR image does not decode: {e}"))?;
    Ok((w, h, texels))
}

/// An OpenEXR image's RGB channels: the header first, then the texels.
fn load_exr(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    use exr::prelude::*;
    let name = path.display();
    let (file, header) = crate::input::exr_header(path, MAX_SIDE as usize, "an environment")?;
    let (w, h) = (header.layer_size.0 as u64, header.layer_size.1 as u64);
    crate::input::ensure_memory(texel_bytes(w, h), path, "its texels")?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size, _| (size.width(), vec![Vec3::ZERO; size.width() * size.height()]),
            |(width, pixels): &mut (usize, Vec<Vec3>), position, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[position.y() * *width + position.x()] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::BufReader::new(file))
        .map_err(|e| anyhow!("{name}: not an OpenEXR image with RGB channels: {e}"))?;
    let layer = image.layer_data;
    let (w, h) = (layer.size.width() as u32, layer.size.height() as u32);
    Ok((w, h, layer.channel_data.pixels.1))
}

/// An image-frame direction's equirectangular coordinates in [0, 1]².
pub fn direction_to_uv(d: Vec3) -> (f32, f32) {
    let theta = d.y.clamp(-1.0, 1.0).acos();
    let phi = d.x.atan2(-d.z);
    let u = 0.5 + phi / (2.0 * PI);
    (u - u.floor(), theta / PI)
}

/// The direction of equirectangular coordinates (u, v) in the image's frame.
pub fn uv_to_direction(u: f32, v: f32) -> Vec3 {
    let phi = 2.0 * PI * (u - 0.5);
    let theta = PI * v;
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_centre_faces_minus_z_and_a_quarter_right_is_plus_x() {
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(close(uv_to_direction(0.5, 0.5), Vec3::NEG_Z));
        assert!(close(uv_to_direction(0.75, 0.5), Vec3::X));
        assert!(close(uv_to_direction(0.3, 0.0), Vec3::Y));
        for (u, v) in [(0.1, 0.2), (0.6, 0.7), (0.95, 0.5)] {
            let (u2, v2) = direction_to_uv(uv_to_direction(u, v));
            assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5, "{u},{v} -> {u2},{v2}");
        }
    }

    #[test]
    fn rotation_turns_about_y_and_undoes() {
        let mut e = Environment::uniform(Vec3::ONE);
        e.rotation_degrees = 90.0;
        // Turned 90° counter-clockwise from above: what faced −Z now faces −X.
        assert!((e.to_world(Vec3::NEG_Z) - Vec3::NEG_X).length() < 1e-6);
        let d = Vec3::new(0.3, 0.4, -0.866).normalize();
        assert!((e.to_local(e.to_world(d)) - d).length() < 1e-6);
    }

    #[test]
    fn bad_texels_and_sizes_are_refused_with_the_name() {
        let err = Environment::new("sky.hdr", 2, 1, vec![Vec3::ONE, Vec3::new(f32::NAN, 0.0, 0.0)]).unwrap_err();
        assert!(err.to_string().starts_with("sky.hdr: texel (1, 0)"), "{err}");
        assert!(Environment::new("sky.hdr", 0, 1, vec![]).is_err());
        let missing = Environment::load(Path::new("no-such.hdr")).unwrap_err().to_string();
        assert_eq!(missing, "no-such.hdr: no such file");
    }

    #[test]
    fn a_uniform_environment_has_its_radiance_as_mean() {
        let e = Environment { intensity: 2.0, ..Environment::uniform(Vec3::splat(0.5)) };
        assert!((e.mean_radiance() - Vec3::ONE).length() < 1e-5);
        assert_eq!(e.radiance(Vec3::new(0.2, -0.9, 0.1).normalize()), Vec3::ONE);
    }
}
