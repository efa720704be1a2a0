//! Descriptor sets: each set has a small pool of its own sized for its bindings, and a writer that updates
//! buffers, images and acceleration structures by binding number.
use super::device::Device;
use super::memory::{Buffer, Image};
use anyhow::{Context as _, Result};
use ash::vk;
use std::sync::Arc;

/// One descriptor binding of a pipeline's single set.
#[derive(Debug, Clone, Copy)]
pub struct Binding {
    pub binding: u32,
    pub kind: vk::DescriptorType,
    pub count: u32,
    /// An array of up to `count` descriptors of which each set fills as many as it needs (partially bound, its
    /// size given when the set is allocated): the set's last binding, so that one pipeline serves every size.
    pub variable: bool,
}

impl Binding {
    pub const fn new(binding: u32, kind: vk::DescriptorType) -> Self {
        Self { binding, kind, count: 1, variable: false }
    }

    /// A fixed array of `count` descriptors.
    pub const fn array(binding: u32, kind: vk::DescriptorType, count: u32) -> Self {
        Self { binding, kind, count, variable: false }
    }

    /// An array of up to `max` descriptors, sized per set (descriptorBindingVariableDescriptorCount).
    pub const fn variable_array(binding: u32, kind: vk::DescriptorType, max: u32) -> Self {
        Self { binding, kind, count: max, variable: true }
    }
}

pub struct DescriptorSet {
    pub raw: vk::DescriptorSet,
    pool: vk::DescriptorPool,
    device: Arc<Device>,
    /// The layout's bindings (read from the shaders' SPIR-V), which every write is checked against.
    bindings: Vec<Binding>,
}

/// Whether a write of `count` descriptors of type `kind` fits `binding` of a set laid out as `layout`: the
/// layout comes from the shaders (vk::spirv), the writes from Rust, so a binding moved or retyped in GLSL alone
/// is named here, before the driver sees it.
pub fn check_write(layout: &[Binding], binding: u32, kind: vk::DescriptorType, count: u32) -> Result<()> {
    let Some(b) = layout.iter().find(|b| b.binding == binding) else {
        anyhow::bail!("descriptor write to binding {binding} ({kind:?}): the shaders declare no binding {binding}");
    };
    if b.kind != kind {
        anyhow::bail!("descriptor write to binding {binding} as {kind:?}: the shaders declare it {:?}", b.kind);
    }
    if count > b.count {
        anyhow::bail!("descriptor write of {count} to binding {binding}: the shaders declare {}", b.count);
    }
    Ok(())
}

impl DescriptorSet {
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        layout: vk::DescriptorSetLayout,
        bindings: &[Binding],
        variable_count: Option<u32>,
    ) -> Result<Self> {
        let variable = bindings.iter().find(|b| b.variable);
        let variable_count = variable.map(|b| variable_count.unwrap_or(b.count).clamp(1, b.count));
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for b in bindings {
            let count = if b.variable { variable_count.unwrap_or(b.count) } else { b.count };
            match sizes.iter_mut().find(|s| s.ty == b.kind) {
                Some(size) => size.descriptor_count += count,
                None => sizes.push(vk::DescriptorPoolSize { ty: b.kind, descriptor_count: count }),
            }
        }
        let info = vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes);
        let pool = unsafe { device.raw.create_descriptor_pool(&info, None) }
            .with_context(|| format!("vkCreateDescriptorPool for {name}"))?;
        device.set_name(pool, &format!("{name} pool"));
        let layouts = [layout];
        let counts = [variable_count.unwrap_or(0)];
        let mut variable_info =
            vk::DescriptorSetVariableDescriptorCountAllocateInfo::default().descriptor_counts(&counts);
        let mut alloc = vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&layouts);
        if variable_count.is_some() {
            alloc = alloc.push_next(&mut variable_info);
        }
        let raw = match unsafe { device.raw.allocate_descriptor_sets(&alloc) } {
            Ok(sets) => sets[0],
            Err(e) => {
                unsafe { device.raw.destroy_descriptor_pool(pool, None) };
                return Err(e).with_context(|| format!("vkAllocateDescriptorSets for {name}"));
            }
        };
        device.set_name(raw, name);
        Ok(Self { raw, pool, device: device.clone(), bindings: bindings.to_vec() })
    }

    /// A write that does not fit the layout is a mistake in strata, not in its input: it stops here, naming the
    /// binding, rather than reaching the driver.
    fn expect_fits(&self, binding: u32, kind: vk::DescriptorType, count: u32) {
        if let Err(e) = check_write(&self.bindings, binding, kind, count) {
            panic!("{e}");
        }
    }

    /// Points `binding` at a whole storage buffer.
    pub fn storage_buffer(&self, binding: u32, buffer: &Buffer) -> &Self {
        self.buffer(binding, vk::DescriptorType::STORAGE_BUFFER, buffer)
    }

    fn buffer(&self, binding: u32, kind: vk::DescriptorType, buffer: &Buffer) -> &Self {
        self.expect_fits(binding, kind, 1);
        let info = [vk::DescriptorBufferInfo::default().buffer(buffer.raw).offset(0).range(vk::WHOLE_SIZE)];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(kind)
            .buffer_info(&info);
        unsafe { self.device.raw.update_descriptor_sets(&[write], &[]) };
        self
    }

    /// Points `binding` at a storage image in `GENERAL` layout.
    pub fn storage_image(&self, binding: u32, image: &Image) -> &Self {
        self.expect_fits(binding, vk::DescriptorType::STORAGE_IMAGE, 1);
        let info = [vk::DescriptorImageInfo::default().image_view(image.view).image_layout(vk::ImageLayout::GENERAL)];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
            .image_info(&info);
        unsafe { self.device.raw.update_descriptor_sets(&[write], &[]) };
        self
    }

    /// Points the array at `binding` at sampled images (in `SHADER_READ_ONLY_OPTIMAL`) with their samplers.
    pub fn combined_image_samplers(&self, binding: u32, images: &[(vk::ImageView, vk::Sampler)]) -> &Self {
        if images.is_empty() {
            return self;
        }
        self.expect_fits(binding, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, images.len() as u32);
        let infos: Vec<vk::DescriptorImageInfo> = images
            .iter()
            .map(|&(view, sampler)| {
                vk::DescriptorImageInfo::default()
                    .image_view(view)
                    .sampler(sampler)
                    .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            })
            .collect();
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&infos);
        unsafe { self.device.raw.update_descriptor_sets(&[write], &[]) };
        self
    }

    /// Points `binding` at a top-level acceleration structure.
    pub fn acceleration_structure(&self, binding: u32, tlas: vk::AccelerationStructureKHR) -> &Self {
        self.expect_fits(binding, vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, 1);
        let structures = [tlas];
        let mut as_info =
            vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(&structures);
        // The count is not derived from a slice here: the structures travel in the pushed extension struct.
        let mut write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .push_next(&mut as_info);
        write.descriptor_count = 1;
        unsafe { self.device.raw.update_descriptor_sets(&[write], &[]) };
        self
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        // Destroying the pool frees its set.
        unsafe { self.device.raw.destroy_descriptor_pool(self.pool, None) };
    }
}
