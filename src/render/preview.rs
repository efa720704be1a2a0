//! The first-frame preview pass: rasterizes every placed mesh with simple view-space shading into a linear
//! RGBA32F image (dynamic rendering, depth tested). The full G-buffer and accumulation passes replace it.
use super::gpu_scene::GpuScene;
use super::textures::GpuTextures;
use crate::output::Frame;
use crate::scene::Scene;
use crate::shaders;
use crate::shaders::constants::{PREVIEW_BINDING_DRAWS, PREVIEW_BINDING_TEXTURES};
use crate::vk::commands::{image_barrier, labelled, submit_and_wait, Access};
use crate::vk::pipeline::{Binding, GraphicsDesc, Pipeline};
use crate::vk::readback::read_image;
use crate::vk::{Buffer, Device, Image};
use anyhow::{bail, Result};
use ash::vk;
use glam::{Mat3, Mat4, Vec4};
use std::sync::Arc;

/// Unit vector towards the preview's key light, in view space; mirrors `KEY_DIRECTION` in `preview.frag`.
pub const KEY_DIRECTION: glam::Vec3 = glam::Vec3::new(1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0);
/// Ambient fraction of the preview shading; mirrors `AMBIENT` in `preview.frag`.
pub const AMBIENT: f32 = 0.15;

/// The preview's shading of a surface with unit view-space normal `n` facing the viewer (CPU twin of
/// `preview.frag`): base · (ambient + (1 − ambient) · max(n·key, 0)).
pub fn preview_shade(base_color: glam::Vec3, view_normal: glam::Vec3) -> glam::Vec3 {
    base_color * (AMBIENT + (1.0 - AMBIENT) * view_normal.dot(KEY_DIRECTION).max(0.0))
}

pub const COLOR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Per-draw data; mirrors `PreviewDraw` in `shaders/include/preview_layout.glsl` (std430).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PreviewDraw {
    pub clip_from_object: Mat4,
    pub view_normal_rows: [Vec4; 3],
    pub base_color: Vec4,
    pub uv_transform_rows: [Vec4; 2],
    pub base_color_texture: i32,
    pub pad: [i32; 3],
}

#[derive(Debug, Clone, Copy)]
pub struct PreviewSettings {
    pub width: u32,
    pub height: u32,
    /// Linear RGB of pixels no surface covers (opaque).
    pub background: [f32; 3],
}

pub struct PreviewPass {
    pipeline: Pipeline,
    device: Arc<Device>,
}

impl PreviewPass {
    /// The pass's descriptor bindings, as `preview_layout.glsl` and `preview.frag` declare them, read from their
    /// SPIR-V. `texture_array`: the most textures the texture array holds (`Device::texture_array_size`).
    pub fn bindings(texture_array: u32) -> Result<Vec<Binding>> {
        let stages = [("preview.vert", shaders::PREVIEW_VERT), ("preview.frag", shaders::PREVIEW_FRAG)];
        crate::vk::spirv::descriptor_bindings(&stages, texture_array)
    }

    /// The preview pipeline: one for every scene, whatever its texture count.
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let vertex_bindings = [
            vk::VertexInputBindingDescription::default().binding(0).stride(12),
            vk::VertexInputBindingDescription::default().binding(1).stride(12),
            vk::VertexInputBindingDescription::default().binding(2).stride(8),
            vk::VertexInputBindingDescription::default().binding(3).stride(16),
        ];
        let vertex_attributes = [
            vk::VertexInputAttributeDescription::default().location(0).binding(0).format(vk::Format::R32G32B32_SFLOAT),
            vk::VertexInputAttributeDescription::default().location(1).binding(1).format(vk::Format::R32G32B32_SFLOAT),
            vk::VertexInputAttributeDescription::default().location(2).binding(2).format(vk::Format::R32G32_SFLOAT),
            vk::VertexInputAttributeDescription::default()
                .location(3)
                .binding(3)
                .format(vk::Format::R32G32B32A32_SFLOAT),
        ];
        let bindings = Self::bindings(device.texture_array_size())?;
        let pipeline = Pipeline::graphics(
            device,
            &GraphicsDesc {
                name: "preview pipeline",
                vertex: ("preview.vert", shaders::PREVIEW_VERT),
                fragment: ("preview.frag", shaders::PREVIEW_FRAG),
                bindings: &bindings,
                push_constant_size: 0,
                vertex_bindings: &vertex_bindings,
                vertex_attributes: &vertex_attributes,
                color_formats: &[COLOR_FORMAT],
                depth_format: Some(DEPTH_FORMAT),
                additive_blend: false,
                cull_mode: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(Self { pipeline, device: device.clone() })
    }

    /// Renders the scene from its camera (or a framing default) and reads the picture back.
    pub fn render(
        &self,
        scene: &Scene,
        gpu_scene: &GpuScene,
        textures: &GpuTextures,
        settings: &PreviewSettings,
    ) -> Result<Frame> {
        let device = &self.device;
        let (width, height) = (settings.width, settings.height);
        if width == 0 || height == 0 {
            bail!("image size {width}x{height}: width and height must be at least 1");
        }
        let extent = vk::Extent2D { width, height };
        let color = Image::new_2d(
            device,
            "preview color",
            COLOR_FORMAT,
            extent,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
        )?;
        let depth = Image::new_2d(
            device,
            "preview depth",
            DEPTH_FORMAT,
            extent,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?;
        let camera = scene.camera_or_default();
        let view_from_world = camera.view_from_world();
        let clip_from_world = camera.clip_from_view(width as f32 / height as f32) * view_from_world;

        let (mut draws, reads_uv1) = draw_records(scene, gpu_scene, textures, view_from_world, clip_from_world);
        if draws.is_empty() {
            // An empty scene still binds a valid buffer.
            draws.push(bytemuck::Zeroable::zeroed());
        }
        let draw_buffer = Buffer::with_data(device, "preview draws", &draws, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
        let set = self.pipeline.new_descriptor_set_sized("preview set", textures.bindings().len() as u32)?;
        set.storage_buffer(PREVIEW_BINDING_DRAWS, &draw_buffer)
            .combined_image_samplers(PREVIEW_BINDING_TEXTURES, &textures.bindings());

        submit_and_wait(device, "preview frame", |cmd| {
            image_barrier(
                device,
                cmd,
                &color,
                (vk::ImageLayout::UNDEFINED, Access::NONE),
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, Access::COLOR_ATTACHMENT_WRITE),
            );
            image_barrier(
                device,
                cmd,
                &depth,
                (vk::ImageLayout::UNDEFINED, Access::NONE),
                (vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, Access::DEPTH_ATTACHMENT),
            );
            labelled(device, cmd, "preview pass", || {
                let [r, g, b] = settings.background;
                let clear = vk::ClearColorValue { float32: [r, g, b, 1.0] };
                crate::vk::commands::begin_cleared_rendering(device, cmd, extent, &[(&color, clear)], &depth);
                self.pipeline.bind(cmd, Some(&set), &[]);
                let primitives = scene.instances.iter().flat_map(|i| gpu_scene.meshes[i.mesh].primitives.iter());
                for ((draw_index, primitive), &uv1) in primitives.enumerate().zip(&reads_uv1) {
                    let uvs = if uv1 { primitive.uvs1.raw } else { primitive.uvs.raw };
                    unsafe {
                        device.raw.cmd_bind_vertex_buffers(
                            cmd,
                            0,
                            &[primitive.positions.raw, primitive.normals.raw, uvs, primitive.colors.raw],
                            &[0, 0, 0, 0],
                        );
                        device.raw.cmd_bind_index_buffer(cmd, primitive.indices.raw, 0, vk::IndexType::UINT32);
                        // firstInstance selects the draw record (gl_InstanceIndex in preview.vert).
                        device.raw.cmd_draw_indexed(cmd, primitive.index_count, 1, 0, 0, draw_index as u32);
                    }
                }
                unsafe { device.raw.cmd_end_rendering(cmd) };
            });
            Ok(())
        })?;
        let readback =
            read_image(device, &color, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, Access::COLOR_ATTACHMENT_WRITE)?;
        Frame::new(width, height, readback.to_rgba_f32()?)
    }
}

/// One record per (instance, primitive), in draw order; and which UV set each draw's texture reads.
fn draw_records(
    scene: &Scene,
    gpu_scene: &GpuScene,
    textures: &GpuTextures,
    view_from_world: Mat4,
    clip_from_world: Mat4,
) -> (Vec<PreviewDraw>, Vec<bool>) {
    let mut draws = Vec::new();
    let mut reads_uv1 = Vec::new();
    for instance in &scene.instances {
        let view_normal = Mat3::from_mat4(view_from_world * instance.world_from_object).inverse().transpose();
        for primitive in &gpu_scene.meshes[instance.mesh].primitives {
            let material = primitive.material.and_then(|m| scene.materials.get(m)).cloned().unwrap_or_default();
            let texture = material.base_color_texture.filter(|t| t.texture < textures.images.len());
            let uv = texture.and_then(|t| t.transform).map(|t| t.matrix()).unwrap_or(Mat3::IDENTITY);
            draws.push(PreviewDraw {
                clip_from_object: clip_from_world * instance.world_from_object,
                view_normal_rows: [0, 1, 2].map(|r| view_normal.row(r).extend(0.0)),
                base_color: material.base_color,
                uv_transform_rows: [uv.row(0).extend(0.0), uv.row(1).extend(0.0)],
                base_color_texture: texture.map(|t| t.texture as i32).unwrap_or(crate::shaders::constants::NO_TEXTURE),
                pad: [0; 3],
            });
            reads_uv1.push(texture.is_some_and(|t| t.tex_coord == 1));
        }
    }
    (draws, reads_uv1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draw_record_matches_the_glsl_layout() {
        // std430: mat4 at 0, vec4[3] at 64, vec4 at 112, vec4[2] at 128, int at 160, padded to 176.
        assert_eq!(std::mem::size_of::<PreviewDraw>(), 176);
        assert_eq!(std::mem::offset_of!(PreviewDraw, view_normal_rows), 64);
        assert_eq!(std::mem::offset_of!(PreviewDraw, base_color), 112);
        assert_eq!(std::mem::offset_of!(PreviewDraw, uv_transform_rows), 128);
        assert_eq!(std::mem::offset_of!(PreviewDraw, base_color_texture), 160);
    }
}
