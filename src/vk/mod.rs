//! Thin owners of Vulkan objects, one file per concept. Knows nothing about scenes.
pub mod accel;
pub mod commands;
pub mod context;
pub mod descriptors;
pub mod device;
pub mod features;
pub mod frame_graph;
pub mod instance;
pub mod kept_pipelines;
pub mod memory;
pub mod pipeline;
pub mod readback;
pub mod sampler;
pub mod shader_binding_table;
pub mod spirv;
pub mod spirv_specialize;
pub mod timer;
pub mod upload;
pub mod validation;

pub use context::{Gpu, GpuOptions};
pub use device::{Device, DeviceNeeds};
pub use memory::{Buffer, Image, MemoryLocation};
