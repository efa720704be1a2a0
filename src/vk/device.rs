//! Physical device selection (rendering needs ray queries or a ray-tracing pipeline; discrete, then integrated,
//! then CPU) and the logical device that owns the queue, the allocator and the extension loaders.
use super::features::{DeviceFeatures, FeatureExtensions};
use super::instance::{version_string, Instance, API_VERSION};
use super::kept_pipelines::KeptPipelines;
use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::CStr;
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};

/// `VkPhysicalDeviceRayTracingPipelinePropertiesKHR`'s shader-group limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShaderGroupLimits {
    pub handle_size: u32,
    pub handle_alignment: u32,
    pub base_alignment: u32,
    pub max_recursion_depth: u32,
}

/// Device extensions strata cannot run without. Deferred host operations is required by
/// `VK_KHR_acceleration_structure` (Vulkan spec, extension dependencies). Rays are traced with one of
/// `VK_KHR_ray_query` and `VK_KHR_ray_tracing_pipeline` (`DeviceNeeds`), each enabled where the device has it.
pub const REQUIRED_EXTENSIONS: [&CStr; 2] =
    [ash::khr::acceleration_structure::NAME, ash::khr::deferred_host_operations::NAME];

/// What a device is asked for. Rendering traces rays with ray queries or a ray-tracing pipeline, whichever the
/// device has (an NVIDIA H100 has acceleration structures and ray-tracing pipelines but no ray queries); the ray
/// probe needs ray queries; the raster pass and the compute shaders that trace no rays (the noise and sampler
/// probes) need neither.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DeviceNeeds {
    /// Ray queries or a ray-tracing pipeline (`--trace auto`).
    #[default]
    RayTracing,
    /// Ray queries (`--trace query`, the ray probe).
    RayQueries,
    /// A ray-tracing pipeline (`--trace pipeline`).
    RayTracingPipeline,
    RasterOnly,
}

impl DeviceNeeds {
    /// What the "no device qualifies" error says strata looked for.
    fn describe(self) -> &'static str {
        match self {
            DeviceNeeds::RayTracing => "Vulkan 1.3 with ray queries or a ray-tracing pipeline",
            DeviceNeeds::RayQueries => "Vulkan 1.3 with ray queries",
            DeviceNeeds::RayTracingPipeline => "Vulkan 1.3 with a ray-tracing pipeline",
            DeviceNeeds::RasterOnly => "Vulkan 1.3 with acceleration structures",
        }
    }
}

/// One physical device as `strata info` and device selection see it.
#[derive(Debug, Clone)]
pub struct DeviceReport {
    /// Position in `vkEnumeratePhysicalDevices` order (what `--device INDEX` means).
    pub index: usize,
    pub name: String,
    pub device_type: vk::PhysicalDeviceType,
    pub api_version: u32,
    pub driver_name: String,
    pub driver_info: String,
    /// Ray queries (`VK_KHR_ray_query` and its feature): the compute-shader way to trace.
    pub ray_query: bool,
    /// Ray-tracing pipelines (`VK_KHR_ray_tracing_pipeline` and its feature).
    pub ray_tracing_pipeline: bool,
    /// What the device lacks for anything strata does (both ways to trace need it); empty when nothing.
    pub missing: Vec<String>,
    /// What it lacks for ray queries alone (empty when `ray_query`).
    pub missing_for_query: Vec<String>,
    /// What it lacks for ray-tracing pipelines alone (empty when `ray_tracing_pipeline`).
    pub missing_for_pipeline: Vec<String>,
    pub handle: vk::PhysicalDevice,
}

impl DeviceReport {
    /// Whether strata can render on it (one way to trace or the other).
    pub fn qualifies(&self) -> bool {
        self.qualifies_for(DeviceNeeds::RayTracing)
    }

    pub fn qualifies_for(&self, needs: DeviceNeeds) -> bool {
        self.missing.is_empty()
            && match needs {
                DeviceNeeds::RayTracing => self.ray_query || self.ray_tracing_pipeline,
                DeviceNeeds::RayQueries => self.ray_query,
                DeviceNeeds::RayTracingPipeline => self.ray_tracing_pipeline,
                DeviceNeeds::RasterOnly => true,
            }
    }

    /// One line on what the device can do for strata, or lacks for each way to trace.
    pub fn status(&self) -> String {
        if !self.missing.is_empty() {
            return format!("lacks {}", self.missing.join(", "));
        }
        match (self.ray_query, self.ray_tracing_pipeline) {
            (true, true) => "ok: ray queries and ray-tracing pipelines".into(),
            (true, false) => {
                format!("ok: ray queries (no ray-tracing pipelines: lacks {})", self.missing_for_pipeline.join(", "))
            }
            (false, true) => {
                format!("ok: ray-tracing pipelines (no ray queries: lacks {})", self.missing_for_query.join(", "))
            }
            (false, false) => format!(
                "cannot trace rays: lacks {} for ray queries and {} for ray-tracing pipelines",
                self.missing_for_query.join(", "),
                self.missing_for_pipeline.join(", ")
            ),
        }
    }

    pub fn type_name(&self) -> &'static str {
        match self.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        }
    }

    fn preference(&self) -> u32 {
        match self.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => 0,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 3,
            _ => 4,
        }
    }

    pub fn api_version_string(&self) -> String {
        version_string(self.api_version)
    }
}

/// Every physical device with what it supports and lacks.
pub fn enumerate_devices(instance: &Instance) -> Result<Vec<DeviceReport>> {
    let physicals = unsafe { instance.raw.enumerate_physical_devices() }.context("vkEnumeratePhysicalDevices")?;
    physicals.into_iter().enumerate().map(|(index, handle)| report_device(instance, index, handle)).collect()
}

fn report_device(instance: &Instance, index: usize, handle: vk::PhysicalDevice) -> Result<DeviceReport> {
    let raw = &instance.raw;
    let properties = unsafe { raw.get_physical_device_properties(handle) };
    let name = properties.device_name_as_c_str().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let extensions = unsafe { raw.enumerate_device_extension_properties(handle) }
        .with_context(|| format!("vkEnumerateDeviceExtensionProperties for {name}"))?;
    let has = |n: &CStr| extensions.iter().any(|e| e.extension_name_as_c_str().ok() == Some(n));

    let mut missing = Vec::new();
    if properties.api_version < API_VERSION {
        missing.push(format!("Vulkan 1.3 (has {})", version_string(properties.api_version)));
    }
    for ext in REQUIRED_EXTENSIONS {
        if !has(ext) {
            missing.push(ext.to_string_lossy().into_owned());
        }
    }

    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
    let (mut driver_name, mut driver_info) = (String::new(), String::new());
    if properties.api_version >= vk::API_VERSION_1_2 {
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver).push_next(&mut subgroup);
        unsafe { raw.get_physical_device_properties2(handle, &mut props2) };
        driver_name = driver.driver_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        driver_info = driver.driver_info_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    }

    let (mut ray_query, mut ray_tracing_pipeline) = (false, false);
    let mut missing_for_query = Vec::new();
    let mut missing_for_pipeline = Vec::new();
    if !has(ash::khr::ray_query::NAME) {
        missing_for_query.push(ash::khr::ray_query::NAME.to_string_lossy().into_owned());
    }
    if !has(ash::khr::ray_tracing_pipeline::NAME) {
        missing_for_pipeline.push(ash::khr::ray_tracing_pipeline::NAME.to_string_lossy().into_owned());
    }
    if properties.api_version >= API_VERSION {
        let extensions_there = FeatureExtensions {
            acceleration_structure: has(ash::khr::acceleration_structure::NAME),
            ray_query: has(ash::khr::ray_query::NAME),
            ray_tracing_pipeline: has(ash::khr::ray_tracing_pipeline::NAME),
        };
        let mut queried = DeviceFeatures::default();
        queried.chain(extensions_there, |features| unsafe { raw.get_physical_device_features2(handle, features) });
        for name in queried.lacking() {
            let label = format!("feature {name}");
            if !missing.iter().any(|m| label.ends_with(m.as_str())) {
                missing.push(label);
            }
        }
        // The extension names already say what is missing when the extension itself is absent.
        if has(ash::khr::ray_query::NAME) && queried.ray_query.ray_query == vk::FALSE {
            missing_for_query.push("feature rayQuery".into());
        }
        if has(ash::khr::ray_tracing_pipeline::NAME) && queried.ray_tracing_pipeline.ray_tracing_pipeline == vk::FALSE {
            missing_for_pipeline.push("feature rayTracingPipeline".into());
        }
        // accumulate.comp's subgroups take their runs of pixels from the queue (subgroupBroadcastFirst) and gather
        // their chains (subgroupBallot, subgroupShuffle).
        let needed = vk::SubgroupFeatureFlags::BALLOT | vk::SubgroupFeatureFlags::SHUFFLE;
        if !subgroup.supported_stages.contains(vk::ShaderStageFlags::COMPUTE)
            || !subgroup.supported_operations.contains(needed)
        {
            missing_for_query.push("subgroup ballot and shuffle operations in compute shaders".into());
        }
        ray_query = missing_for_query.is_empty();
        ray_tracing_pipeline = missing_for_pipeline.is_empty();
        if !has(ash::khr::acceleration_structure::NAME) {
            missing.retain(|m| m != "feature accelerationStructure");
        }
    }
    if queue_family_index(instance, handle).is_none() {
        missing.push("a queue family with graphics and compute".into());
    }
    Ok(DeviceReport {
        index,
        name,
        device_type: properties.device_type,
        api_version: properties.api_version,
        driver_name,
        driver_info,
        ray_query,
        ray_tracing_pipeline,
        missing,
        missing_for_query,
        missing_for_pipeline,
        handle,
    })
}

fn queue_family_index(instance: &Instance, handle: vk::PhysicalDevice) -> Option<u32> {
    let families = unsafe { instance.raw.get_physical_device_queue_family_properties(handle) };
    families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        .map(|i| i as u32)
}

/// Picks a device: the one `selector` names (an index, or a case-insensitive part of the name), else the most
/// preferred one that qualifies for `needs`. Errors list every device and what it lacks.
pub fn select_device(reports: &[DeviceReport], selector: Option<&str>, needs: DeviceNeeds) -> Result<usize> {
    let listing = || {
        let mut s = String::new();
        for r in reports {
            s.push_str(&format!(
                "\n  [{}] {} ({}, Vulkan {}): {}",
                r.index,
                r.name,
                r.type_name(),
                r.api_version_string(),
                r.status()
            ));
        }
        if reports.is_empty() {
            s.push_str("\n  (no Vulkan devices found)");
        }
        s
    };
    if let Some(sel) = selector.map(str::trim).filter(|s| !s.is_empty()) {
        let chosen: Vec<&DeviceReport> = match sel.parse::<usize>() {
            Ok(i) => reports.iter().filter(|r| r.index == i).collect(),
            Err(_) => {
                let needle = sel.to_lowercase();
                reports.iter().filter(|r| r.name.to_lowercase().contains(&needle)).collect()
            }
        };
        let report = match chosen.as_slice() {
            [] => bail!("--device {sel:?} matches no Vulkan device; the devices are:{}", listing()),
            [one] => *one,
            many => bail!(
                "--device {sel:?} matches {} devices ({}); use an index; the devices are:{}",
                many.len(),
                many.iter().map(|r| r.name.as_str()).collect::<Vec<_>>().join(", "),
                listing()
            ),
        };
        if !report.qualifies_for(needs) {
            bail!(
                "device [{}] {} cannot run this (it needs {}); the devices are:{}",
                report.index,
                report.name,
                needs.describe(),
                listing()
            );
        }
        return Ok(report.index);
    }
    let what = needs.describe();
    reports
        .iter()
        .filter(|r| r.qualifies_for(needs))
        .min_by_key(|r| (r.preference(), r.index))
        .map(|r| r.index)
        .ok_or_else(|| {
            anyhow!(
                "no Vulkan device supports what strata needs ({what}); \
                 run scripts/setup.sh to install Mesa's lavapipe, which has both ways to trace; the devices are:{}",
                listing()
            )
        })
}

/// Limits strata reads often.
/// The most textures a scene may have: the size of the passes' texture arrays where the device allows it.
pub const MAX_TEXTURE_ARRAY: u32 = 4096;

#[derive(Debug, Clone, Copy)]
pub struct DeviceLimits {
    pub min_scratch_offset_alignment: u64,
    pub max_image_dimension_2d: u32,
    pub timestamp_period_ns: f32,
    pub min_storage_buffer_offset_alignment: u64,
    /// Rasterization snaps vertices to 1/2^bits of a pixel (Vulkan spec, "Rasterization"): what a CPU twin of
    /// the raster pass can expect to agree to.
    pub sub_pixel_precision_bits: u32,
    /// The most sampled images (and samplers) one shader stage and one set may see: what bounds the texture array.
    pub max_sampled_images: u32,
}

/// What a device with `VK_KHR_ray_tracing_pipeline` enabled brings: its commands and its shader-group limits.
pub struct RayTracingPipelines {
    pub loader: ash::khr::ray_tracing_pipeline::Device,
    pub limits: ShaderGroupLimits,
}

/// The logical device and everything bound to its lifetime. Resources hold an `Arc<Device>`; it is destroyed
/// when the last one goes, after the allocator and before the instance (which it keeps alive).
pub struct Device {
    pub raw: ash::Device,
    pub physical: vk::PhysicalDevice,
    pub report: DeviceReport,
    pub limits: DeviceLimits,
    pub queue_family: u32,
    queue: Mutex<vk::Queue>,
    pub accel: ash::khr::acceleration_structure::Device,
    /// Ray-tracing pipelines, where the device has them (`DeviceReport::ray_tracing_pipeline`).
    pub ray_tracing: Option<RayTracingPipelines>,
    pub debug_utils: Option<ash::ext::debug_utils::Device>,
    allocator: Mutex<ManuallyDrop<Allocator>>,
    pub(crate) command_pool: Mutex<vk::CommandPool>,
    kept_pipelines: Mutex<KeptPipelines>,
    pub instance: Arc<Instance>,
}

impl Device {
    /// Creates the logical device on the selected physical device with every feature strata needs, and ray
    /// queries and ray-tracing pipelines wherever the device has them.
    pub fn new(instance: Arc<Instance>, selector: Option<&str>, needs: DeviceNeeds) -> Result<Arc<Self>> {
        let reports = enumerate_devices(&instance)?;
        let index = select_device(&reports, selector, needs)?;
        let report = reports[index].clone();
        let physical = report.handle;
        let queue_family = queue_family_index(&instance, physical)
            .ok_or_else(|| anyhow!("{}: no graphics+compute queue", report.name))?;

        let mut accel_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
        let mut rt_props = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut accel_props);
        if report.ray_tracing_pipeline {
            props2 = props2.push_next(&mut rt_props);
        }
        unsafe { instance.raw.get_physical_device_properties2(physical, &mut props2) };
        let props = props2.properties;
        let limits = DeviceLimits {
            min_scratch_offset_alignment: u64::from(accel_props.min_acceleration_structure_scratch_offset_alignment)
                .max(1),
            max_image_dimension_2d: props.limits.max_image_dimension2_d,
            timestamp_period_ns: props.limits.timestamp_period,
            min_storage_buffer_offset_alignment: props.limits.min_storage_buffer_offset_alignment,
            sub_pixel_precision_bits: props.limits.sub_pixel_precision_bits,
            max_sampled_images: [
                props.limits.max_per_stage_descriptor_sampled_images,
                props.limits.max_per_stage_descriptor_samplers,
                props.limits.max_descriptor_set_sampled_images,
                props.limits.max_descriptor_set_samplers,
            ]
            .into_iter()
            .min()
            .unwrap_or(16),
        };

        let priorities = [1.0f32];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        let (ray_queries, pipelines) = (report.ray_query, report.ray_tracing_pipeline);
        let mut extensions: Vec<*const std::ffi::c_char> = REQUIRED_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
        if ray_queries {
            extensions.push(ash::khr::ray_query::NAME.as_ptr());
        }
        if pipelines {
            extensions.push(ash::khr::ray_tracing_pipeline::NAME.as_ptr());
        }
        // The table of vk::features, as the support check read it.
        let mut enabled = DeviceFeatures::to_enable(ray_queries, pipelines);
        let chained =
            FeatureExtensions { acceleration_structure: true, ray_query: ray_queries, ray_tracing_pipeline: pipelines };
        let created = enabled.chain(chained, |features| {
            let create_info = vk::DeviceCreateInfo::default()
                .queue_create_infos(&queue_info)
                .enabled_extension_names(&extensions)
                .push_next(features);
            unsafe { instance.raw.create_device(physical, &create_info, None) }
        });
        let raw = created.with_context(|| format!("vkCreateDevice on {}", report.name))?;
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.raw.clone(),
            device: raw.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            // Without it binding device-address buffers is invalid (VUID-vkBindBufferMemory-bufferDeviceAddress-03339).
            buffer_device_address: true,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(e) => {
                unsafe { raw.destroy_device(None) };
                return Err(anyhow!(e)).context("creating the memory allocator");
            }
        };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        let command_pool = match unsafe { raw.create_command_pool(&pool_info, None) } {
            Ok(p) => p,
            Err(e) => {
                drop(allocator);
                unsafe { raw.destroy_device(None) };
                return Err(e).context("vkCreateCommandPool");
            }
        };
        let accel = ash::khr::acceleration_structure::Device::new(&instance.raw, &raw);
        let ray_tracing = pipelines.then(|| RayTracingPipelines {
            loader: ash::khr::ray_tracing_pipeline::Device::new(&instance.raw, &raw),
            limits: ShaderGroupLimits {
                handle_size: rt_props.shader_group_handle_size,
                handle_alignment: rt_props.shader_group_handle_alignment,
                base_alignment: rt_props.shader_group_base_alignment,
                max_recursion_depth: rt_props.max_ray_recursion_depth,
            },
        });
        let debug_utils =
            instance.debug_utils.as_ref().map(|_| ash::ext::debug_utils::Device::new(&instance.raw, &raw));
        let device = Arc::new(Self {
            raw,
            physical,
            report,
            limits,
            queue_family,
            queue: Mutex::new(queue),
            accel,
            ray_tracing,
            debug_utils,
            allocator: Mutex::new(ManuallyDrop::new(allocator)),
            command_pool: Mutex::new(command_pool),
            kept_pipelines: Mutex::new(KeptPipelines::default()),
            instance,
        });
        device.set_name(device.raw.handle(), &format!("strata device ({})", device.report.name));
        device.set_name(queue, "strata queue");
        device.set_name(command_pool, "strata command pool");
        Ok(device)
    }

    /// Fails, naming `what` and the device, where the device has no ray queries.
    pub fn require_ray_queries(&self, what: &str) -> Result<()> {
        if !self.report.ray_query {
            bail!(
                "{what} traces rays with VK_KHR_ray_query, which {} lacks ({})",
                self.report.name,
                self.report.missing_for_query.join(", ")
            );
        }
        Ok(())
    }

    /// The ray-tracing pipeline commands and limits, or an error naming `what` and what the device lacks.
    pub fn require_ray_tracing_pipelines(&self, what: &str) -> Result<&RayTracingPipelines> {
        self.ray_tracing.as_ref().ok_or_else(|| {
            anyhow!(
                "{what} traces rays with a ray-tracing pipeline (VK_KHR_ray_tracing_pipeline), which {} lacks ({})",
                self.report.name,
                self.report.missing_for_pipeline.join(", ")
            )
        })
    }

    /// The shader stages that may trace rays on this device, for barriers around the passes that do: compute
    /// (ray queries), and ray tracing where pipelines are enabled (a barrier may name that stage only then:
    /// VUID-VkMemoryBarrier2-srcStageMask-07946).
    pub fn tracing_stages(&self) -> vk::PipelineStageFlags2 {
        if self.ray_tracing.is_some() {
            vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR
        } else {
            vk::PipelineStageFlags2::COMPUTE_SHADER
        }
    }

    /// Gives a Vulkan object a debug-utils name (what validation messages and RenderDoc show).
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        let Some(debug_utils) = &self.debug_utils else { return };
        let Ok(cname) = std::ffi::CString::new(name.replace('\0', " ")) else { return };
        let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&cname);
        // Naming is best effort: a failure here must never fail a render.
        let _ = unsafe { debug_utils.set_debug_utils_object_name(&info) };
    }

    pub fn allocator(&self) -> MutexGuard<'_, ManuallyDrop<Allocator>> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The compute and ray-tracing pipelines this device keeps (`Pipeline::compute_specialized`,
    /// `Pipeline::ray_tracing`).
    pub fn kept_pipelines(&self) -> MutexGuard<'_, KeptPipelines> {
        self.kept_pipelines.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub(crate) fn queue(&self) -> MutexGuard<'_, vk::Queue> {
        self.queue.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Waits until the device is idle (used before teardown and after errors).
    /// The size of the passes' texture arrays: one size for every scene, so one set of pipelines serves them all
    /// (a scene's textures fill the array's first entries). At most [`MAX_TEXTURE_ARRAY`], and within the
    /// device's limits after the other sampled images a pass binds (the accumulation pass's G-buffer).
    pub fn texture_array_size(&self) -> u32 {
        MAX_TEXTURE_ARRAY.min(self.limits.max_sampled_images.saturating_sub(16)).max(1)
    }

    pub fn wait_idle(&self) -> Result<()> {
        let _queue = self.queue();
        unsafe { self.raw.device_wait_idle() }.context("vkDeviceWaitIdle")
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        unsafe {
            let _ = self.raw.device_wait_idle();
            let pool = *self.command_pool.get_mut().unwrap_or_else(|p| p.into_inner());
            self.raw.destroy_command_pool(pool, None);
            self.kept_pipelines.get_mut().unwrap_or_else(|p| p.into_inner()).destroy_all(&self.raw);
            // The allocator frees its memory blocks; it must go before the device.
            ManuallyDrop::drop(self.allocator.get_mut().unwrap_or_else(|p| p.into_inner()));
            self.raw.destroy_device(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NO_QUERY: &str = "VK_KHR_ray_query";
    const NO_PIPELINE: &str = "VK_KHR_ray_tracing_pipeline";

    /// A device with `missing` lacking for everything, and ray queries and pipelines as given.
    fn report(index: usize, device_type: vk::PhysicalDeviceType, query: bool, pipeline: bool) -> DeviceReport {
        DeviceReport {
            index,
            name: format!("device {index}"),
            device_type,
            api_version: API_VERSION,
            driver_name: String::new(),
            driver_info: String::new(),
            ray_query: query,
            ray_tracing_pipeline: pipeline,
            missing: Vec::new(),
            missing_for_query: if query { vec![] } else { vec![NO_QUERY.into()] },
            missing_for_pipeline: if pipeline { vec![] } else { vec![NO_PIPELINE.into()] },
            handle: vk::PhysicalDevice::null(),
        }
    }

    #[test]
    fn each_need_takes_the_devices_that_have_its_way_to_trace() {
        use vk::PhysicalDeviceType as T;
        let both = report(0, T::CPU, true, true);
        let query_only = report(1, T::INTEGRATED_GPU, true, false);
        let pipeline_only = report(2, T::DISCRETE_GPU, false, true);
        let neither = report(3, T::DISCRETE_GPU, false, false);
        let mut old = report(4, T::DISCRETE_GPU, true, true);
        old.missing.push("feature dynamicRendering".into());

        let table = [
            (&both, [true, true, true, true]),
            (&query_only, [true, true, false, true]),
            (&pipeline_only, [true, false, true, true]),
            (&neither, [false, false, false, true]),
            (&old, [false, false, false, false]),
        ];
        let needs = [
            DeviceNeeds::RayTracing,
            DeviceNeeds::RayQueries,
            DeviceNeeds::RayTracingPipeline,
            DeviceNeeds::RasterOnly,
        ];
        for (r, expected) in table {
            for (need, want) in needs.iter().zip(expected) {
                assert_eq!(r.qualifies_for(*need), want, "{} for {need:?}", r.name);
            }
        }

        // Preference: discrete, integrated, CPU; among those that qualify.
        let all = [both.clone(), query_only.clone(), pipeline_only.clone(), neither.clone(), old.clone()];
        assert_eq!(select_device(&all, None, DeviceNeeds::RayTracing).unwrap(), 2, "the GPU with pipelines only");
        assert_eq!(select_device(&all, None, DeviceNeeds::RayQueries).unwrap(), 1);
        assert_eq!(select_device(&all, None, DeviceNeeds::RayTracingPipeline).unwrap(), 2);
        assert_eq!(select_device(&all, None, DeviceNeeds::RasterOnly).unwrap(), 2);
        assert_eq!(select_device(&all[..2], None, DeviceNeeds::RayTracingPipeline).unwrap(), 0);

        // What each device lacks, for each way to trace.
        assert_eq!(both.status(), "ok: ray queries and ray-tracing pipelines");
        assert!(
            pipeline_only.status().contains("no ray queries: lacks VK_KHR_ray_query"),
            "{}",
            pipeline_only.status()
        );
        assert!(query_only.status().contains("no ray-tracing pipelines: lacks VK_KHR_ray_tracing_pipeline"));
        let err =
            select_device(&[neither.clone(), old.clone()], None, DeviceNeeds::RayTracing).unwrap_err().to_string();
        assert!(err.contains("ray queries or a ray-tracing pipeline"), "{err}");
        assert!(
            err.contains("[3] device 3")
                && err.contains("lacks VK_KHR_ray_query for ray queries")
                && err.contains("VK_KHR_ray_tracing_pipeline for ray-tracing pipelines"),
            "{err}"
        );
        assert!(err.contains("[4] device 4") && err.contains("lacks feature dynamicRendering"), "{err}");

        // A device named on the command line must have what is asked of it.
        let err = select_device(&all, Some("1"), DeviceNeeds::RayTracingPipeline).unwrap_err().to_string();
        assert!(err.contains("device [1] device 1 cannot run this") && err.contains("a ray-tracing pipeline"), "{err}");
        assert_eq!(select_device(&all, Some("device 2"), DeviceNeeds::RayTracing).unwrap(), 2);
    }
}
