//! Texture samplers: filters and address modes, named, destroyed with their owner.
use super::device::Device;
use anyhow::{Context as _, Result};
use ash::vk;
use std::sync::Arc;

/// What a sampler does; maps one to one onto `VkSamplerCreateInfo`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SamplerDesc {
    pub mag_linear: bool,
    pub min_linear: bool,
    pub address_u: vk::SamplerAddressMode,
    pub address_v: vk::SamplerAddressMode,
    /// How minification moves between mip levels; `None`: level 0 only.
    pub mipmaps: Option<vk::SamplerMipmapMode>,
}

pub struct Sampler {
    pub raw: vk::Sampler,
    device: Arc<Device>,
}

impl Sampler {
    pub fn new(device: &Arc<Device>, name: &str, desc: &SamplerDesc) -> Result<Self> {
        let filter = |linear: bool| if linear { vk::Filter::LINEAR } else { vk::Filter::NEAREST };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter(desc.mag_linear))
            .min_filter(filter(desc.min_linear))
            .mipmap_mode(desc.mipmaps.unwrap_or(vk::SamplerMipmapMode::NEAREST))
            .address_mode_u(desc.address_u)
            .address_mode_v(desc.address_v)
            .address_mode_w(vk::SamplerAddressMode::REPEAT)
            .max_lod(if desc.mipmaps.is_some() { vk::LOD_CLAMP_NONE } else { 0.0 });
        let raw =
            unsafe { device.raw.create_sampler(&info, None) }.with_context(|| format!("vkCreateSampler {name}"))?;
        device.set_name(raw, name);
        Ok(Self { raw, device: device.clone() })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        unsafe { self.device.raw.destroy_sampler(self.raw, None) };
    }
}
