//! Command recording and submission: one-shot command buffers with a fence, debug labels, and
//! synchronization2 barrier helpers.
use super::device::Device;
use super::memory::{Buffer, Image};
use anyhow::{Context as _, Result};
use ash::vk;
use std::sync::Arc;

/// Records commands with `record` into a fresh command buffer labelled `label`, submits it and waits.
/// The command buffer and fence are freed on every path.
pub fn submit_and_wait<R>(
    device: &Arc<Device>,
    label: &str,
    record: impl FnOnce(vk::CommandBuffer) -> Result<R>,
) -> Result<R> {
    let pool_guard = device.command_pool.lock().unwrap_or_else(|p| p.into_inner());
    let pool = *pool_guard;
    let alloc = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .level(vk::CommandBufferLevel::PRIMARY)
        .command_buffer_count(1);
    let cmd = unsafe { device.raw.allocate_command_buffers(&alloc) }
        .with_context(|| format!("vkAllocateCommandBuffers for \"{label}\""))?[0];
    device.set_name(cmd, label);
    let fence = match unsafe { device.raw.create_fence(&vk::FenceCreateInfo::default(), None) } {
        Ok(f) => f,
        Err(e) => {
            unsafe { device.raw.free_command_buffers(pool, &[cmd]) };
            return Err(e).context("vkCreateFence");
        }
    };
    device.set_name(fence, &format!("{label} fence"));
    let result = (|| {
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        unsafe { device.raw.begin_command_buffer(cmd, &begin) }.context("vkBeginCommandBuffer")?;
        begin_label(device, cmd, label);
        let value = record(cmd)?;
        end_label(device, cmd);
        unsafe { device.raw.end_command_buffer(cmd) }.context("vkEndCommandBuffer")?;
        let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos)];
        {
            let queue = device.queue();
            unsafe { device.raw.queue_submit2(*queue, &submit, fence) }
                .with_context(|| format!("vkQueueSubmit2 \"{label}\""))?;
        }
        unsafe { device.raw.wait_for_fences(&[fence], true, u64::MAX) }
            .with_context(|| format!("waiting for \"{label}\""))?;
        Ok(value)
    })();
    if result.is_err() {
        // The command buffer may still be pending if waiting failed.
        let _ = device.wait_idle();
    }
    unsafe {
        device.raw.destroy_fence(fence, None);
        device.raw.free_command_buffers(pool, &[cmd]);
    }
    drop(pool_guard);
    result
}

/// Opens a debug label region (what RenderDoc and validation messages show as the pass name).
pub fn begin_label(device: &Device, cmd: vk::CommandBuffer, label: &str) {
    if let Some(debug_utils) = &device.debug_utils {
        let name = std::ffi::CString::new(label.replace('\0', " ")).unwrap_or_default();
        let info = vk::DebugUtilsLabelEXT::default().label_name(&name);
        unsafe { debug_utils.cmd_begin_debug_utils_label(cmd, &info) };
    }
}

pub fn end_label(device: &Device, cmd: vk::CommandBuffer) {
    if let Some(debug_utils) = &device.debug_utils {
        unsafe { debug_utils.cmd_end_debug_utils_label(cmd) };
    }
}

/// Sets the dynamic viewport (depth 0..1) and scissor to cover all of `extent`.
pub fn set_full_viewport(device: &Device, cmd: vk::CommandBuffer, extent: vk::Extent2D) {
    let viewport =
        vk::Viewport::default().width(extent.width as f32).height(extent.height as f32).min_depth(0.0).max_depth(1.0);
    unsafe {
        device.raw.cmd_set_viewport(cmd, 0, &[viewport]);
        device.raw.cmd_set_scissor(cmd, 0, &[extent.into()]);
    }
}

/// Begins dynamic rendering over all of `extent`: each of `colors` (in `COLOR_ATTACHMENT_OPTIMAL`) cleared to its
/// value and stored, and `depth` (in `DEPTH_ATTACHMENT_OPTIMAL`) cleared to 1 and not stored; then sets the full
/// viewport. The caller draws and ends rendering.
pub fn begin_cleared_rendering(
    device: &Device,
    cmd: vk::CommandBuffer,
    extent: vk::Extent2D,
    colors: &[(&Image, vk::ClearColorValue)],
    depth: &Image,
) {
    let color_attachments: Vec<vk::RenderingAttachmentInfo> = colors
        .iter()
        .map(|(image, clear)| {
            vk::RenderingAttachmentInfo::default()
                .image_view(image.view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { color: *clear })
        })
        .collect();
    let depth_attachment = vk::RenderingAttachmentInfo::default()
        .image_view(depth.view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
    let rendering = vk::RenderingInfo::default()
        .render_area(extent.into())
        .layer_count(1)
        .color_attachments(&color_attachments)
        .depth_attachment(&depth_attachment);
    unsafe { device.raw.cmd_begin_rendering(cmd, &rendering) };
    set_full_viewport(device, cmd, extent);
}

/// Runs `record` inside a labelled region.
pub fn labelled<R>(device: &Device, cmd: vk::CommandBuffer, label: &str, record: impl FnOnce() -> R) -> R {
    begin_label(device, cmd, label);
    let value = record();
    end_label(device, cmd);
    value
}

/// One access scope: the stages and accesses on one side of a barrier.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Access {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
}

impl Access {
    pub const NONE: Access = Access { stage: vk::PipelineStageFlags2::NONE, access: vk::AccessFlags2::NONE };
    pub const TRANSFER_WRITE: Access =
        Access { stage: vk::PipelineStageFlags2::COPY, access: vk::AccessFlags2::TRANSFER_WRITE };
    pub const TRANSFER_READ: Access =
        Access { stage: vk::PipelineStageFlags2::COPY, access: vk::AccessFlags2::TRANSFER_READ };
    pub const BLIT_WRITE: Access =
        Access { stage: vk::PipelineStageFlags2::BLIT, access: vk::AccessFlags2::TRANSFER_WRITE };
    pub const BLIT_READ: Access =
        Access { stage: vk::PipelineStageFlags2::BLIT, access: vk::AccessFlags2::TRANSFER_READ };
    pub const HOST_READ: Access = Access { stage: vk::PipelineStageFlags2::HOST, access: vk::AccessFlags2::HOST_READ };
    pub const COLOR_ATTACHMENT_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
        access: vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
    };
    pub const DEPTH_ATTACHMENT: Access = Access {
        stage: vk::PipelineStageFlags2::from_raw(
            vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw()
                | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
        ),
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
                | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw(),
        ),
    };
    /// Every way strata reads uploaded data: vertex and index input, shaders, acceleration-structure builds.
    /// Named stage by stage (best practices flags `ALL_COMMANDS`).
    pub const ANY_READ_OF_UPLOAD: Access = Access {
        stage: vk::PipelineStageFlags2::from_raw(
            vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT.as_raw()
                | vk::PipelineStageFlags2::INDEX_INPUT.as_raw()
                | vk::PipelineStageFlags2::VERTEX_SHADER.as_raw()
                | vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw()
                | vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw()
                | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR.as_raw(),
        ),
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ.as_raw()
                | vk::AccessFlags2::INDEX_READ.as_raw()
                | vk::AccessFlags2::SHADER_READ.as_raw(),
        ),
    };
    /// Sampled reads in fragment and compute shaders. (SHADER_READ rather than sync2's narrower
    /// SHADER_SAMPLED_READ: best practices 1.3.239 expects it for SHADER_READ_ONLY_OPTIMAL.)
    pub const SHADER_SAMPLED_READ: Access = Access {
        stage: vk::PipelineStageFlags2::from_raw(
            vk::PipelineStageFlags2::FRAGMENT_SHADER.as_raw() | vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw(),
        ),
        access: vk::AccessFlags2::SHADER_READ,
    };
    pub const COMPUTE_READ: Access =
        Access { stage: vk::PipelineStageFlags2::COMPUTE_SHADER, access: vk::AccessFlags2::SHADER_STORAGE_READ };
    /// Storage images and buffers that compute shaders both read and write (accumulation).
    pub const COMPUTE_READ_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::SHADER_STORAGE_READ.as_raw() | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
        ),
    };
    pub const COMPUTE_WRITE: Access =
        Access { stage: vk::PipelineStageFlags2::COMPUTE_SHADER, access: vk::AccessFlags2::SHADER_STORAGE_WRITE };
    pub const AS_BUILD_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
        access: vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
    };
    /// An acceleration-structure build: it writes its structure and scratch, and reads the structures it
    /// refers to (a TLAS its BLASes) and, as an update, its own.
    pub const AS_BUILD_READ_WRITE: Access = Access {
        stage: vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
        access: vk::AccessFlags2::from_raw(
            vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR.as_raw()
                | vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR.as_raw(),
        ),
    };
    pub const AS_BUILD_READ: Access = Access {
        stage: vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
        access: vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
    };
    /// A build's reads of its vertex and index buffers (Vulkan 1.3 §37.2: `SHADER_READ` in the build stage).
    pub const AS_BUILD_INPUT_READ: Access = Access {
        stage: vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
        access: vk::AccessFlags2::SHADER_READ,
    };
    /// Vertex buffers read by a draw.
    pub const VERTEX_INPUT_READ: Access = Access {
        stage: vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT,
        access: vk::AccessFlags2::VERTEX_ATTRIBUTE_READ,
    };
    pub const AS_COMPUTE_READ: Access = Access {
        stage: vk::PipelineStageFlags2::COMPUTE_SHADER,
        access: vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
    };
}

/// A barrier's stage mask as recorded: where pipelines are enabled, the compute stage stands for every stage
/// that may trace rays (`Device::tracing_stages`), so that one `Access` covers the accumulation pass whether it
/// runs as a compute shader or as a ray-tracing pipeline.
pub(super) fn recorded(device: &Device, stage: vk::PipelineStageFlags2) -> vk::PipelineStageFlags2 {
    if stage.contains(vk::PipelineStageFlags2::COMPUTE_SHADER) {
        stage | device.tracing_stages()
    } else {
        stage
    }
}

/// An image layout transition with the two access scopes.
pub fn image_barrier(
    device: &Device,
    cmd: vk::CommandBuffer,
    image: &Image,
    from: (vk::ImageLayout, Access),
    to: (vk::ImageLayout, Access),
) {
    image_levels_barrier(device, cmd, image, 0..image.mip_levels, from, to);
}

/// A layout transition of some mip levels of an image.
pub fn image_levels_barrier(
    device: &Device,
    cmd: vk::CommandBuffer,
    image: &Image,
    levels: std::ops::Range<u32>,
    from: (vk::ImageLayout, Access),
    to: (vk::ImageLayout, Access),
) {
    let range = image.subresource_range().base_mip_level(levels.start).level_count(levels.len() as u32);
    let barrier = [vk::ImageMemoryBarrier2::default()
        .image(image.raw)
        .subresource_range(range)
        .old_layout(from.0)
        .new_layout(to.0)
        .src_stage_mask(recorded(device, from.1.stage))
        .src_access_mask(from.1.access)
        .dst_stage_mask(recorded(device, to.1.stage))
        .dst_access_mask(to.1.access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)];
    let dependency = vk::DependencyInfo::default().image_memory_barriers(&barrier);
    unsafe { device.raw.cmd_pipeline_barrier2(cmd, &dependency) };
}

/// A global memory barrier between two access scopes.
pub fn memory_barrier(device: &Device, cmd: vk::CommandBuffer, from: Access, to: Access) {
    let barrier = [vk::MemoryBarrier2::default()
        .src_stage_mask(recorded(device, from.stage))
        .src_access_mask(from.access)
        .dst_stage_mask(recorded(device, to.stage))
        .dst_access_mask(to.access)];
    let dependency = vk::DependencyInfo::default().memory_barriers(&barrier);
    unsafe { device.raw.cmd_pipeline_barrier2(cmd, &dependency) };
}

/// A barrier on one whole buffer.
pub fn buffer_barrier(device: &Device, cmd: vk::CommandBuffer, buffer: &Buffer, from: Access, to: Access) {
    let barrier = [vk::BufferMemoryBarrier2::default()
        .buffer(buffer.raw)
        .offset(0)
        .size(vk::WHOLE_SIZE)
        .src_stage_mask(recorded(device, from.stage))
        .src_access_mask(from.access)
        .dst_stage_mask(recorded(device, to.stage))
        .dst_access_mask(to.access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)];
    let dependency = vk::DependencyInfo::default().buffer_memory_barriers(&barrier);
    unsafe { device.raw.cmd_pipeline_barrier2(cmd, &dependency) };
}
