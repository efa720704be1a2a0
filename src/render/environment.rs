//! The environment on the GPU: one storage buffer (`shaders/include/environment.glsl` reads it) holding a header,
//! the texels and the importance-sampling distribution (`math::environment`). A scene without an environment
//! gets a header that says so, so the accumulation pass always has the binding.
use crate::math::environment::EnvironmentDistribution;
use crate::scene::environment::Environment;
use crate::vk::{Buffer, Device};
use anyhow::Result;
use ash::vk;
use std::sync::Arc;

/// The header's size in floats: width, height, present, the sampling; cos and sin of the rotation, intensity,
/// unused.
const HEADER_FLOATS: usize = 8;

/// How light sampling picks directions towards the environment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EnvironmentSampling {
    /// By the luminance distribution (what renders use).
    #[default]
    Importance,
    /// Uniformly over the sphere: only for the test that shows importance sampling is better.
    UniformSphere,
}

/// The buffer's contents, as 32-bit words: the header (width, height and the present flag as integers), then
/// RGB texels padded to 4 floats, the marginal CDF (height + 1) and the conditional CDFs (height × (width + 1)).
pub fn environment_words(environment: Option<&Environment>, sampling: EnvironmentSampling) -> Vec<u32> {
    let Some(e) = environment else {
        let mut words = vec![0u32; HEADER_FLOATS + 4];
        (words[0], words[1]) = (1, 1);
        return words;
    };
    let luminance: Vec<f32> = e.texels.iter().map(|t| t.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722))).collect();
    let distribution = EnvironmentDistribution::new(e.width, e.height, &luminance);
    let (sin, cos) = e.rotation_degrees.to_radians().sin_cos();
    let mut words = Vec::with_capacity(
        HEADER_FLOATS + 4 * e.texels.len() + distribution.marginal.len() + distribution.conditional.len(),
    );
    words.extend([e.width, e.height, 1, u32::from(sampling == EnvironmentSampling::UniformSphere)]);
    words.extend([cos, sin, e.intensity, 0.0].map(f32::to_bits));
    for t in &e.texels {
        words.extend([t.x, t.y, t.z, 0.0].map(f32::to_bits));
    }
    words.extend(distribution.marginal.iter().map(|f| f.to_bits()));
    words.extend(distribution.conditional.iter().map(|f| f.to_bits()));
    words
}

/// Uploads the scene's environment (or the header of none).
pub fn upload(device: &Arc<Device>, environment: Option<&Environment>) -> Result<Buffer> {
    upload_sampled(device, environment, EnvironmentSampling::Importance)
}

/// Uploads the scene's environment to be sampled as `sampling` says.
pub fn upload_sampled(
    device: &Arc<Device>,
    environment: Option<&Environment>,
    sampling: EnvironmentSampling,
) -> Result<Buffer> {
    let words = environment_words(environment, sampling);
    Buffer::with_data(device, "environment", &words, vk::BufferUsageFlags::STORAGE_BUFFER, 16)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_layout_holds_header_texels_and_both_cdfs() {
        let e = Environment::one_texel(4, 2, 1, 1, Vec3::new(1.0, 2.0, 3.0));
        let words = environment_words(Some(&e), EnvironmentSampling::Importance);
        assert_eq!(&words[..3], &[4, 2, 1]);
        assert_eq!(words.len(), HEADER_FLOATS + 4 * 8 + 3 + 2 * 5);
        let texel = HEADER_FLOATS + 4 * (4 + 1);
        assert_eq!(f32::from_bits(words[texel + 2]), 3.0);
        let marginal = HEADER_FLOATS + 4 * 8;
        assert_eq!([0, 1, 2].map(|i| f32::from_bits(words[marginal + i])), [0.0, 0.0, 1.0]);
        assert_eq!(
            environment_words(None, EnvironmentSampling::Importance)[2],
            0,
            "no environment: the present flag is 0"
        );
    }
}
