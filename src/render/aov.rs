//! Arbitrary output variables: G-buffer channels a user can look at (`strata render --aov normal,depth,...`).
use super::gbuffer::GBufferFrame;
use super::gbuffer_layout::{ALBEDO, EMISSION, GEOMETRIC_NORMAL, MATERIAL, POSITION, SHADING_NORMAL};
use crate::output::Frame;
use anyhow::{bail, Result};

/// The AOVs strata writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aov {
    /// Bumped shading normal, world space, xyz in RGB.
    Normal,
    /// Face normal, world space.
    GeometricNormal,
    /// Base colour × texture × vertex colour, linear.
    Albedo,
    /// View depth in metres.
    Depth,
    /// Bump height B(u, v).
    Height,
    /// World position.
    Position,
    /// Emitted radiance.
    Emission,
    /// Metallic, roughness, transmission, (ior − 1)/3.
    Material,
}

impl Aov {
    pub const NAMES: [&'static str; 8] =
        ["normal", "geometric-normal", "albedo", "depth", "height", "position", "emission", "material"];

    pub fn parse_list(text: &str) -> Result<Vec<Aov>> {
        let mut list = Vec::new();
        for name in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let aov = match name {
                "normal" => Aov::Normal,
                "geometric-normal" => Aov::GeometricNormal,
                "albedo" => Aov::Albedo,
                "depth" => Aov::Depth,
                "height" => Aov::Height,
                "position" => Aov::Position,
                "emission" => Aov::Emission,
                "material" => Aov::Material,
                other => bail!("unknown AOV \"{other}\" (one of: {})", Aov::NAMES.join(", ")),
            };
            if !list.contains(&aov) {
                list.push(aov);
            }
        }
        if list.is_empty() {
            bail!("--aov needs at least one name (one of: {})", Aov::NAMES.join(", "));
        }
        Ok(list)
    }

    pub fn name(self) -> &'static str {
        Aov::NAMES[self as usize]
    }

    /// Colour AOVs are encoded as sRGB in a PNG; the others are data.
    pub fn is_color(self) -> bool {
        matches!(self, Aov::Albedo | Aov::Emission)
    }

    /// The raw values (what an EXR layer holds); alpha is 1 where a surface was drawn, 0 elsewhere.
    pub fn extract(self, g: &GBufferFrame) -> Result<Frame> {
        let pixels = (0..g.width * g.height)
            .map(|i| {
                let (x, y) = (i % g.width, i / g.width);
                let covered = if g.covered(x, y) { 1.0 } else { 0.0 };
                let px = |c: usize| g.at(c, x, y);
                match self {
                    Aov::Normal => with_alpha(px(SHADING_NORMAL), covered),
                    Aov::GeometricNormal => with_alpha(px(GEOMETRIC_NORMAL), covered),
                    Aov::Albedo => with_alpha(px(ALBEDO), covered),
                    Aov::Depth => [px(POSITION)[3], px(POSITION)[3], px(POSITION)[3], covered],
                    Aov::Height => [px(SHADING_NORMAL)[3], px(SHADING_NORMAL)[3], px(SHADING_NORMAL)[3], covered],
                    Aov::Position => with_alpha(px(POSITION), covered),
                    Aov::Emission => with_alpha(px(EMISSION), covered),
                    Aov::Material => px(MATERIAL),
                }
            })
            .collect();
        Frame::new(g.width, g.height, pixels)
    }

    /// The values mapped to [0, 1] for an 8-bit PNG: normals as ½ + ½n, depth and height scaled by their range
    /// over covered pixels (near and high are bright), the rest as they are.
    pub fn for_display(self, raw: &Frame) -> Frame {
        let covered: Vec<&[f32; 4]> = raw.pixels.iter().filter(|p| p[3] > 0.0).collect();
        let (lo, hi) = covered.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
        let span = if hi > lo { hi - lo } else { 1.0 };
        let pixels = raw
            .pixels
            .iter()
            .map(|p| {
                let a = p[3];
                match self {
                    Aov::Normal | Aov::GeometricNormal => [0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1], 0.5 + 0.5 * p[2], 1.0],
                    Aov::Depth if a > 0.0 => {
                        let v = 1.0 - (p[0] - lo) / span;
                        [v, v, v, 1.0]
                    }
                    Aov::Height if a > 0.0 => {
                        let v = (p[0] - lo) / span;
                        [v, v, v, 1.0]
                    }
                    Aov::Depth | Aov::Height => [0.0, 0.0, 0.0, 1.0],
                    _ => [p[0], p[1], p[2], 1.0],
                }
            })
            .collect();
        Frame { width: raw.width, height: raw.height, pixels }
    }
}

fn with_alpha(p: [f32; 4], alpha: f32) -> [f32; 4] {
    [p[0], p[1], p[2], alpha]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aov_lists_parse_and_reject_unknown_names() {
        assert_eq!(Aov::parse_list("normal, depth,normal").unwrap(), vec![Aov::Normal, Aov::Depth]);
        assert!(Aov::parse_list("normals").unwrap_err().to_string().contains("one of: normal"));
        assert!(Aov::parse_list(",").is_err());
        for name in Aov::NAMES {
            assert_eq!(Aov::parse_list(name).unwrap()[0].name(), name);
        }
    }
}
