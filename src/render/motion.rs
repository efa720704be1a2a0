//! The motion pass (`shaders/motion.vert`, `motion.frag`): the forward flow of deformed instances for the motion
//! AOV. A rigid instance's points all move by one transform, so `render::aov` works its flow out on the host from
//! the G-buffer's position (`AovScene::moves`); a skinned or morphing mesh's points each move their own way. This
//! pass draws those meshes at the frame's time, each vertex carrying where the deformation puts it one frame
//! later, and the rasteriser interpolates both ends: for any point of a triangle, the flow is the projection of the
//! same barycentric point one frame later minus its projection now (docs/outputs.md, "motion").
use super::gbuffer_layout::DEPTH_FORMAT;
use super::SceneOnGpu;
use crate::math::lens::CameraSample;
use crate::output::Frame;
use crate::scene::Scene;
use crate::shaders;
use crate::vk::commands::{begin_cleared_rendering, submit_and_wait, Access};
use crate::vk::frame_graph::{FrameGraph, Use};
use crate::vk::pipeline::{GraphicsDesc, Pipeline};
use crate::vk::readback::read_image;
use crate::vk::{Buffer, Device, Image};
use anyhow::{Context as _, Result};
use ash::vk;
use glam::{Mat4, Vec2, Vec3};
use std::sync::Arc;

/// One draw's record (`MotionDraw` in motion.vert).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MotionDraw {
    world_from_object_now: Mat4,
    clip_from_object_next: Mat4,
    instance_plus_one: u32,
    pad: [u32; 3],
}

/// The push constants (`MotionPush` in both stages).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MotionPush {
    clip_from_world: Mat4,
    image_size: Vec2,
    pad: Vec2,
}

/// One deformed primitive to draw: where its vertices start in the position streams, and its indices.
struct PrimitiveDraw<'a> {
    first_vertex: u64,
    indices: &'a Buffer,
    index_count: u32,
}

/// Both ends of the frame interval the flow spans: the time and the pixel-centre camera at each.
pub struct FlowInterval<'a> {
    pub now: (f32, &'a CameraSample),
    pub next: (f32, &'a CameraSample),
}

/// The flow of `scene`'s deformed instances over `interval`, per pixel of a `width`×`height` image: x and y in
/// pixels, then the instance + 1 whose surface the pass drew there (0 where none), then coverage. None when no
/// instance deforms (the pass is not run).
pub fn deformed_flow(
    device: &Arc<Device>,
    scene: &Scene,
    on_gpu: &SceneOnGpu,
    (width, height): (u32, u32),
    interval: &FlowInterval<'_>,
) -> Result<Option<Frame>> {
    let deformed = scene.deformed_instances();
    if deformed.is_empty() {
        return Ok(None);
    }
    let (now, camera_now) = interval.now;
    let (next, camera_next) = interval.next;
    let nodes_now = scene.node_world_transforms(Some(now));
    let nodes_next = scene.node_world_transforms(Some(next));
    let (transforms_now, transforms_next) =
        (scene.instance_transforms_from(&nodes_now), scene.instance_transforms_from(&nodes_next));
    let (mut positions_now, mut positions_next) = (Vec::<Vec3>::new(), Vec::<Vec3>::new());
    let (mut records, mut draws) = (Vec::new(), Vec::new());
    for &instance in &deformed {
        let mesh = scene.instances[instance].mesh;
        let vertices_at = |nodes: &[Mat4], t: f32| {
            // GpuScene leaves out primitives without triangles; so do the streams (as render::deformed does).
            let vertices = scene.deform_instance(instance, nodes, Some(t)).unwrap_or_default();
            scene.meshes[mesh].primitives.iter().zip(vertices).filter(|(p, _)| !p.indices.is_empty()).map(|(_, v)| v)
        };
        let kept = vertices_at(&nodes_now, now).zip(vertices_at(&nodes_next, next));
        for (gpu, (at_now, at_next)) in on_gpu.geometry.meshes[mesh].primitives.iter().zip(kept) {
            let count = gpu.vertex_count as usize;
            let first_vertex = positions_now.len() as u64;
            for (stream, values) in [(&mut positions_now, &at_now.positions), (&mut positions_next, &at_next.positions)]
            {
                stream.extend(values.iter().copied().chain(std::iter::repeat(Vec3::ZERO)).take(count));
            }
            draws.push(PrimitiveDraw { first_vertex, indices: &gpu.indices, index_count: gpu.index_count });
            records.push(MotionDraw {
                world_from_object_now: transforms_now[instance],
                clip_from_object_next: camera_next.clip_from_world() * transforms_next[instance],
                instance_plus_one: instance as u32 + 1,
                pad: [0; 3],
            });
        }
    }
    if draws.is_empty() {
        return Ok(None);
    }
    let pass = MotionPass::new(device)?;
    let streams = [
        Buffer::with_data(device, "motion positions now", &positions_now, vk::BufferUsageFlags::VERTEX_BUFFER, 16)?,
        Buffer::with_data(device, "motion positions next", &positions_next, vk::BufferUsageFlags::VERTEX_BUFFER, 16)?,
    ];
    let records = Buffer::with_data(device, "motion draws", &records, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
    let push = MotionPush {
        clip_from_world: camera_now.clip_from_world(),
        image_size: Vec2::new(width as f32, height as f32),
        pad: Vec2::ZERO,
    };
    pass.draw(width, height, &streams, &records, &draws, &push).map(Some)
}

struct MotionPass {
    pipeline: Pipeline,
    device: Arc<Device>,
}

impl MotionPass {
    fn new(device: &Arc<Device>) -> Result<Self> {
        let stages = [("motion.vert", shaders::MOTION_VERT), ("motion.frag", shaders::MOTION_FRAG)];
        let bindings = crate::vk::spirv::descriptor_bindings(&stages, 1)?;
        let vertex_bindings: Vec<vk::VertexInputBindingDescription> =
            (0..2).map(|b| vk::VertexInputBindingDescription::default().binding(b).stride(12)).collect();
        let vertex_attributes: Vec<vk::VertexInputAttributeDescription> = (0..2)
            .map(|b| {
                vk::VertexInputAttributeDescription::default()
                    .location(b)
                    .binding(b)
                    .format(vk::Format::R32G32B32_SFLOAT)
            })
            .collect();
        let pipeline = Pipeline::graphics(
            device,
            &GraphicsDesc {
                name: "motion pipeline",
                vertex: stages[0],
                fragment: stages[1],
                bindings: &bindings,
                push_constant_size: std::mem::size_of::<MotionPush>() as u32,
                vertex_bindings: &vertex_bindings,
                vertex_attributes: &vertex_attributes,
                color_formats: &[vk::Format::R32G32B32A32_SFLOAT],
                depth_format: Some(DEPTH_FORMAT),
                additive_blend: false,
                cull_mode: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(Self { pipeline, device: device.clone() })
    }

    /// Clears, draws `draws` (vertex streams now and next, one record each) and reads the flow back.
    fn draw(
        &self,
        width: u32,
        height: u32,
        streams: &[Buffer; 2],
        records: &Buffer,
        draws: &[PrimitiveDraw<'_>],
        push: &MotionPush,
    ) -> Result<Frame> {
        let device = &self.device;
        let extent = vk::Extent2D { width, height };
        let attachment = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
        let flow = Image::new_2d(device, "motion flow", vk::Format::R32G32B32A32_SFLOAT, extent, attachment)?;
        let depth =
            Image::new_2d(device, "motion depth", DEPTH_FORMAT, extent, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?;
        let set = self.pipeline.new_descriptor_set("motion set")?;
        set.storage_buffer(0, records);
        let color_layout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
        let uses = [
            Use::overwrite_image(&flow, color_layout, Access::COLOR_ATTACHMENT_WRITE),
            Use::overwrite_image(&depth, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, Access::DEPTH_ATTACHMENT),
        ];
        let mut graph = FrameGraph::new(device);
        submit_and_wait(device, "motion frame", |cmd| {
            graph.pass(cmd, "motion pass", &uses, || {
                let clear = vk::ClearColorValue { float32: [0.0; 4] };
                begin_cleared_rendering(device, cmd, extent, &[(&flow, clear)], &depth);
                self.pipeline.bind(cmd, Some(&set), bytemuck::bytes_of(push));
                for (index, draw) in draws.iter().enumerate() {
                    let offset = draw.first_vertex * std::mem::size_of::<Vec3>() as u64;
                    unsafe {
                        device.raw.cmd_bind_vertex_buffers(cmd, 0, &[streams[0].raw, streams[1].raw], &[offset; 2]);
                        device.raw.cmd_bind_index_buffer(cmd, draw.indices.raw, 0, vk::IndexType::UINT32);
                        // firstInstance selects the draw's record (gl_InstanceIndex in motion.vert).
                        device.raw.cmd_draw_indexed(cmd, draw.index_count, 1, 0, 0, index as u32);
                    }
                }
                unsafe { device.raw.cmd_end_rendering(cmd) };
            });
            Ok(())
        })?;
        let readback = read_image(device, &flow, color_layout, Access::COLOR_ATTACHMENT_WRITE)?;
        Frame::new(width, height, readback.to_rgba_f32()?).context("motion flow")
    }
}
