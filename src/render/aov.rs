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
    /// The glTF node index + 1 of the surface each pixel's centre sees (0: nothing), exact per pixel (one
    /// sample at the pixel centre, not a mean); as a float, exact below 2^24.
    Instance,
    /// The semantic class of the surface each pixel's centre sees (its node's `category`, inherited from its
    /// ancestors; 0: unlabelled or nothing), exact per pixel.
    Semantic,
    /// Forward flow in pixels (x right, y down) of the surface point each pixel's centre sees, from this frame's
    /// time to one frame later (the scene's animation, motion and camera); 0 on the background.
    Motion,
}

/// What the AOVs that follow the scene rather than the G-buffer need: which node drew each instance, and where
/// every instance and the camera are now and one frame later.
pub struct AovScene {
    /// Per instance: its glTF node index + 1 (0 for an instance without a node).
    pub instance_labels: Vec<u32>,
    /// Per instance: its node's semantic class (0: none).
    pub categories: Vec<u32>,
    /// Per instance: where a world point of it now is one frame later (its transform then times the inverse of
    /// its transform now; None where that has no inverse). See [`AovScene::moves`].
    pub moves: Vec<Option<glam::Mat4>>,
    /// The pixel-centre camera now and one frame later.
    pub camera_now: crate::math::lens::CameraSample,
    pub camera_next: crate::math::lens::CameraSample,
    /// The motion pass's flow of the deformed instances (`render::motion::deformed_flow`): x, y, the instance + 1
    /// it drew, coverage. None when nothing deforms.
    pub deformed_flow: Option<Frame>,
}

impl Aov {
    pub const NAMES: [&'static str; 11] = [
        "normal",
        "geometric-normal",
        "albedo",
        "depth",
        "height",
        "position",
        "emission",
        "material",
        "instance",
        "semantic",
        "motion",
    ];

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
                "instance" => Aov::Instance,
                "semantic" => Aov::Semantic,
                "motion" => Aov::Motion,
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

    /// How many of a raw frame's four channels hold the AOV (the rest pad): what an array of it keeps.
    pub fn channels(self) -> usize {
        match self {
            Aov::Depth | Aov::Height | Aov::Instance | Aov::Semantic => 1,
            Aov::Motion => 2,
            Aov::Normal | Aov::GeometricNormal | Aov::Albedo | Aov::Position | Aov::Emission => 3,
            Aov::Material => 4,
        }
    }

    /// Labels (node index + 1, class id): whole numbers, held as floats in a frame, as integers in an array.
    pub fn is_label(self) -> bool {
        matches!(self, Aov::Instance | Aov::Semantic)
    }

    /// Colour AOVs are encoded as sRGB in a PNG; the others are data.
    pub fn is_color(self) -> bool {
        matches!(self, Aov::Albedo | Aov::Emission)
    }

    /// The raw values (what an EXR layer holds); alpha is 1 where a surface was drawn, 0 elsewhere.
    pub fn extract(self, g: &GBufferFrame, scene: &AovScene) -> Result<Frame> {
        let pixels = (0..g.width * g.height)
            .map(|i| {
                let (x, y) = (i % g.width, i / g.width);
                let covered = if g.covered(x, y) { 1.0 } else { 0.0 };
                let px = |c: usize| g.at(c, x, y);
                // The instance the pixel's centre sees (ids hold instance + 1).
                let instance = g.ids[i as usize][0].checked_sub(1).map(|k| k as usize);
                match self {
                    Aov::Instance | Aov::Semantic => {
                        let labels = if self == Aov::Instance { &scene.instance_labels } else { &scene.categories };
                        let label = instance.and_then(|k| labels.get(k)).copied().unwrap_or(0) as f32;
                        [label, label, label, covered]
                    }
                    Aov::Motion => match instance {
                        Some(k) => {
                            // A deformed instance's flow is the motion pass's where it drew the surface the
                            // G-buffer sees; a rigid one's is its transform's, worked out here.
                            let drawn = scene.deformed_flow.as_ref().map(|f| f.pixel(x, y));
                            let [fx, fy] = match drawn.filter(|p| p[3] > 0.0 && p[2] == (k + 1) as f32) {
                                Some(p) => [p[0], p[1]],
                                None => flow(scene, k, glam::Vec4::from(px(POSITION)).truncate(), g.width, g.height),
                            };
                            [fx, fy, 0.0, covered]
                        }
                        None => [0.0, 0.0, 0.0, 0.0],
                    },
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
        let largest_flow = raw.pixels.iter().map(|p| p[0].abs().max(p[1].abs())).fold(1e-6f32, f32::max);
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
                    // Labels as distinct colours (a hash of the label), nothing black.
                    Aov::Instance | Aov::Semantic if p[0] > 0.0 => {
                        let h = (p[0] as u32).wrapping_mul(0x9e37_79b9);
                        let c = |shift: u32| 0.25 + 0.75 * ((h >> shift) & 0xff) as f32 / 255.0;
                        [c(8), c(16), c(24), 1.0]
                    }
                    Aov::Instance | Aov::Semantic => [0.0, 0.0, 0.0, 1.0],
                    // Flow as a colour: grey is still, red/green the x/y components up to the frame's largest.
                    Aov::Motion => [0.5 + 0.5 * p[0] / largest_flow, 0.5 + 0.5 * p[1] / largest_flow, 0.5, 1.0],
                    _ => [p[0], p[1], p[2], 1.0],
                }
            })
            .collect();
        Frame { width: raw.width, height: raw.height, pixels }
    }
}

impl AovScene {
    /// Each instance's motion over one frame, from its transforms now and one frame later: a point rides on its
    /// instance's transform (object space is where it stays put). Once per instance, not per pixel.
    pub fn moves(now: &[glam::Mat4], next: &[glam::Mat4]) -> Vec<Option<glam::Mat4>> {
        now.iter()
            .zip(next)
            .map(|(now, next)| (now.determinant().abs() >= 1e-20).then(|| *next * now.inverse()))
            .collect()
    }
}

/// Where `world`, a point of instance `k` seen now, is one frame later, minus where it is now, in pixels, each end
/// projected by its own camera.
fn flow(scene: &AovScene, k: usize, world: glam::Vec3, width: u32, height: u32) -> [f32; 2] {
    use crate::math::lens::project_to_pixel;
    let Some(Some(later)) = scene.moves.get(k) else { return [0.0; 2] };
    let moved = later.transform_point3(world);
    let f = project_to_pixel(&scene.camera_next, moved, width, height)
        - project_to_pixel(&scene.camera_now, world, width, height);
    if f.is_finite() {
        f.to_array()
    } else {
        [0.0; 2]
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
