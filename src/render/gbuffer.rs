//! The G-buffer pass: for one camera sample (lens point, jitter) and one time, rasterizes every instance into the
//! attachments of `gbuffer_layout` with dynamic rendering; the fragment shader evaluates the material and the
//! Blinn bump-mapped normal. One pipeline draws every material: materials in a storage buffer, textures in a
//! combined-image-sampler array indexed per material.
use super::deformed::{DeformedStreams, DEFORMED_STREAMS};
use super::gbuffer_layout::{
    attachment, GBufferDraw, GBufferDrawPush, GBufferPush, GpuMaterial, ATTACHMENTS, DEPTH_FORMAT,
};
use super::gpu_scene::GpuScene;
use super::textures::GpuTextures;
use crate::math::lens::CameraSample;
use crate::scene::{Material, Scene};
use crate::shaders;
use crate::shaders::constants::{GBUFFER_BINDING_DRAWS, GBUFFER_BINDING_MATERIALS, GBUFFER_BINDING_TEXTURES};
use crate::vk::commands::{submit_and_wait, Access};
use crate::vk::descriptors::DescriptorSet;
use crate::vk::frame_graph::{FrameGraph, Use};
use crate::vk::pipeline::{Binding, GraphicsDesc, Pipeline};
use crate::vk::readback::read_image;
use crate::vk::{Buffer, Device, Image};
use anyhow::{bail, Result};
use ash::vk;
use glam::Mat4;
use std::sync::Arc;

/// The G-buffer's images for one image size.
pub struct GBuffer {
    pub color: Vec<Image>,
    pub depth: Image,
    pub extent: vk::Extent2D,
}

impl GBuffer {
    pub fn new(device: &Arc<Device>, width: u32, height: u32) -> Result<Self> {
        let extent = vk::Extent2D { width, height };
        let usage =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
        let color = ATTACHMENTS
            .iter()
            .enumerate()
            .map(|(i, a)| {
                // Once a frame's samples are in, the resolve writes the linear mean over the position
                // (FrameTargets): the one attachment of its format, and dead by then.
                let usage = if i == attachment::POSITION { usage | vk::ImageUsageFlags::STORAGE } else { usage };
                Image::new_2d(device, &format!("gbuffer {}", a.name), a.format, extent, usage)
            })
            .collect::<Result<Vec<_>>>()?;
        let depth = Image::new_2d(
            device,
            "gbuffer depth",
            DEPTH_FORMAT,
            extent,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        )?;
        Ok(Self { color, depth, extent })
    }
}

/// The G-buffer's contents on the host, one entry per pixel, row-major.
#[derive(Debug, Clone)]
pub struct GBufferFrame {
    pub width: u32,
    pub height: u32,
    /// Per channel (`gbuffer_layout::{POSITION, SHADING_NORMAL, ...}`), decoded to linear RGBA floats.
    pub channels: Vec<Vec<[f32; 4]>>,
    /// (instance + 1, material); (0, _) where nothing was drawn.
    pub ids: Vec<[u32; 2]>,
}

impl GBufferFrame {
    pub fn at(&self, attachment: usize, x: u32, y: u32) -> [f32; 4] {
        self.channels[attachment][(y * self.width + x) as usize]
    }

    pub fn covered(&self, x: u32, y: u32) -> bool {
        self.ids[(y * self.width + x) as usize][0] != 0
    }
}

/// The scene's materials on the GPU: the same for every sample of a frame, so uploaded once.
pub struct GBufferMaterials {
    pub(crate) buffer: Buffer,
}

/// The draws of `slots` samples (each at its own time), ready to record: one host-visible buffer and one
/// descriptor set for all of them, refilled per sample with `write_slot`. Borrows the frame's materials, which
/// its descriptor set refers to.
pub struct GBufferInputs<'m> {
    draws: Buffer,
    geometry: &'m GpuScene,
    _materials: &'m GBufferMaterials,
    set: DescriptorSet,
    /// (mesh, primitive) per draw, in draw order; the same in every slot.
    order: Vec<(usize, usize)>,
    /// (instance, material) per draw, in draw order.
    draw_of: Vec<(usize, u32)>,
    /// The vertex streams of deformed (skinned) instances, per slot; drawn in place of their mesh's.
    pub deformed: DeformedStreams,
    slots: u32,
}

impl<'m> GBufferInputs<'m> {
    /// The scene geometry the draws read.
    pub fn geometry(&self) -> &'m GpuScene {
        self.geometry
    }

    /// Writes the draws of `slot` for one sample's time `t`: each instance at its transform (`transforms`, one per
    /// scene instance, from the node transforms `node_world`), deformed instances deformed, with the sample's BLEND
    /// coverage key. The GPU must not be reading that slot.
    pub fn write_slot(
        &mut self,
        slot: u32,
        scene: &Scene,
        pose: (f32, &[Mat4]),
        transforms: &[Mat4],
        key: u32,
    ) -> Result<()> {
        if slot >= self.slots {
            bail!("gbuffer draws: slot {slot} of {}", self.slots);
        }
        let (t, node_world) = pose;
        self.deformed.write_slot(slot, scene, node_world, t)?;
        let records: Vec<GBufferDraw> = self
            .draw_of
            .iter()
            .map(|&(instance, _)| {
                let transform = transforms.get(instance).copied().unwrap_or(Mat4::ZERO);
                GBufferDraw::new(transform, instance as u32, key)
            })
            .collect();
        let offset = u64::from(slot) * (self.order.len() * std::mem::size_of::<GBufferDraw>()) as u64;
        self.draws.write(offset, bytemuck::cast_slice(&records))
    }
}

/// `GBufferInputs::order` and `GBufferInputs::draw_of`: (mesh, primitive) and (instance, material) per draw.
type DrawOrder = (Vec<(usize, usize)>, Vec<(usize, u32)>);

/// Every (mesh, primitive) draw and its (instance, material), nearest first: the distance from the camera at the
/// shutter's opening to the centre of the primitive's box where its instance rests (ties in scene order). The
/// depth test keeps the nearest surface whatever the order, but llvmpipe tests depth before it shades, so a far
/// wall drawn after the boxes in front of it shades only the pixels they leave (docs/performance.md, "The
/// G-buffer pass: draws nearest first").
fn draws_front_to_back(scene: &Scene, gpu_scene: &GpuScene) -> DrawOrder {
    let default_material = scene.materials.len() as u32;
    let eye = scene.camera_at(scene.shutter.0).world_from_camera.w_axis.truncate();
    let mut draws = Vec::new();
    for (i, instance) in scene.instances.iter().enumerate() {
        for (p, primitive) in gpu_scene.meshes[instance.mesh].primitives.iter().enumerate() {
            let distance = instance.world_from_object.transform_point3(primitive.center).distance(eye);
            let material = primitive.material.map(|m| m as u32).unwrap_or(default_material);
            draws.push((distance, (instance.mesh, p), (i, material)));
        }
    }
    // A stable sort by a total order (a degenerate transform's NaN distance has its place too): equal distances
    // keep the scene's order, and every process that renders the frame draws in the same order.
    draws.sort_by(|a, b| a.0.total_cmp(&b.0));
    draws.into_iter().map(|(_, draw, of)| (draw, of)).unzip()
}

pub struct GBufferPass {
    pipeline: Pipeline,
    device: Arc<Device>,
}

const VERTEX_STREAMS: [(u32, vk::Format); 7] = [
    (12, vk::Format::R32G32B32_SFLOAT),    // position
    (12, vk::Format::R32G32B32_SFLOAT),    // normal
    (8, vk::Format::R32G32_SFLOAT),        // uv
    (16, vk::Format::R32G32B32A32_SFLOAT), // colour
    (12, vk::Format::R32G32B32_SFLOAT),    // dpdu
    (12, vk::Format::R32G32B32_SFLOAT),    // dpdv
    (8, vk::Format::R32G32_SFLOAT),        // uv1
];

impl GBufferPass {
    /// The pass's descriptor bindings, as `gbuffer_layout.glsl` and `gbuffer.frag` declare them, read from their
    /// SPIR-V. `texture_array`: the most textures the texture array holds (`Device::texture_array_size`).
    pub fn bindings(texture_array: u32) -> Result<Vec<Binding>> {
        let stages = [("gbuffer.vert", shaders::GBUFFER_VERT), ("gbuffer.frag", shaders::GBUFFER_FRAG)];
        crate::vk::spirv::descriptor_bindings(&stages, texture_array)
    }

    /// The G-buffer pipeline: one for every scene, whatever its texture count.
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let vertex_bindings: Vec<vk::VertexInputBindingDescription> = VERTEX_STREAMS
            .iter()
            .enumerate()
            .map(|(i, (stride, _))| vk::VertexInputBindingDescription::default().binding(i as u32).stride(*stride))
            .collect();
        let vertex_attributes: Vec<vk::VertexInputAttributeDescription> = VERTEX_STREAMS
            .iter()
            .enumerate()
            .map(|(i, (_, format))| {
                vk::VertexInputAttributeDescription::default().location(i as u32).binding(i as u32).format(*format)
            })
            .collect();
        let bindings = Self::bindings(device.texture_array_size())?;
        let formats: Vec<vk::Format> = ATTACHMENTS.iter().map(|a| a.format).collect();
        let pipeline = Pipeline::graphics(
            device,
            &GraphicsDesc {
                name: "gbuffer pipeline",
                vertex: ("gbuffer.vert", shaders::GBUFFER_VERT),
                fragment: ("gbuffer.frag", shaders::GBUFFER_FRAG),
                bindings: &bindings,
                push_constant_size: std::mem::size_of::<GBufferPush>() as u32,
                vertex_bindings: &vertex_bindings,
                vertex_attributes: &vertex_attributes,
                color_formats: &formats,
                depth_format: Some(DEPTH_FORMAT),
                additive_blend: false,
                cull_mode: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(Self { pipeline, device: device.clone() })
    }

    /// Uploads `scene`'s materials (plus glTF's default material, last, for primitives without one). Once per
    /// frame.
    pub fn materials(&self, scene: &Scene, textures: &GpuTextures) -> Result<GBufferMaterials> {
        let sizes: Vec<(u32, u32)> = textures.images.iter().map(|i| (i.extent.width, i.extent.height)).collect();
        let mut materials: Vec<GpuMaterial> = scene.materials.iter().map(|m| GpuMaterial::new(m, &sizes)).collect();
        materials.push(GpuMaterial::new(&Material::default(), &sizes));
        let buffer =
            Buffer::with_data(&self.device, "gbuffer materials", &materials, vk::BufferUsageFlags::STORAGE_BUFFER, 16)?;
        Ok(GBufferMaterials { buffer })
    }

    /// Draw records for `scene` at time `t` (animation, motion and skins at that time).
    pub fn inputs<'m>(
        &self,
        scene: &Scene,
        gpu_scene: &'m GpuScene,
        textures: &GpuTextures,
        materials: &'m GBufferMaterials,
        t: f32,
    ) -> Result<GBufferInputs<'m>> {
        let node_world = scene.node_world_transforms(Some(t));
        let transforms = scene.instance_transforms_from(&node_world);
        let mut inputs = self.inputs_for_slots(scene, gpu_scene, textures, materials, 1)?;
        inputs.write_slot(0, scene, (t, &node_world), &transforms, 0)?;
        Ok(inputs)
    }

    /// Room for the draws of `slots` samples; fill each with `GBufferInputs::write_slot`.
    pub fn inputs_for_slots<'m>(
        &self,
        scene: &Scene,
        gpu_scene: &'m GpuScene,
        textures: &GpuTextures,
        materials: &'m GBufferMaterials,
        slots: u32,
    ) -> Result<GBufferInputs<'m>> {
        let (order, draw_of) = draws_front_to_back(scene, gpu_scene);
        let slots = slots.max(1);
        let bytes = (order.len().max(1) * std::mem::size_of::<GBufferDraw>()) as u64 * u64::from(slots);
        let draws = Buffer::new(
            &self.device,
            "gbuffer draws",
            bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            crate::vk::MemoryLocation::CpuToGpu,
            16,
        )?;
        let set = self.pipeline.new_descriptor_set_sized("gbuffer set", textures.bindings().len() as u32)?;
        set.storage_buffer(GBUFFER_BINDING_DRAWS, &draws)
            .storage_buffer(GBUFFER_BINDING_MATERIALS, &materials.buffer)
            .combined_image_samplers(GBUFFER_BINDING_TEXTURES, &textures.bindings());
        let deformed = DeformedStreams::new(&self.device, scene, gpu_scene, slots)?;
        Ok(GBufferInputs { draws, geometry: gpu_scene, _materials: materials, set, order, draw_of, deformed, slots })
    }

    /// Records the pass into `cmd` as a pass of `graph`: clears and draws over every attachment (their old
    /// contents discarded), which it leaves in `COLOR_ATTACHMENT_OPTIMAL` (and depth in
    /// `DEPTH_ATTACHMENT_OPTIMAL`) for the next pass's uses.
    pub fn record(
        &self,
        graph: &mut FrameGraph,
        cmd: vk::CommandBuffer,
        gbuffer: &GBuffer,
        inputs: &GBufferInputs,
        slot: u32,
        sample: &CameraSample,
    ) {
        let device = &self.device;
        let mut uses: Vec<Use> = gbuffer
            .color
            .iter()
            .map(|image| {
                Use::overwrite_image(image, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, Access::COLOR_ATTACHMENT_WRITE)
            })
            .collect();
        uses.push(Use::overwrite_image(
            &gbuffer.depth,
            vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            Access::DEPTH_ATTACHMENT,
        ));
        uses.push(Use::read_memory(DEFORMED_STREAMS, Access::VERTEX_INPUT_READ));
        graph.pass(cmd, "gbuffer pass", &uses, || {
            let colors: Vec<(&Image, vk::ClearColorValue)> = gbuffer
                .color
                .iter()
                .enumerate()
                .map(|(i, image)| {
                    let clear = if i == attachment::SURFACE_IDS {
                        vk::ClearColorValue { uint32: [0; 4] }
                    } else {
                        vk::ClearColorValue { float32: [0.0; 4] }
                    };
                    (image, clear)
                })
                .collect();
            crate::vk::commands::begin_cleared_rendering(device, cmd, gbuffer.extent, &colors, &gbuffer.depth);
            let push = GBufferPush {
                clip_from_world: sample.clip_from_world(),
                view_z_row: sample.view_from_world.row(2),
                draw: 0,
                material: 0,
                pad: [0; 2],
            };
            self.pipeline.bind(cmd, Some(&inputs.set), bytemuck::bytes_of(&push));
            let first_draw = slot as usize * inputs.order.len();
            for (draw_index, &(mesh, p)) in inputs.order.iter().enumerate() {
                let primitive = &inputs.geometry.meshes[mesh].primitives[p];
                let mut buffers = [
                    primitive.positions.raw,
                    primitive.normals.raw,
                    primitive.uvs.raw,
                    primitive.colors.raw,
                    primitive.dpdu.raw,
                    primitive.dpdv.raw,
                    primitive.uvs1.raw,
                ];
                let mut offsets = [0; 7];
                // A deformed instance's moving streams: this slot's copy.
                if let Some(moving) = inputs.deformed.of_instance(inputs.draw_of[draw_index].0) {
                    let moving = &moving.primitives[p];
                    let offset = moving.offset(slot);
                    for (stream, buffer) in
                        [(0, &moving.positions), (1, &moving.normals), (4, &moving.dpdu), (5, &moving.dpdv)]
                    {
                        buffers[stream] = buffer.raw;
                        offsets[stream] = offset;
                    }
                }
                // The draw's record and material, for both stages: a push constant is uniform over the draw.
                let draw =
                    GBufferDrawPush { draw: (first_draw + draw_index) as u32, material: inputs.draw_of[draw_index].1 };
                self.pipeline.push_constants_at(cmd, GBufferPush::DRAW_OFFSET, bytemuck::bytes_of(&draw));
                unsafe {
                    device.raw.cmd_bind_vertex_buffers(cmd, 0, &buffers, &offsets);
                    device.raw.cmd_bind_index_buffer(cmd, primitive.indices.raw, 0, vk::IndexType::UINT32);
                    device.raw.cmd_draw_indexed(cmd, primitive.index_count, 1, 0, 0, 0);
                }
            }
            unsafe { device.raw.cmd_end_rendering(cmd) };
        });
    }

    /// Renders one sample and reads every attachment back (for AOVs and tests).
    pub fn render_to_host(
        &self,
        gbuffer: &GBuffer,
        inputs: &GBufferInputs,
        sample: &CameraSample,
    ) -> Result<GBufferFrame> {
        let device = &self.device;
        let mut graph = FrameGraph::new(device);
        submit_and_wait(device, "gbuffer frame", |cmd| {
            inputs.deformed.record_skinning(&mut graph, cmd, 0);
            self.record(&mut graph, cmd, gbuffer, inputs, 0, sample);
            Ok(())
        })?;
        let mut floats = Vec::new();
        let mut surface_ids = Vec::new();
        for (i, image) in gbuffer.color.iter().enumerate() {
            let readback =
                read_image(device, image, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, Access::COLOR_ATTACHMENT_WRITE)?;
            if i == attachment::SURFACE_IDS {
                surface_ids = readback.to_uvec4()?;
            } else {
                floats.push(readback.to_rgba_f32()?);
            }
        }
        let mut channels: Vec<Vec<[f32; 4]>> =
            (0..super::gbuffer_layout::CHANNELS).map(|_| Vec::with_capacity(surface_ids.len())).collect();
        let mut ids = Vec::with_capacity(surface_ids.len());
        for (pixel, surface) in surface_ids.iter().enumerate() {
            // The float attachments are every one before the surface ids.
            let texel: [[f32; 4]; attachment::SURFACE_IDS] = std::array::from_fn(|a| floats[a][pixel]);
            let (decoded, pixel_ids) = super::gbuffer_encoding::decode_texel(&texel, *surface);
            for (channel, value) in channels.iter_mut().zip(decoded) {
                channel.push(value);
            }
            ids.push(pixel_ids);
        }
        Ok(GBufferFrame { width: gbuffer.extent.width, height: gbuffer.extent.height, channels, ids })
    }
}
