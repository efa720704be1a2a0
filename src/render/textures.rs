//! The scene's textures on the GPU: one sampled image per glTF texture (sRGB format where materials use it as
//! colour, so sampling returns linear values; with its mip chain where its sampler minifies through mipmaps) and
//! one sampler each. A scene without textures gets one white texel, so texture arrays are never empty.
use crate::scene::{MipFilter, Scene, Wrap};
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
            let mipmaps = match texture.sampler.mipmaps {
                MipFilter::None => None,
                MipFilter::Nearest => Some(vk::SamplerMipmapMode::NEAREST),
                MipFilter::Linear => Some(vk::SamplerMipmapMode::LINEAR),
            };
            let name = &texture.name;
            images.push(Image::sampled_with_data(device, name, format, extent, &image.rgba8, mipmaps.is_some())?);
            let desc = SamplerDesc {
                mag_linear: texture.sampler.mag_linear,
                min_linear: texture.sampler.min_linear,
                address_u: address_mode(texture.sampler.wrap_s),
                address_v: address_mode(texture.sampler.wrap_t),
                mipmaps,
            };
            samplers.push(Sampler::new(device, &format!("{} sampler", texture.name), &desc)?);
        }
        let room = device.texture_array_size() as usize;
        if images.len() > room {
            anyhow::bail!(
                "{}: {} textures, more than the {room} this device's texture array holds",
                scene.source.display(),
                images.len()
            );
        }
        if images.is_empty() {
            let white = [255u8; 4];
            let extent = vk::Extent2D { width: 1, height: 1 };
            let format = vk::Format::R8G8B8A8_UNORM;
            images.push(Image::sampled_with_data(device, "white texel", format, extent, &white, false)?);
            let desc = SamplerDesc {
                mag_linear: false,
                min_linear: false,
                address_u: vk::SamplerAddressMode::REPEAT,
                address_v: vk::SamplerAddressMode::REPEAT,
                mipmaps: None,
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
