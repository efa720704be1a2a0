//! Headless frame capture: copies an image into a host-visible buffer with an explicit, tightly packed row
//! pitch and returns the texels.
use super::commands::{buffer_barrier, image_barrier, submit_and_wait, Access};
use super::device::Device;
use super::memory::{texel_size, Buffer, Image, MemoryLocation};
use anyhow::{anyhow, Result};
use ash::vk;
use std::sync::Arc;

/// Texels read back from an image: row `y` starts at `y * row_pitch` bytes.
#[derive(Debug, Clone)]
pub struct Readback {
    pub width: u32,
    pub height: u32,
    pub format: vk::Format,
    pub row_pitch: usize,
    pub texel_size: usize,
    pub bytes: Vec<u8>,
}

impl Readback {
    /// The bytes of texel (x, y).
    pub fn texel(&self, x: u32, y: u32) -> &[u8] {
        let start = y as usize * self.row_pitch + x as usize * self.texel_size;
        &self.bytes[start..start + self.texel_size]
    }

    /// Every texel of an `R32G32B32A32_SFLOAT` image as RGBA, row-major.
    pub fn to_rgba_f32(&self) -> Result<Vec<[f32; 4]>> {
        match self.format {
            vk::Format::R32G32B32A32_SFLOAT => Ok(bytemuck::pod_collect_to_vec(&self.bytes)),
            vk::Format::R16G16B16A16_SFLOAT => {
                let halves: Vec<u16> = bytemuck::pod_collect_to_vec(&self.bytes);
                Ok(halves
                    .chunks_exact(4)
                    .map(|c| std::array::from_fn(|i| half::f16::from_bits(c[i]).to_f32()))
                    .collect())
            }
            vk::Format::R8G8B8A8_UNORM => {
                Ok(self.bytes.chunks_exact(4).map(|c| std::array::from_fn(|i| f32::from(c[i]) / 255.0)).collect())
            }
            vk::Format::R8G8B8A8_SRGB => Ok(self
                .bytes
                .chunks_exact(4)
                .map(|c| {
                    let unorm = |v: u8| f32::from(v) / 255.0;
                    let linear = |v: u8| crate::output::srgb_to_linear(unorm(v));
                    [linear(c[0]), linear(c[1]), linear(c[2]), unorm(c[3])]
                })
                .collect()),
            other => Err(anyhow!("cannot convert {other:?} texels to RGBA float")),
        }
    }

    /// Every texel of an `R32G32B32A32_UINT` image, row-major.
    pub fn to_uvec4(&self) -> Result<Vec<[u32; 4]>> {
        match self.format {
            vk::Format::R32G32B32A32_UINT => Ok(bytemuck::pod_collect_to_vec(&self.bytes)),
            other => Err(anyhow!("cannot read {other:?} texels as four unsigned integers")),
        }
    }
}

/// Copies `image` (currently in `layout`, last touched by `last_access`) to the host. The image is left in
/// `TRANSFER_SRC_OPTIMAL`.
pub fn read_image(
    device: &Arc<Device>,
    image: &Image,
    layout: vk::ImageLayout,
    last_access: Access,
) -> Result<Readback> {
    let texel = texel_size(image.format)
        .ok_or_else(|| anyhow!("image \"{}\": cannot read back format {:?}", image.name, image.format))?;
    let (width, height) = (image.extent.width, image.extent.height);
    let row_pitch = width as usize * texel;
    let size = row_pitch * height as usize;
    let buffer = Buffer::new(
        device,
        &format!("{} readback", image.name),
        size as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
        1,
    )?;
    submit_and_wait(device, &format!("read back {}", image.name), |cmd| {
        image_barrier(
            device,
            cmd,
            image,
            (layout, last_access),
            (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, Access::TRANSFER_READ),
        );
        let region = vk::BufferImageCopy::default()
            .buffer_offset(0)
            .buffer_row_length(width) // in texels: rows are tightly packed, row_pitch = width * texel
            .buffer_image_height(height)
            .image_subresource(
                vk::ImageSubresourceLayers::default().aspect_mask(image.aspect).mip_level(0).layer_count(1),
            )
            .image_extent(vk::Extent3D { width, height, depth: 1 });
        unsafe {
            device.raw.cmd_copy_image_to_buffer(
                cmd,
                image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            )
        };
        buffer_barrier(device, cmd, &buffer, Access::TRANSFER_WRITE, Access::HOST_READ);
        Ok(())
    })?;
    Ok(Readback { width, height, format: image.format, row_pitch, texel_size: texel, bytes: buffer.mapped()?.to_vec() })
}

/// Copies a device-local buffer (last touched by `last_access`) to the host as `T`s.
pub fn read_buffer<T: bytemuck::Pod>(device: &Arc<Device>, buffer: &Buffer, last_access: Access) -> Result<Vec<T>> {
    let staging = Buffer::new(
        device,
        &format!("{} readback", buffer.name),
        buffer.size,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
        1,
    )?;
    submit_and_wait(device, &format!("read back {}", buffer.name), |cmd| {
        buffer_barrier(device, cmd, buffer, last_access, Access::TRANSFER_READ);
        let region = [vk::BufferCopy::default().size(buffer.size)];
        unsafe { device.raw.cmd_copy_buffer(cmd, buffer.raw, staging.raw, &region) };
        buffer_barrier(device, cmd, &staging, Access::TRANSFER_WRITE, Access::HOST_READ);
        Ok(())
    })?;
    staging.read()
}
