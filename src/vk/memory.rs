//! Buffers and images through gpu-allocator, each with a debug-utils name that matches its allocation name.
//! They free themselves on drop (also on error paths), before the device they keep alive.
use super::device::Device;
use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
pub use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Memory for one resource, named like it. `linear`: a buffer or linear-tiling image, which gpu-allocator keeps
/// apart from optimal-tiling images as the spec's bufferImageGranularity asks ("Buffer-Image Granularity").
fn allocate(
    device: &Device,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> Result<Allocation> {
    device
        .allocator()
        .allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })
        .map_err(|e| anyhow!(e))
}

/// A buffer with its memory. `address` is its device address when created with `SHADER_DEVICE_ADDRESS`.
pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    pub address: vk::DeviceAddress,
    pub name: String,
    allocation: Option<Allocation>,
    device: Arc<Device>,
}

impl Buffer {
    /// Creates a named buffer. `alignment` raises the memory alignment above what the driver asks for
    /// (gpu-allocator only honours `requirements.alignment`; acceleration-structure scratch needs more).
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
        alignment: u64,
    ) -> Result<Self> {
        if size == 0 {
            bail!("buffer \"{name}\": size is zero");
        }
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { device.raw.create_buffer(&info, None) }
            .with_context(|| format!("vkCreateBuffer \"{name}\" ({size} bytes)"))?;
        device.set_name(raw, name);
        let mut requirements = unsafe { device.raw.get_buffer_memory_requirements(raw) };
        requirements.alignment = requirements.alignment.max(alignment.max(1));
        let mut buffer =
            Self { raw, size, address: 0, name: name.to_owned(), allocation: None, device: device.clone() };
        let allocation = allocate(device, name, requirements, location, true)
            .with_context(|| format!("allocating {size} bytes for buffer \"{name}\""))?;
        unsafe { device.raw.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }
            .with_context(|| format!("vkBindBufferMemory \"{name}\""))?;
        buffer.allocation = Some(allocation);
        if usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS) {
            let info = vk::BufferDeviceAddressInfo::default().buffer(raw);
            buffer.address = unsafe { device.raw.get_buffer_device_address(&info) };
        }
        Ok(buffer)
    }

    /// A host-visible buffer filled with `data`.
    pub fn with_data<T: bytemuck::Pod>(
        device: &Arc<Device>,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
        alignment: u64,
    ) -> Result<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut buffer = Self::new(device, name, bytes.len() as u64, usage, MemoryLocation::CpuToGpu, alignment)?;
        buffer.write(0, bytes)?;
        Ok(buffer)
    }

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

    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&self) -> Result<&[u8]> {
        let slice = self
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| anyhow!("buffer \"{}\" is not host-visible", self.name))?;
        Ok(&slice[..self.size as usize])
    }

    pub fn write(&mut self, offset: u64, bytes: &[u8]) -> Result<()> {
        let name = self.name.clone();
        let size = self.size;
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| anyhow!("buffer \"{name}\" is not host-visible"))?;
        let end = offset as usize + bytes.len();
        if end as u64 > size {
            bail!("write of {} bytes at {offset} overflows buffer \"{name}\" ({size} bytes)", bytes.len());
        }
        slice[offset as usize..end].copy_from_slice(bytes);
        Ok(())
    }

    /// Reads the mapped contents as `T`s (copied: mapped memory need not be aligned for `T`).
    pub fn read<T: bytemuck::Pod>(&self) -> Result<Vec<T>> {
        let bytes = self.mapped()?;
        let n = bytes.len() / std::mem::size_of::<T>();
        Ok(bytemuck::pod_collect_to_vec(&bytes[..n * std::mem::size_of::<T>()]))
    }

    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        unsafe { self.device.raw.destroy_buffer(self.raw, None) };
        if let Some(allocation) = self.allocation.take() {
            let _ = self.device.allocator().free(allocation);
        }
    }
}

/// A 2D image and a default view of all its mip levels.
pub struct Image {
    pub raw: vk::Image,
    pub view: vk::ImageView,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub mip_levels: u32,
    pub aspect: vk::ImageAspectFlags,
    pub name: String,
    allocation: Option<Allocation>,
    device: Arc<Device>,
}

impl Image {
    pub fn new_2d(
        device: &Arc<Device>,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        usage: vk::ImageUsageFlags,
    ) -> Result<Self> {
        Self::new_2d_with_levels(device, name, format, extent, usage, 1)
    }

    /// A 2D image with `mip_levels` levels (at most a full chain down to 1×1).
    pub fn new_2d_with_levels(
        device: &Arc<Device>,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        usage: vk::ImageUsageFlags,
        mip_levels: u32,
    ) -> Result<Self> {
        let max = device.limits.max_image_dimension_2d;
        if extent.width == 0 || extent.height == 0 || extent.width > max || extent.height > max {
            bail!(
                "image \"{name}\": size {}x{} is outside what the device allows (1..={max} per side)",
                extent.width,
                extent.height
            );
        }
        let aspect = if is_depth_format(format) { vk::ImageAspectFlags::DEPTH } else { vk::ImageAspectFlags::COLOR };
        let mip_levels = mip_levels.clamp(1, full_mip_chain(extent));
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 })
            .mip_levels(mip_levels)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { device.raw.create_image(&info, None) }
            .with_context(|| format!("vkCreateImage \"{name}\" {format:?} {}x{}", extent.width, extent.height))?;
        device.set_name(raw, name);
        let mut image = Self {
            raw,
            view: vk::ImageView::null(),
            format,
            extent,
            mip_levels,
            aspect,
            name: name.to_owned(),
            allocation: None,
            device: device.clone(),
        };
        let requirements = unsafe { device.raw.get_image_memory_requirements(raw) };
        let allocation = allocate(device, name, requirements, MemoryLocation::GpuOnly, false)
            .with_context(|| format!("allocating memory for image \"{name}\""))?;
        unsafe { device.raw.bind_image_memory(raw, allocation.memory(), allocation.offset()) }
            .with_context(|| format!("vkBindImageMemory \"{name}\""))?;
        image.allocation = Some(allocation);
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(image.subresource_range());
        image.view = unsafe { device.raw.create_image_view(&view_info, None) }
            .with_context(|| format!("vkCreateImageView \"{name}\""))?;
        device.set_name(image.view, &format!("{name} view"));
        Ok(image)
    }

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

    pub fn subresource_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default().aspect_mask(self.aspect).level_count(self.mip_levels).layer_count(1)
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            if self.view != vk::ImageView::null() {
                self.device.raw.destroy_image_view(self.view, None);
            }
            self.device.raw.destroy_image(self.raw, None);
        }
        if let Some(allocation) = self.allocation.take() {
            let _ = self.device.allocator().free(allocation);
        }
    }
}

/// The number of levels of a full mip chain: halving the larger side down to 1.
pub fn full_mip_chain(extent: vk::Extent2D) -> u32 {
    32 - extent.width.max(extent.height).max(1).leading_zeros()
}

/// Whether the device can make mip levels of `format` by linear-filtered blits (optimal tiling).
fn can_blit_linear(device: &Device, format: vk::Format) -> bool {
    let needed = vk::FormatFeatureFlags::BLIT_SRC
        | vk::FormatFeatureFlags::BLIT_DST
        | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
    let properties = unsafe { device.instance.raw.get_physical_device_format_properties(device.physical, format) };
    properties.optimal_tiling_features.contains(needed)
}

pub fn is_depth_format(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::D16_UNORM
            | vk::Format::D32_SFLOAT
            | vk::Format::D24_UNORM_S8_UINT
            | vk::Format::D32_SFLOAT_S8_UINT
            | vk::Format::X8_D24_UNORM_PACK32
    )
}

/// Bytes per texel of the colour formats strata reads back.
pub fn texel_size(format: vk::Format) -> Option<usize> {
    Some(match format {
        vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_UNORM => 4,
        vk::Format::R32_SFLOAT | vk::Format::R32_UINT | vk::Format::D32_SFLOAT => 4,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32G32_SFLOAT | vk::Format::R32G32_UINT => 8,
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        _ => return None,
    })
}
