//! Pipelines built from the embedded SPIR-V: shader modules, one descriptor-set layout and push-constant range
//! per pipeline, compute pipelines, ray-tracing pipelines and dynamic-rendering graphics pipelines. A pass owns
//! its graphics pipeline; compute and ray-tracing pipelines are kept by the device (`KeptPipelines`) and shared by
//! every pass that asks for the same.
pub use super::descriptors::Binding;
use super::descriptors::DescriptorSet;
use super::device::Device;
use super::kept_pipelines::{KeptHandles, PipelineKey};
use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use std::ffi::CStr;
use std::sync::Arc;

const ENTRY: &CStr = c"main";

/// The SPIR-V words of an embedded shader (`shaders::ALL`), checked for the magic number.
pub fn spirv_words(name: &str, bytes: &[u8]) -> Result<Vec<u32>> {
    ash::util::read_spv(&mut std::io::Cursor::new(bytes)).with_context(|| format!("shader {name}: not valid SPIR-V"))
}

/// A shader module that destroys itself.
pub struct ShaderModule {
    pub raw: vk::ShaderModule,
    device: Arc<Device>,
}

impl ShaderModule {
    pub fn new(device: &Arc<Device>, name: &str, spirv: &[u8]) -> Result<Self> {
        Self::from_words(device, name, &spirv_words(name, spirv)?)
    }

    /// The module with its specialization constants `constant_id = i` frozen at `constants[i]` and the blocks
    /// they switch off removed (`spirv_specialize`), and whether that was done: if not (a module without
    /// specialization constants, or with a kind this does not freeze), the module is whole and the pipeline must
    /// pass the constants to the driver.
    pub fn specialized(device: &Arc<Device>, name: &str, spirv: &[u8], constants: &[u32]) -> Result<(Self, bool)> {
        let words = spirv_words(name, spirv)?;
        match super::spirv_specialize::specialize(&words, constants) {
            Some(specialized) => Ok((Self::from_words(device, name, &specialized)?, true)),
            None => Ok((Self::from_words(device, name, &words)?, false)),
        }
    }

    fn from_words(device: &Arc<Device>, name: &str, words: &[u32]) -> Result<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(words);
        let raw = unsafe { device.raw.create_shader_module(&info, None) }
            .with_context(|| format!("vkCreateShaderModule {name}"))?;
        device.set_name(raw, name);
        Ok(Self { raw, device: device.clone() })
    }
}

impl Drop for ShaderModule {
    fn drop(&mut self) {
        unsafe { self.device.raw.destroy_shader_module(self.raw, None) };
    }
}

/// A pipeline, its layout and its descriptor-set layout (set 0).
pub struct Pipeline {
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    pub bind_point: vk::PipelineBindPoint,
    pub bindings: Vec<Binding>,
    pub push_constant_size: u32,
    pub name: String,
    /// The handles belong to the device's `KeptPipelines`, which destroys them with the device.
    kept_by_device: bool,
    device: Arc<Device>,
}

/// The shaders and layout of a ray-tracing pipeline (`Pipeline::ray_tracing`): (file name, SPIR-V) each.
pub struct RayTracingDesc<'a> {
    pub name: &'a str,
    pub raygen: (&'a str, &'a [u8]),
    pub miss: (&'a str, &'a [u8]),
    pub closest_hit: (&'a str, &'a [u8]),
    pub any_hit: Option<(&'a str, &'a [u8])>,
    pub bindings: &'a [Binding],
    pub push_constant_size: u32,
    pub constants: &'a [u32],
}

/// Fixed state of a graphics pipeline; viewport and scissor are dynamic.
pub struct GraphicsDesc<'a> {
    pub name: &'a str,
    pub vertex: (&'a str, &'a [u8]),
    pub fragment: (&'a str, &'a [u8]),
    pub bindings: &'a [Binding],
    pub push_constant_size: u32,
    pub vertex_bindings: &'a [vk::VertexInputBindingDescription],
    pub vertex_attributes: &'a [vk::VertexInputAttributeDescription],
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    /// Additive blending on every colour attachment (else replace).
    pub additive_blend: bool,
    pub cull_mode: vk::CullModeFlags,
}

impl GraphicsDesc<'_> {
    /// The fixed-function state as words, for the key a kept pipeline is found by.
    fn fixed_function_words(&self) -> Vec<u32> {
        let mut words = Vec::new();
        for b in self.vertex_bindings {
            words.extend([b.binding, b.stride, b.input_rate.as_raw() as u32]);
        }
        words.push(u32::MAX);
        for a in self.vertex_attributes {
            words.extend([a.location, a.binding, a.format.as_raw() as u32, a.offset]);
        }
        words.push(u32::MAX);
        words.extend(self.color_formats.iter().map(|f| f.as_raw() as u32));
        words.push(u32::MAX);
        words.push(self.depth_format.map_or(u32::MAX - 1, |f| f.as_raw() as u32));
        words.extend([u32::from(self.additive_blend), self.cull_mode.as_raw()]);
        words
    }
}

impl Pipeline {
    fn new_layout(
        device: &Arc<Device>,
        name: &str,
        bindings: &[Binding],
        push_constant_size: u32,
    ) -> Result<(vk::DescriptorSetLayout, vk::PipelineLayout)> {
        let raw_bindings: Vec<vk::DescriptorSetLayoutBinding> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.kind)
                    .descriptor_count(b.count)
                    .stage_flags(vk::ShaderStageFlags::ALL)
            })
            .collect();
        if let Some(variable) = bindings.iter().find(|b| b.variable) {
            if bindings.iter().any(|b| b.binding > variable.binding) {
                bail!("{name}: the variable-size array at binding {} must be the set's last binding", variable.binding);
            }
        }
        let flags: Vec<vk::DescriptorBindingFlags> = bindings
            .iter()
            .map(|b| {
                if b.variable {
                    vk::DescriptorBindingFlags::PARTIALLY_BOUND | vk::DescriptorBindingFlags::VARIABLE_DESCRIPTOR_COUNT
                } else {
                    vk::DescriptorBindingFlags::empty()
                }
            })
            .collect();
        let mut binding_flags = vk::DescriptorSetLayoutBindingFlagsCreateInfo::default().binding_flags(&flags);
        let mut info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&raw_bindings);
        if bindings.iter().any(|b| b.variable) {
            info = info.push_next(&mut binding_flags);
        }
        let set_layout = unsafe { device.raw.create_descriptor_set_layout(&info, None) }
            .with_context(|| format!("vkCreateDescriptorSetLayout for {name}"))?;
        device.set_name(set_layout, &format!("{name} set layout"));
        let set_layouts = [set_layout];
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::ALL)
            .offset(0)
            .size(push_constant_size)];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_constant_size > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        match unsafe { device.raw.create_pipeline_layout(&info, None) } {
            Ok(layout) => {
                device.set_name(layout, &format!("{name} layout"));
                Ok((set_layout, layout))
            }
            Err(e) => {
                unsafe { device.raw.destroy_descriptor_set_layout(set_layout, None) };
                Err(e).with_context(|| format!("vkCreatePipelineLayout for {name}"))
            }
        }
    }

    /// A compute pipeline from one embedded shader.
    pub fn compute(
        device: &Arc<Device>,
        name: &str,
        shader: (&str, &[u8]),
        bindings: &[Binding],
        push_constant_size: u32,
    ) -> Result<Self> {
        Self::compute_specialized(device, name, shader, bindings, push_constant_size, &[])
    }

    /// A compute pipeline whose 32-bit specialization constants `constant_id = i` take `constants[i]`, frozen
    /// into the module with the branches they switch off removed before the driver reads it
    /// (`ShaderModule::specialized`). Built once per device for each distinct request and kept
    /// (`KeptPipelines`); later requests share it.
    pub fn compute_specialized(
        device: &Arc<Device>,
        name: &str,
        shader: (&str, &[u8]),
        bindings: &[Binding],
        push_constant_size: u32,
        constants: &[u32],
    ) -> Result<Self> {
        let key = PipelineKey {
            name: name.to_owned(),
            bind_point: vk::PipelineBindPoint::COMPUTE,
            spirv: vec![shader.1.to_vec()],
            bindings: bindings.iter().map(|b| (b.binding, b.kind, b.count, b.variable)).collect(),
            push_constant_size,
            constants: constants.to_vec(),
            fixed_function: Vec::new(),
        };
        Self::kept(device, key, bindings, |device, layout, specialization| {
            let (module, frozen) = ShaderModule::specialized(device, shader.0, shader.1, constants)?;
            let mut stage = vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::COMPUTE)
                .module(module.raw)
                .name(ENTRY);
            if let Some(specialization) = specialization.filter(|_| !frozen) {
                stage = stage.specialization_info(specialization);
            }
            let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
            unsafe { device.raw.create_compute_pipelines(vk::PipelineCache::null(), &info, None) }
                .map_err(|(_, e)| anyhow!(e))
                .with_context(|| format!("vkCreateComputePipelines {name}"))
                .map(|p| p[0])
        })
    }

    /// A ray-tracing pipeline (`VK_KHR_ray_tracing_pipeline`) of three shader groups, in this order: the raygen
    /// shader, the miss shader, and one triangle hit group of a closest-hit shader and, where given, an any-hit
    /// shader. Rays recurse no deeper than the raygen shader's own `traceRayEXT` (maxPipelineRayRecursionDepth
    /// 1): bounces are loops in the raygen shader. The specialization constants go to every stage, frozen into
    /// it as for compute. Kept by the device like compute pipelines; `ShaderBindingTable` lays out its group
    /// handles.
    pub fn ray_tracing(device: &Arc<Device>, desc: &RayTracingDesc<'_>) -> Result<Self> {
        let rt = device.require_ray_tracing_pipelines(desc.name)?;
        let mut stages = vec![desc.raygen, desc.miss, desc.closest_hit];
        stages.extend(desc.any_hit);
        let key = PipelineKey {
            name: desc.name.to_owned(),
            bind_point: vk::PipelineBindPoint::RAY_TRACING_KHR,
            spirv: stages.iter().map(|s| s.1.to_vec()).collect(),
            bindings: desc.bindings.iter().map(|b| (b.binding, b.kind, b.count, b.variable)).collect(),
            push_constant_size: desc.push_constant_size,
            constants: desc.constants.to_vec(),
            fixed_function: Vec::new(),
        };
        Self::kept(device, key, desc.bindings, |device, layout, specialization| {
            let kinds = [
                vk::ShaderStageFlags::RAYGEN_KHR,
                vk::ShaderStageFlags::MISS_KHR,
                vk::ShaderStageFlags::CLOSEST_HIT_KHR,
                vk::ShaderStageFlags::ANY_HIT_KHR,
            ];
            let modules = stages
                .iter()
                .map(|s| ShaderModule::specialized(device, s.0, s.1, desc.constants))
                .collect::<Result<Vec<_>>>()?;
            let stage_infos: Vec<vk::PipelineShaderStageCreateInfo> = modules
                .iter()
                .zip(kinds)
                .map(|((module, frozen), kind)| {
                    let info = vk::PipelineShaderStageCreateInfo::default().stage(kind).module(module.raw).name(ENTRY);
                    match specialization.filter(|_| !frozen) {
                        Some(s) => info.specialization_info(s),
                        None => info,
                    }
                })
                .collect();
            let general = |shader: u32| {
                vk::RayTracingShaderGroupCreateInfoKHR::default()
                    .ty(vk::RayTracingShaderGroupTypeKHR::GENERAL)
                    .general_shader(shader)
                    .closest_hit_shader(vk::SHADER_UNUSED_KHR)
                    .any_hit_shader(vk::SHADER_UNUSED_KHR)
                    .intersection_shader(vk::SHADER_UNUSED_KHR)
            };
            let groups = [
                general(0),
                general(1),
                vk::RayTracingShaderGroupCreateInfoKHR::default()
                    .ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
                    .general_shader(vk::SHADER_UNUSED_KHR)
                    .closest_hit_shader(2)
                    .any_hit_shader(if desc.any_hit.is_some() { 3 } else { vk::SHADER_UNUSED_KHR })
                    .intersection_shader(vk::SHADER_UNUSED_KHR),
            ];
            let info = [vk::RayTracingPipelineCreateInfoKHR::default()
                .stages(&stage_infos)
                .groups(&groups)
                .max_pipeline_ray_recursion_depth(1)
                .layout(layout)];
            unsafe {
                rt.loader.create_ray_tracing_pipelines(
                    vk::DeferredOperationKHR::null(),
                    vk::PipelineCache::null(),
                    &info,
                    None,
                )
            }
            .map_err(|(_, e)| anyhow!(e))
            .with_context(|| format!("vkCreateRayTracingPipelinesKHR {}", desc.name))
            .map(|p| p[0])
        })
    }

    /// The pipeline `key` names: the device's kept one, or one `build` makes (given the layout and the
    /// specialization constants, if any) and the device keeps from now on.
    fn kept(
        device: &Arc<Device>,
        key: PipelineKey,
        bindings: &[Binding],
        build: impl FnOnce(&Arc<Device>, vk::PipelineLayout, Option<&vk::SpecializationInfo>) -> Result<vk::Pipeline>,
    ) -> Result<Self> {
        let (name, bind_point, push_constant_size) = (key.name.clone(), key.bind_point, key.push_constant_size);
        // Held while building, so that two threads asking for the same pipeline build it once.
        let mut kept = device.kept_pipelines();
        let handles = match kept.0.get(&key) {
            Some(handles) => *handles,
            None => {
                let (set_layout, layout) = Self::new_layout(device, &name, bindings, push_constant_size)?;
                // Owns the layouts until the pipeline exists, so that a failure below destroys them.
                let mut owner = Self {
                    raw: vk::Pipeline::null(),
                    layout,
                    set_layout,
                    bind_point,
                    bindings: bindings.to_vec(),
                    push_constant_size,
                    name: name.clone(),
                    kept_by_device: false,
                    device: device.clone(),
                };
                let constants = key.constants.as_slice();
                let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
                    .map(|i| vk::SpecializationMapEntry { constant_id: i, offset: 4 * i, size: 4 })
                    .collect();
                let data: &[u8] = bytemuck::cast_slice(constants);
                let specialization = vk::SpecializationInfo::default().map_entries(&entries).data(data);
                owner.raw = build(device, layout, (!constants.is_empty()).then_some(&specialization))?;
                device.set_name(owner.raw, &name);
                owner.kept_by_device = true;
                let handles = KeptHandles { raw: owner.raw, layout, set_layout };
                kept.0.insert(key, handles);
                handles
            }
        };
        Ok(Self {
            raw: handles.raw,
            layout: handles.layout,
            set_layout: handles.set_layout,
            bind_point,
            bindings: bindings.to_vec(),
            push_constant_size,
            name,
            kept_by_device: true,
            device: device.clone(),
        })
    }

    /// A graphics pipeline for dynamic rendering. Kept by the device like compute pipelines: every render builds
    /// its G-buffer pass, and a program that renders many frames (the library's `Renderer`) builds it once.
    pub fn graphics(device: &Arc<Device>, desc: &GraphicsDesc<'_>) -> Result<Self> {
        let key = PipelineKey {
            name: desc.name.to_owned(),
            bind_point: vk::PipelineBindPoint::GRAPHICS,
            spirv: vec![desc.vertex.1.to_vec(), desc.fragment.1.to_vec()],
            bindings: desc.bindings.iter().map(|b| (b.binding, b.kind, b.count, b.variable)).collect(),
            push_constant_size: desc.push_constant_size,
            constants: Vec::new(),
            fixed_function: desc.fixed_function_words(),
        };
        Self::kept(device, key, desc.bindings, |device, layout, _| Self::build_graphics(device, desc, layout))
    }

    fn build_graphics(
        device: &Arc<Device>,
        desc: &GraphicsDesc<'_>,
        layout: vk::PipelineLayout,
    ) -> Result<vk::Pipeline> {
        let vertex = ShaderModule::new(device, desc.vertex.0, desc.vertex.1)?;
        let fragment = ShaderModule::new(device, desc.fragment.0, desc.fragment.1)?;
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vertex.raw)
                .name(ENTRY),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fragment.raw)
                .name(ENTRY),
        ];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(desc.vertex_bindings)
            .vertex_attribute_descriptions(desc.vertex_attributes);
        let input_assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull_mode)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_format.is_some())
            .depth_write_enable(desc.depth_format.is_some())
            .depth_compare_op(vk::CompareOp::LESS);
        let attachment = if desc.additive_blend {
            vk::PipelineColorBlendAttachmentState::default()
                .blend_enable(true)
                .src_color_blend_factor(vk::BlendFactor::ONE)
                .dst_color_blend_factor(vk::BlendFactor::ONE)
                .color_blend_op(vk::BlendOp::ADD)
                .src_alpha_blend_factor(vk::BlendFactor::ONE)
                .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                .alpha_blend_op(vk::BlendOp::ADD)
                .color_write_mask(vk::ColorComponentFlags::RGBA)
        } else {
            vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)
        };
        let attachments = vec![attachment; desc.color_formats.len()];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED));
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering)];
        unsafe { device.raw.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) }
            .map_err(|(_, e)| anyhow!(e))
            .with_context(|| format!("vkCreateGraphicsPipelines {}", desc.name))
            .map(|p| p[0])
    }

    /// A descriptor set for this pipeline's layout, from a pool of its own (a variable-size array, if any, at
    /// its largest).
    pub fn new_descriptor_set(&self, name: &str) -> Result<DescriptorSet> {
        DescriptorSet::new(&self.device, name, self.set_layout, &self.bindings, None)
    }

    /// A descriptor set whose variable-size array holds `variable_count` descriptors.
    pub fn new_descriptor_set_sized(&self, name: &str, variable_count: u32) -> Result<DescriptorSet> {
        DescriptorSet::new(&self.device, name, self.set_layout, &self.bindings, Some(variable_count))
    }

    /// Binds the pipeline, its descriptor set and push constants.
    pub fn bind(&self, cmd: vk::CommandBuffer, set: Option<&DescriptorSet>, push_constants: &[u8]) {
        let device = &self.device.raw;
        unsafe {
            device.cmd_bind_pipeline(cmd, self.bind_point, self.raw);
            if let Some(set) = set {
                device.cmd_bind_descriptor_sets(cmd, self.bind_point, self.layout, 0, &[set.raw], &[]);
            }
            if !push_constants.is_empty() {
                device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::ALL, 0, push_constants);
            }
        }
    }

    /// Pushes `bytes` at `offset` of the bound pipeline's push constants (a member that changes between draws).
    pub fn push_constants_at(&self, cmd: vk::CommandBuffer, offset: u32, bytes: &[u8]) {
        unsafe { self.device.raw.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::ALL, offset, bytes) };
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        if self.kept_by_device {
            return;
        }
        unsafe {
            self.device.raw.destroy_pipeline(self.raw, None);
            self.device.raw.destroy_pipeline_layout(self.layout, None);
            self.device.raw.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
