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
    pub(super) device: Arc<Device>,
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
    pub(super) device: Arc<Device>,
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
