//! glTF animations: translation, rotation, scale and morph-weight channels sampled at any time t with STEP, LINEAR
//! (slerp for rotations) and CUBICSPLINE interpolation (glTF 2.0 §3.11 and Appendix C). This is what motion blur
//! reads.
use super::NodeTransform;
use anyhow::{bail, Result};
use glam::{Quat, Vec3, Vec4};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
    /// Morph target weights: `width` Vec4s per value, the weights four at a time (the last padded with zeros).
    Weights,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

/// One animated property of one node. `values` holds one entry per key (xyz in a Vec4 for translation and
/// scale, xyzw for rotation, `width` Vec4s for weights); for CUBICSPLINE, three per key: in-tangent, value,
/// out-tangent.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    pub times: Vec<f32>,
    pub values: Vec<Vec4>,
    /// Vec4s per value: 1, or for weights ⌈targets / 4⌉.
    pub width: usize,
    /// For weights: how many targets (the rest of the last Vec4 is padding).
    pub targets: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Animation {
    pub name: String,
    pub channels: Vec<Channel>,
}

impl Channel {
    /// Checks the shape the sampler code relies on: increasing times, the right number of values.
    pub fn new(
        node: usize,
        property: Property,
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<Vec4>,
    ) -> Result<Self> {
        Self::with_width(node, property, interpolation, times, values, 1, 0)
    }

    /// A morph-weight channel: `weights` holds `targets` floats per value (times three per key for CUBICSPLINE).
    pub fn weights(
        node: usize,
        interpolation: Interpolation,
        times: Vec<f32>,
        weights: &[f32],
        targets: usize,
    ) -> Result<Self> {
        if targets == 0 || weights.len() % targets != 0 {
            bail!("morph weight sampler has {} outputs, not a whole number of {targets}-target values", weights.len());
        }
        let width = targets.div_ceil(4);
        let values = weights
            .chunks(targets)
            .flat_map(|value| {
                (0..width).map(move |c| {
                    Vec4::from_array(std::array::from_fn(|k| value.get(4 * c + k).copied().unwrap_or(0.0)))
                })
            })
            .collect();
        Self::with_width(node, Property::Weights, interpolation, times, values, width, targets)
    }

    fn with_width(
        node: usize,
        property: Property,
        interpolation: Interpolation,
        times: Vec<f32>,
        values: Vec<Vec4>,
        width: usize,
        targets: usize,
    ) -> Result<Self> {
        if times.is_empty() {
            bail!("animation sampler has no keyframes");
        }
        if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] <= w[0]) {
            bail!("animation sampler input times must be finite and strictly increasing");
        }
        let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        if values.len() != times.len() * per_key * width {
            bail!(
                "animation sampler has {} outputs for {} keys ({per_key} per key for {interpolation:?})",
                values.len(),
                times.len()
            );
        }
        if values.iter().any(|v| !v.is_finite()) {
            bail!("animation sampler output is not finite");
        }
        Ok(Self { node, property, interpolation, times, values, width, targets })
    }

    /// Entry `part` (0 in-tangent, 1 value, 2 out-tangent; plain keys have only the value) of key `key`, Vec4 `c`.
    fn entry(&self, key: usize, part: usize, c: usize) -> Vec4 {
        match self.interpolation {
            Interpolation::CubicSpline => self.values[(3 * key + part) * self.width + c],
            _ => self.values[key * self.width + c],
        }
    }

    /// The property's value at time `t`; before the first key the first value, after the last the last.
    pub fn sample(&self, t: f32) -> Vec4 {
        self.sample_part(t, 0)
    }

    /// A weights channel's weights at time `t`, one per target.
    pub fn sample_weights(&self, t: f32) -> Vec<f32> {
        let mut weights: Vec<f32> = (0..self.width).flat_map(|c| self.sample_part(t, c).to_array()).collect();
        weights.truncate(self.targets);
        weights
    }

    /// Vec4 `c` of the value at time `t`.
    fn sample_part(&self, t: f32, c: usize) -> Vec4 {
        let times = &self.times;
        let last = times.len() - 1;
        if t <= times[0] || last == 0 {
            return self.entry(0, 1, c);
        }
        if t >= times[last] {
            return self.entry(last, 1, c);
        }
        // times[k] <= t < times[k + 1]
        let k = times.partition_point(|&x| x <= t) - 1;
        let dt = times[k + 1] - times[k];
        let s = (t - times[k]) / dt;
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => self.entry(k, 1, c),
            Interpolation::Linear => {
                let (a, b) = (self.entry(k, 1, c), self.entry(k + 1, 1, c));
                if rotation {
                    Vec4::from(Quat::from_vec4(a).normalize().slerp(Quat::from_vec4(b).normalize(), s))
                } else {
                    a.lerp(b, s)
                }
            }
            Interpolation::CubicSpline => {
                // Hermite spline, glTF 2.0 Appendix C: tangents are scaled by the key interval.
                let v0 = self.entry(k, 1, c);
                let b0 = self.entry(k, 2, c); // out-tangent of key k
                let a1 = self.entry(k + 1, 0, c); // in-tangent of key k+1
                let v1 = self.entry(k + 1, 1, c);
                let (s2, s3) = (s * s, s * s * s);
                let p = v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + b0 * (dt * (s3 - 2.0 * s2 + s))
                    + v1 * (-2.0 * s3 + 3.0 * s2)
                    + a1 * (dt * (s3 - s2));
                if rotation {
                    p.normalize_or_zero()
                } else {
                    p
                }
            }
        }
    }
}

/// Which of a file's animation clips plays (`--animation`, the scene file's `animation`): viewers play one clip
/// at a time, the first unless told otherwise.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AnimationChoice {
    Index(usize),
    Name(String),
}

impl AnimationChoice {
    /// A clip's index (digits) or its name.
    pub fn parse(text: &str) -> Self {
        match text.parse() {
            Ok(index) => Self::Index(index),
            Err(_) => Self::Name(text.to_string()),
        }
    }
}

/// "0 \"Survey\" (4.3 s), 1 \"Walk\" (0.7 s)": the clips, for listings and errors.
pub fn list_clips(animations: &[Animation]) -> String {
    let clips: Vec<String> =
        animations.iter().enumerate().map(|(i, a)| format!("{i} \"{}\" ({:.2} s)", a.name, a.duration())).collect();
    clips.join(", ")
}

/// Keeps only the clip `choice` names (the first when None) of `animations`, as viewers play one clip at a time.
/// Returns a note for the user when the file has several and none was chosen; an unknown clip is an error that
/// lists the file's clips.
pub fn select_clip(animations: &mut Vec<Animation>, choice: Option<&AnimationChoice>) -> Result<Option<String>> {
    let index = match choice {
        None => 0,
        Some(AnimationChoice::Index(i)) => *i,
        Some(AnimationChoice::Name(name)) => match animations.iter().position(|a| &a.name == name) {
            Some(i) => i,
            None if animations.is_empty() => bail!("no animation clip \"{name}\": the scene has no animations"),
            None => bail!("no animation clip \"{name}\" (clips: {})", list_clips(animations)),
        },
    };
    if index >= animations.len().max(1) {
        match animations.len() {
            0 => bail!("no animation clip {index}: the scene has no animations"),
            _ => bail!("no animation clip {index} (clips: {})", list_clips(animations)),
        }
    }
    let note = (choice.is_none() && animations.len() > 1).then(|| {
        format!(
            "playing animation clip 0 \"{}\" of {} ({}); --animation NAME|INDEX picks another",
            animations[0].name,
            animations.len(),
            list_clips(animations)
        )
    });
    if !animations.is_empty() {
        let chosen = animations.swap_remove(index);
        *animations = vec![chosen];
    }
    Ok(note)
}

impl Animation {
    /// The clip's length: its last key time (0 for a clip without keys).
    pub fn duration(&self) -> f32 {
        self.channels.iter().filter_map(|c| c.times.last().copied()).fold(0.0, f32::max)
    }

    /// Node `node`'s morph weights at `t`, if the clip animates them.
    pub fn weights_at(&self, node: usize, t: f32) -> Option<Vec<f32>> {
        let channel = self.channels.iter().find(|c| c.node == node && c.property == Property::Weights)?;
        Some(channel.sample_weights(t))
    }

    /// Overwrites the animated properties of `locals` with their values at `t`.
    pub fn apply(&self, t: f32, locals: &mut [NodeTransform]) {
        for channel in self.channels.iter().filter(|c| c.property != Property::Weights) {
            let Some(local) = locals.get_mut(channel.node) else { continue };
            let NodeTransform::Trs { translation, rotation, scale } = local else { continue };
            let v = channel.sample(t);
            match channel.property {
                Property::Translation => *translation = v.truncate(),
                Property::Rotation => *rotation = Quat::from_vec4(v).normalize(),
                Property::Scale => *scale = v.truncate(),
                Property::Weights => {}
            }
        }
    }
}

/// A `Vec4` from xyz (w = 0), for translation and scale keys.
pub fn vec4_from_xyz(v: [f32; 3]) -> Vec4 {
    Vec3::from_array(v).extend(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(interpolation: Interpolation, times: &[f32], values: &[Vec4]) -> Channel {
        Channel::new(0, Property::Translation, interpolation, times.to_vec(), values.to_vec()).unwrap()
    }

    #[test]
    fn step_holds_until_the_next_key() {
        let c = channel(Interpolation::Step, &[0.0, 1.0], &[Vec4::ZERO, Vec4::ONE]);
        assert_eq!(c.sample(0.999), Vec4::ZERO);
        assert_eq!(c.sample(1.0), Vec4::ONE);
        assert_eq!(c.sample(-5.0), Vec4::ZERO);
        assert_eq!(c.sample(5.0), Vec4::ONE);
    }

    #[test]
    fn cubic_spline_with_zero_tangents_is_smoothstep() {
        let z = Vec4::ZERO;
        let c = channel(Interpolation::CubicSpline, &[0.0, 2.0], &[z, z, z, z, Vec4::ONE, z]);
        // p(s) = 3s² − 2s³ at s = 0.25: 0.15625.
        assert!((c.sample(0.5).x - 0.15625).abs() < 1e-6);
        // Tangents scale with the interval: out-tangent 1 per second over 2 s.
        let d = channel(Interpolation::CubicSpline, &[0.0, 2.0], &[z, z, Vec4::ONE, z, z, z]);
        // p(s) = dt (s³ − 2s² + s) = 2 (0.015625 − 0.125 + 0.25) at s = 0.25.
        assert!((d.sample(0.5).x - 0.28125).abs() < 1e-6);
    }

    #[test]
    fn bad_keyframes_are_rejected() {
        assert!(Channel::new(0, Property::Scale, Interpolation::Linear, vec![1.0, 1.0], vec![Vec4::ONE; 2]).is_err());
        assert!(
            Channel::new(0, Property::Scale, Interpolation::CubicSpline, vec![0.0, 1.0], vec![Vec4::ONE; 2]).is_err()
        );
        assert!(Channel::new(0, Property::Scale, Interpolation::Linear, vec![], vec![]).is_err());
    }
}
