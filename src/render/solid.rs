//! Flat-coloured triangles given in clip space, drawn into a colour image of any format: the smallest raster
//! pass, used to check rasterization and readback exactly.
use crate::shaders;
use crate::vk::commands::{image_barrier, labelled, submit_and_wait, Access};
use crate::vk::pipeline::{GraphicsDesc, Pipeline};
use crate::vk::readback::{read_image, Readback};
use crate::vk::{Buffer, Device, Image};
use anyhow::Result;
use ash::vk;
use glam::{Vec2, Vec4};
use std::sync::Arc;

/// One draw: triangles (clip-space xy, three vertices each) in one colour.
pub struct SolidDraw<'a> {
    pub vertices: &'a [Vec2],
    pub color: Vec4,
}

pub struct SolidPass {
    pipeline: Pipeline,
    format: vk::Format,
    device: Arc<Device>,
}

impl SolidPass {
    /// `additive`: blend ONE+ONE, so overlapping coverage adds up (how the tests count coverage).
    pub fn new(device: &Arc<Device>, format: vk::Format, additive: bool) -> Result<Self> {
        let vertex_bindings = [vk::VertexInputBindingDescription::default().binding(0).stride(8)];
        let vertex_attributes =
            [vk::VertexInputAttributeDescription::default().location(0).binding(0).format(vk::Format::R32G32_SFLOAT)];
        let pipeline = Pipeline::graphics(
            device,
            &GraphicsDesc {
                name: "solid pipeline",
                vertex: ("solid.vert", shaders::SOLID_VERT),
                fragment: ("solid.frag", shaders::SOLID_FRAG),
                bindings: &[],
                push_constant_size: 16,
                vertex_bindings: &vertex_bindings,
                vertex_attributes: &vertex_attributes,
                color_formats: &[format],
                depth_format: None,
                additive_blend: additive,
                cull_mode: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(Self { pipeline, format, device: device.clone() })
    }

    /// Clears a `width`×`height` image to zero, draws `draws` in order and reads the image back.
    pub fn draw(&self, width: u32, height: u32, draws: &[SolidDraw<'_>]) -> Result<Readback> {
        let device = &self.device;
        let extent = vk::Extent2D { width, height };
        let target = Image::new_2d(
            device,
            "solid target",
            self.format,
            extent,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
        )?;
        let vertex_buffers = draws
            .iter()
            .enumerate()
            .map(|(i, d)| {
                Buffer::with_data(
                    device,
                    &format!("solid vertices {i}"),
                    d.vertices,
                    vk::BufferUsageFlags::VERTEX_BUFFER,
                    16,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        submit_and_wait(device, "solid frame", |cmd| {
            image_barrier(
                device,
                cmd,
                &target,
                (vk::ImageLayout::UNDEFINED, Access::NONE),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, Access::COLOR_ATTACHMENT_WRITE),
            );
            labelled(device, cmd, "solid pass", || unsafe {
                let attachment = [vk::RenderingAttachmentInfo::default()
                    .image_view(target.view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } })];
                let rendering = vk::RenderingInfo::default()
                    .render_area(extent.into())
                    .layer_count(1)
                    .color_attachments(&attachment);
                device.raw.cmd_begin_rendering(cmd, &rendering);
                crate::vk::commands::set_full_viewport(device, cmd, extent);
                for (draw, buffer) in draws.iter().zip(&vertex_buffers) {
                    self.pipeline.bind(cmd, None, bytemuck::bytes_of(&draw.color));
                    device.raw.cmd_bind_vertex_buffers(cmd, 0, &[buffer.raw], &[0]);
                    device.raw.cmd_draw(cmd, draw.vertices.len() as u32, 1, 0, 0);
                }
                device.raw.cmd_end_rendering(cmd);
            });
            Ok(())
        })?;
        read_image(device, &target, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, Access::COLOR_ATTACHMENT_WRITE)
    }
}
