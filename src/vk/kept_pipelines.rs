//! The pipelines a device keeps for its lifetime, by what they are built from. Apart from `pipeline.rs`, which
//! builds them, because the device holds the store: the device knows nothing of how a pipeline is made.
use ash::vk;
use std::collections::HashMap;

/// Everything a kept pipeline is built from: two requests with equal keys get the same pipeline.
#[derive(PartialEq, Eq, Hash)]
pub(super) struct PipelineKey {
    pub(super) name: String,
    pub(super) bind_point: vk::PipelineBindPoint,
    /// Each stage's SPIR-V, in the order the pipeline's builder takes them.
    pub(super) spirv: Vec<Vec<u8>>,
    pub(super) bindings: Vec<(u32, vk::DescriptorType, u32, bool)>,
    pub(super) push_constant_size: u32,
    pub(super) constants: Vec<u32>,
    /// A graphics pipeline's fixed-function state (vertex layout, attachment formats, blending, culling), as
    /// words; empty for compute and ray tracing.
    pub(super) fixed_function: Vec<u32>,
}

#[derive(Clone, Copy)]
pub(super) struct KeptHandles {
    pub(super) raw: vk::Pipeline,
    pub(super) layout: vk::PipelineLayout,
    pub(super) set_layout: vk::DescriptorSetLayout,
}

/// The pipelines a device keeps until it is destroyed. Building one is the costly part
/// of a pass on lavapipe even when Mesa's shader disk cache holds its code (the accumulation pipeline: about
/// 0.8 s, 2 s under the validation layer; docs/performance.md), and every render builds its passes anew; kept, a
/// program that renders many frames on one device (an animation, the benchmark, the test suite) builds each
/// variant once.
#[derive(Default)]
pub struct KeptPipelines(pub(super) HashMap<PipelineKey, KeptHandles>);

impl KeptPipelines {
    /// How many distinct pipelines the device holds.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Destroys every kept pipeline; only while the device is being destroyed, when no pass can use them.
    pub(crate) unsafe fn destroy_all(&mut self, device: &ash::Device) {
        for (_, h) in self.0.drain() {
            unsafe {
                device.destroy_pipeline(h.raw, None);
                device.destroy_pipeline_layout(h.layout, None);
                device.destroy_descriptor_set_layout(h.set_layout, None);
            }
        }
    }
}
