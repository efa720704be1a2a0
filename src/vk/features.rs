//! The device features strata needs, listed once: the same table says what a device is checked for (a device
//! that lacks one is not chosen, and `strata info` names it) and what device creation enables. Two lists had
//! drifted apart (descriptorIndexing was enabled and never checked); wgpu-hal keeps one struct for both phases.
use ash::vk;

/// The feature structures strata reads and sets, without a pNext chain of their own: [`DeviceFeatures::chain`]
/// links them for one query or one vkCreateDevice.
#[derive(Default, Clone, Copy)]
pub struct DeviceFeatures {
    pub base: vk::PhysicalDeviceFeatures,
    pub v12: vk::PhysicalDeviceVulkan12Features<'static>,
    pub v13: vk::PhysicalDeviceVulkan13Features<'static>,
    pub acceleration_structure: vk::PhysicalDeviceAccelerationStructureFeaturesKHR<'static>,
    pub ray_query: vk::PhysicalDeviceRayQueryFeaturesKHR<'static>,
    pub ray_tracing_pipeline: vk::PhysicalDeviceRayTracingPipelineFeaturesKHR<'static>,
}

/// Which extension structures go in a chain: only those of extensions the device has (a query) or that are
/// enabled (a device), as VUID-VkPhysicalDeviceFeatures2-pNext-pNext and VUID-VkDeviceCreateInfo-pNext-pNext ask.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FeatureExtensions {
    pub acceleration_structure: bool,
    pub ray_query: bool,
    pub ray_tracing_pipeline: bool,
}

/// The table: each required feature once, as `structure.field => "its name in the spec"`.
macro_rules! required_features {
    ($($group:ident . $field:ident => $name:literal),* $(,)?) => {
        /// Every feature strata requires of any device, by its name in the Vulkan specification.
        pub const REQUIRED_FEATURES: &[&str] = &[$($name),*];

        impl DeviceFeatures {
            /// The required features this (queried) device lacks, by their names in the specification.
            pub fn lacking(&self) -> Vec<&'static str> {
                let mut lacking = Vec::new();
                $(if self.$group.$field == vk::FALSE {
                    lacking.push($name);
                })*
                lacking
            }

            /// Every required feature on, and the ray-tracing ones the device will trace with.
            pub fn to_enable(ray_query: bool, ray_tracing_pipeline: bool) -> Self {
                let mut features = Self::default();
                $(features.$group.$field = vk::TRUE;)*
                features.ray_query.ray_query = vk::Bool32::from(ray_query);
                features.ray_tracing_pipeline.ray_tracing_pipeline = vk::Bool32::from(ray_tracing_pipeline);
                features
            }
        }
    };
}

required_features! {
    base.shader_int64 => "shaderInt64",
    v12.buffer_device_address => "bufferDeviceAddress",
    v12.scalar_block_layout => "scalarBlockLayout",
    v12.descriptor_indexing => "descriptorIndexing",
    v12.runtime_descriptor_array => "runtimeDescriptorArray",
    v12.descriptor_binding_partially_bound => "descriptorBindingPartiallyBound",
    v12.descriptor_binding_variable_descriptor_count => "descriptorBindingVariableDescriptorCount",
    v12.shader_sampled_image_array_non_uniform_indexing => "shaderSampledImageArrayNonUniformIndexing",
    v12.host_query_reset => "hostQueryReset",
    v13.dynamic_rendering => "dynamicRendering",
    v13.synchronization2 => "synchronization2",
    // SPIR-V 1.6 compute shaders declare their size with LocalSizeId (VUID-RuntimeSpirv-LocalSizeId-06434).
    v13.maintenance4 => "maintenance4",
    acceleration_structure.acceleration_structure => "accelerationStructure",
}

impl DeviceFeatures {
    /// `with` gets these structures linked as one `VkPhysicalDeviceFeatures2` chain (for a query, or to chain into
    /// vkCreateDevice); afterwards the links are undone, so no pointer into `self` outlives the call.
    pub fn chain<R>(
        &mut self,
        extensions: FeatureExtensions,
        with: impl FnOnce(&mut vk::PhysicalDeviceFeatures2) -> R,
    ) -> R {
        let result = {
            let mut features2 = vk::PhysicalDeviceFeatures2::default()
                .features(self.base)
                .push_next(&mut self.v12)
                .push_next(&mut self.v13);
            if extensions.acceleration_structure {
                features2 = features2.push_next(&mut self.acceleration_structure);
            }
            if extensions.ray_query {
                features2 = features2.push_next(&mut self.ray_query);
            }
            if extensions.ray_tracing_pipeline {
                features2 = features2.push_next(&mut self.ray_tracing_pipeline);
            }
            let result = with(&mut features2);
            self.base = features2.features;
            result
        };
        self.v12.p_next = std::ptr::null_mut();
        self.v13.p_next = std::ptr::null_mut();
        self.acceleration_structure.p_next = std::ptr::null_mut();
        self.ray_query.p_next = std::ptr::null_mut();
        self.ray_tracing_pipeline.p_next = std::ptr::null_mut();
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_is_enabled_is_what_is_checked() {
        // A device with exactly the features strata enables lacks nothing; without any one it lacks that one.
        let enabled = DeviceFeatures::to_enable(true, true);
        assert!(enabled.lacking().is_empty());
        assert!(REQUIRED_FEATURES.contains(&"descriptorIndexing"), "enabled, so checked too");
        let mut without = enabled;
        without.v12.descriptor_indexing = vk::FALSE;
        assert_eq!(without.lacking(), vec!["descriptorIndexing"]);
        assert_eq!(DeviceFeatures::default().lacking().len(), REQUIRED_FEATURES.len());
    }

    #[test]
    fn a_chain_leaves_no_links_behind() {
        let mut features = DeviceFeatures::to_enable(true, false);
        let all = FeatureExtensions { acceleration_structure: true, ray_query: true, ray_tracing_pipeline: true };
        let links = features.chain(all, |f| {
            let mut n = 0;
            let mut next = f.p_next;
            while !next.is_null() {
                n += 1;
                next = unsafe { (*next.cast::<vk::BaseOutStructure>()).p_next.cast() };
            }
            n
        });
        assert_eq!(links, 5);
        assert!(features.v12.p_next.is_null() && features.ray_tracing_pipeline.p_next.is_null());
        assert_eq!(features.base.shader_int64, vk::TRUE);
    }
}
