//! Filling device-local buffers and sampled images from the host: a staging copy and, for images, their mip
//! chain. Apart from `memory.rs` because it records commands (`commands.rs`), which in turn take buffers and
//! images: memory knows nothing of command buffers, and no two modules of `vk/` import each other.
use super::device::Device;
use super::memory::{full_mip_chain, texel_size, Buffer, Image, MemoryLocation};
use anyhow::{anyhow, bail, Result};
use ash::vk;
use std::sync::Arc;

impl Buffer {
    /// A device-local buffer filled with `data` through a staging copy (what discrete GPUs want for data the
    /// GPU reads often). `usage` gets `TRANSFER_DST` added.
    pub fn device_local_with_data<T: bytemuck::Pod>(
        device: &Arc<Device>,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
        alignment: u64,
    ) -> Result<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let staging =
            Self::with_data(device, &format!("{name} staging"), bytes, vk::BufferUsageFlags::TRANSFER_SRC, 1)?;
        let buffer = Self::new(
            device,
            name,
            bytes.len() as u64,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
            alignment,
        )?;
        super::commands::submit_and_wait(device, &format!("upload {name}"), |cmd| {
            let region = [vk::BufferCopy::default().size(bytes.len() as u64)];
            unsafe { device.raw.cmd_copy_buffer(cmd, staging.raw, buffer.raw, &region) };
            super::commands::buffer_barrier(
                device,
                cmd,
                &buffer,
                super::commands::Access::TRANSFER_WRITE,
                super::commands::Access::ANY_READ_OF_UPLOAD,
            );
            Ok(())
        })?;
        Ok(buffer)
    }
}

impl Image {
    /// A sampled 2D image filled with `texels` (tightly packed rows of `format`) through a staging copy, left in
    /// `SHADER_READ_ONLY_OPTIMAL` for fragment and compute shaders. With `mipmapped`, every level down to 1×1 is
    /// made from the one above by a linear-filtered blit (a 2×2 box, in linear space for sRGB formats) where
    /// the device can blit and filter the format; elsewhere the image keeps one level.
    pub fn sampled_with_data(
        device: &Arc<Device>,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        texels: &[u8],
        mipmapped: bool,
    ) -> Result<Self> {
        let texel = texel_size(format).ok_or_else(|| anyhow!("image \"{name}\": cannot upload format {format:?}"))?;
        let expected = texel * extent.width as usize * extent.height as usize;
        if texels.len() != expected {
            bail!("image \"{name}\": {} bytes given, {expected} needed", texels.len());
        }
        let levels = if mipmapped && can_blit_linear(device, format) { full_mip_chain(extent) } else { 1 };
        let mut usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        if levels > 1 {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let image = Self::new_2d_with_levels(device, name, format, extent, usage, levels)?;
        let staging =
            Buffer::with_data(device, &format!("{name} staging"), texels, vk::BufferUsageFlags::TRANSFER_SRC, 1)?;
        super::commands::submit_and_wait(device, &format!("upload {name}"), |cmd| {
            use super::commands::{image_barrier, Access};
            let copy_or_blit = Access {
                stage: vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::BLIT,
                access: vk::AccessFlags2::TRANSFER_WRITE,
            };
            image_barrier(
                device,
                cmd,
                &image,
                (vk::ImageLayout::UNDEFINED, Access::NONE),
                (vk::ImageLayout::TRANSFER_DST_OPTIMAL, copy_or_blit),
            );
            let region = vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(image.aspect).layer_count(1))
                .image_extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 });
            unsafe {
                device.raw.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            if image.mip_levels == 1 {
                image_barrier(
                    device,
                    cmd,
                    &image,
                    (vk::ImageLayout::TRANSFER_DST_OPTIMAL, Access::TRANSFER_WRITE),
                    (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, Access::SHADER_SAMPLED_READ),
                );
            } else {
                image.record_mip_chain(cmd);
            }
            Ok(())
        })?;
        Ok(image)
    }

    /// Fills levels 1.. from level 0 (which a copy has just written in `TRANSFER_DST_OPTIMAL`), each by a
    /// linear blit of the level above, and leaves every level `SHADER_READ_ONLY_OPTIMAL`.
    fn record_mip_chain(&self, cmd: vk::CommandBuffer) {
        use super::commands::{image_levels_barrier, Access};
        let device = &self.device;
        let size = |level: u32| vk::Offset3D {
            x: (self.extent.width >> level).max(1) as i32,
            y: (self.extent.height >> level).max(1) as i32,
            z: 1,
        };
        let layers =
            |level: u32| vk::ImageSubresourceLayers::default().aspect_mask(self.aspect).mip_level(level).layer_count(1);
        for level in 1..self.mip_levels {
            let written_by = if level == 1 { Access::TRANSFER_WRITE } else { Access::BLIT_WRITE };
            image_levels_barrier(
                device,
                cmd,
                self,
                level - 1..level,
                (vk::ImageLayout::TRANSFER_DST_OPTIMAL, written_by),
                (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, Access::BLIT_READ),
            );
            let blit = vk::ImageBlit::default()
                .src_subresource(layers(level - 1))
                .src_offsets([vk::Offset3D::default(), size(level - 1)])
                .dst_subresource(layers(level))
                .dst_offsets([vk::Offset3D::default(), size(level)]);
            unsafe {
                device.raw.cmd_blit_image(
                    cmd,
                    self.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    self.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[blit],
                    vk::Filter::LINEAR,
                )
            };
        }
        let last = self.mip_levels - 1;
        image_levels_barrier(
            device,
            cmd,
            self,
            0..last,
            (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, Access::BLIT_READ),
            (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, Access::SHADER_SAMPLED_READ),
        );
        image_levels_barrier(
            device,
            cmd,
            self,
            last..self.mip_levels,
            (vk::ImageLayout::TRANSFER_DST_OPTIMAL, Access::BLIT_WRITE),
            (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, Access::SHADER_SAMPLED_READ),
        );
    }
}

/// Whether the device can make mip levels of `format` by linear-filtered blits (optimal tiling).
fn can_blit_linear(device: &Device, format: vk::Format) -> bool {
    let needed = vk::FormatFeatureFlags::BLIT_SRC
        | vk::FormatFeatureFlags::BLIT_DST
        | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
    let properties = unsafe { device.instance.raw.get_physical_device_format_properties(device.physical, format) };
    properties.optimal_tiling_features.contains(needed)
}
