//! The scene's textures on the GPU: one sampled image per glTF texture (sRGB format where materials use it as
//! colour, so sampling returns linear values) and one sampler each. A scene without textures gets one white
//! texel, so texture arrays are never empty.
use crate::scene::{Scene, Wrap};
use crate::vk::sampler::{Sampler, SamplerDesc};
use crate::vk::{Device, Image};
use anyhow::{Context as _, Result};
use ash::vk;
use std::sync::Arc;

pub struct GpuTextures {
    pub images: Vec<Image>,
    pub samplers: Vec<Sampler>,
}

fn address_mode(wrap: Wrap) -> vk::SamplerAddressMode {
    match wrap {
        Wrap::Repeat => vk::SamplerAddressMode::REPEAT,
        Wrap::MirroredRepeat => vk::SamplerAddressMode::MIRRORED_REPEAT,
        Wrap::ClampToEdge => vk::SamplerAddressMode::CLAMP_TO_EDGE,
    }
}

impl GpuTextures {
    pub fn upload(device: &Arc<Device>, scene: &Scene) -> Result<Self> {
        let mut images = Vec::new();
        let mut samplers = Vec::new();
        for texture in &scene.textures {
            let image = scene
                .images
                .get(texture.image)
                .with_context(|| format!("texture \"{}\" names missing image {}", texture.name, texture.image))?;
            // glTF 2.0 §3.9.2: colour textures are sRGB-encoded, data textures linear.
            let format = if texture.srgb { vk::Format::R8G8B8A8_SRGB } else { vk::Format::R8G8B8A8_UNORM };
            let extent = vk::Extent2D { width: image.width, height: image.height };
            images.push(Image::sampled_with_data(device, &texture.name, format, extent, &image.rgba8)?);
            let desc = SamplerDesc {
                mag_linear: texture.sampler.mag_linear,
                min_linear: texture.sampler.min_linear,
                address_u: address_mode(texture.sampler.wrap_s),
                address_v: address_mode(texture.sampler.wrap_t),
            };
            samplers.push(Sampler::new(device, &format!("{} sampler", texture.name), &desc)?);
        }
        if images.is_empty() {
            let white = [255u8; 4];
            let extent = vk::Extent2D { width: 1, height: 1 };
            images.push(Image::sampled_with_data(device, "white texel", vk::Format::R8G8B8A8_UNORM, extent, &white)?);
            let desc = SamplerDesc {
                mag_linear: false,
                min_linear: false,
                address_u: vk::SamplerAddressMode::REPEAT,
                address_v: vk::SamplerAddressMode::REPEAT,
            };
            samplers.push(Sampler::new(device, "white texel sampler", &desc)?);
        }
        Ok(Self { images, samplers })
    }

    /// (view, sampler) pairs for a combined-image-sampler array.
    pub fn bindings(&self) -> Vec<(vk::ImageView, vk::Sampler)> {
        self.images.iter().zip(&self.samplers).map(|(i, s)| (i.view, s.raw)).collect()
    }
}
