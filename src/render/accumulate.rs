//! The accumulation pass: per pixel, it reads the G-buffer (or, in the reference mode, traces the pixel's own
//! primary ray), casts shadow, gloss and translucency rays against the TLAS, and adds the sample's radiance to
//! the pixel's fixed-point sums. One shading body (`shaders/include/path_tracer.glsl`) traces in one of two
//! ways ([`TracePath`]): with ray queries in a compute shader (`accumulate.comp`), whose subgroups take runs of
//! an 8×8 tile's pixels from a queue (a counter per sample) so that threads that finish early take more
//! ([`workgroups_for`]); or through a ray-tracing pipeline (`accumulate.rgen`, with hit shaders that only record
//! the hit and run the alpha test), for devices without ray queries: one invocation per pixel on a GPU, and on a
//! CPU device a few rows of 8 invocations that deal 8-pixel runs of the image out in turn, for the same reason
//! ([`AccumulateLaunch`]).
use super::accumulate_layout::{AccumulatePush, COUNTERS_PER_SLOT};
use super::gbuffer::{GBuffer, GBufferMaterials};
use super::gbuffer_layout::attachment::SURFACE_IDS;
use super::textures::GpuTextures;
use crate::scene::settings::Trace;
use crate::shaders;
use crate::vk::accel::AccelerationStructure;
use crate::vk::descriptors::DescriptorSet;
use crate::vk::pipeline::{Binding, Pipeline, RayTracingDesc};
use crate::vk::sampler::{Sampler, SamplerDesc};
use crate::vk::shader_binding_table::ShaderBindingTable;
use crate::vk::{Buffer, Device};
use anyhow::{anyhow, Result};
use ash::vk;
use std::sync::Arc;

/// The compute shader's workgroups are LOCAL_SIZE × LOCAL_SIZE invocations, the size of the tiles whose rows its
/// subgroups take from the queue.
const LOCAL_SIZE: u32 = crate::shaders::constants::ACCUMULATE_TILE_SIZE;

/// How the pass traces its rays on a device (`Trace` resolved).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TracePath {
    /// Ray queries in a compute shader (`VK_KHR_ray_query`).
    Query,
    /// A ray-tracing pipeline (`VK_KHR_ray_tracing_pipeline`).
    Pipeline,
}

impl TracePath {
    /// What the summary line, `--json` and the benchmark call it (`--trace`'s words).
    pub fn name(self) -> &'static str {
        match self {
            TracePath::Query => "query",
            TracePath::Pipeline => "pipeline",
        }
    }

    /// The way `trace` asks for on `device`: auto takes ray queries where the device has them, else a pipeline.
    /// Fails, saying what the device lacks, where it has not the way asked for.
    pub fn choose(trace: Trace, device: &Device) -> Result<Self> {
        let report = &device.report;
        match trace {
            Trace::Query => device.require_ray_queries("--trace query").map(|_| TracePath::Query),
            Trace::Pipeline => device.require_ray_tracing_pipelines("--trace pipeline").map(|_| TracePath::Pipeline),
            // `available` lists ray queries first: the one place auto's preference is written.
            Trace::Auto => Self::available(device)
                .first()
                .copied()
                .ok_or_else(|| anyhow!("{} can trace rays neither way: {}", report.name, report.status())),
        }
    }

    /// What a device must have for `trace`.
    pub fn device_needs(trace: Trace) -> crate::vk::DeviceNeeds {
        match trace {
            Trace::Auto => crate::vk::DeviceNeeds::RayTracing,
            Trace::Query => crate::vk::DeviceNeeds::RayQueries,
            Trace::Pipeline => crate::vk::DeviceNeeds::RayTracingPipeline,
        }
    }

    /// The ways `device` can trace: what a test renders with to hold both to the same picture.
    pub fn available(device: &Device) -> Vec<TracePath> {
        let mut paths = Vec::new();
        if device.report.ray_query {
            paths.push(TracePath::Query);
        }
        if device.ray_tracing.is_some() {
            paths.push(TracePath::Pipeline);
        }
        paths
    }

    pub fn as_trace(self) -> Trace {
        match self {
            TracePath::Query => Trace::Query,
            TracePath::Pipeline => Trace::Pipeline,
        }
    }
}

/// The pass's pipeline: a compute pipeline, or a ray-tracing pipeline and its shader binding table.
enum Tracer {
    Query(Pipeline),
    Pipeline {
        pipeline: Pipeline,
        table: Box<ShaderBindingTable>,
        /// The device's ray-tracing commands (`vkCmdTraceRaysKHR`).
        commands: ash::khr::ray_tracing_pipeline::Device,
        /// The raygen shader's invocations take 8-pixel runs in turn (its PIXEL_RUNS specialization constant).
        pixel_runs: bool,
    },
}

pub struct AccumulatePass {
    tracer: Tracer,
    /// Nearest, clamped: the G-buffer is read texel by texel.
    gbuffer_sampler: Sampler,
    /// The specular and sheen lobes' directional albedo tables (math::brdf::albedo_tables): the same for every
    /// frame, so the pass holds them.
    specular_albedo: Buffer,
    launch: AccumulateLaunch,
    device: Arc<Device>,
}

/// What one frame's accumulation reads and writes.
pub struct AccumulateInputs<'a> {
    pub tlas: &'a AccelerationStructure,
    pub gbuffer: &'a GBuffer,
    /// Per pixel, the fixed-point sums of its samples (strata::partial).
    pub sums: &'a Buffer,
    pub materials: &'a GBufferMaterials,
    pub lights: &'a Buffer,
    pub primitives: &'a Buffer,
    pub textures: &'a GpuTextures,
    pub counters: &'a Buffer,
    /// One `GpuCamera` per sample slot (the reference mode's primary rays, and every mode's background).
    pub cameras: &'a Buffer,
    /// The scene's environment (render::environment).
    pub environment: &'a Buffer,
}

/// How the pass spreads a sample's pixels over the invocations it launches. The picture does not depend on it
/// (render_frames.rs checks every kind bit for bit); speed does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AccumulateLaunch {
    /// What suits the device: on a CPU device a few workgroups sharing the work ([`workgroups_for`],
    /// [`CPU_PIPELINE_INVOCATIONS`]); on a GPU one workgroup per tile or one invocation per pixel.
    #[default]
    DeviceDefault,
    /// This many workgroups share the work: with ray queries their subgroups take runs of 8×8 tiles' pixels from a
    /// queue; through the pipeline, rows of 8 invocations take 8-pixel runs in turn.
    Workgroups(u32),
    /// A GPU's launch on any device: one workgroup per tile (ray queries), one invocation per pixel (pipeline).
    OnePerTileOrPixel,
}

/// Whether any path can go on past its visible surface: with `max_depth` path vertices (the visible surface and
/// its bounces) only when there is a second, or when BSDF sampling alone (`bsdf_sampling_alone`) casts its
/// gather ray past the last (path.glsl, next_chain_ray). Exact, so a pipeline without chain code draws the same
/// picture.
pub fn paths_go_on(max_depth: u32, bsdf_sampling_alone: bool) -> bool {
    max_depth > 1 || bsdf_sampling_alone
}

/// Which accumulation pipeline a pass builds.
#[derive(Debug, Clone, Copy)]
pub struct AccumulateVariant {
    pub path: TracePath,
    /// Trace each pixel's primary ray (the reference mode) instead of reading the G-buffer.
    pub primary_rays: bool,
    /// Some geometry is not opaque to rays (RayScene::alpha_tested); without it every ray is forced opaque and
    /// the pipeline carries no alpha test (and no any-hit shader).
    pub alpha_tested: bool,
    /// The scene has an environment; without one the pipeline holds none of its code (HAS_ENVIRONMENT).
    pub environment: bool,
    /// Paths may go on past the visible surface ([`paths_go_on`]); without it the pipeline holds no chain code
    /// (CHAINS).
    pub chains: bool,
    /// Some transmissive material disperses (`Scene::disperses`); without it the pipeline holds no dispersion
    /// code (DISPERSION).
    pub dispersion: bool,
    /// Some material has a layer over its base (`Scene::layered`: a clear coat or a sheen); without it the
    /// pipeline holds none of the layers' code (LAYERS).
    pub layers: bool,
    pub launch: AccumulateLaunch,
    /// Bytes to move the shader binding table off its alignment (0 but in the test that breaks it on purpose).
    pub table_shift: u64,
}

impl AccumulatePass {
    pub fn new(device: &Arc<Device>, variant: &AccumulateVariant) -> Result<Self> {
        let AccumulateVariant {
            path,
            primary_rays,
            alpha_tested,
            environment,
            chains,
            dispersion,
            layers,
            launch,
            table_shift,
        } = *variant;
        // constant_id 0, 1, 2 (the raygen shader's PIXEL_RUNS; unused by the compute shader), 3, 4, 5, 6.
        let flag = u32::from;
        let bindings = Self::bindings(device.texture_array_size())?;
        let push_constant_size = std::mem::size_of::<AccumulatePush>() as u32;
        let mode = if primary_rays { " (primary rays)" } else { "" };
        let cpu = device.report.device_type == vk::PhysicalDeviceType::CPU;
        let pixel_runs = match launch {
            AccumulateLaunch::DeviceDefault => cpu,
            AccumulateLaunch::Workgroups(_) => true,
            AccumulateLaunch::OnePerTileOrPixel => false,
        };
        let tracer = match path {
            TracePath::Query => Tracer::Query(Pipeline::compute_specialized(
                device,
                &format!("accumulate pipeline{mode}"),
                ("accumulate.comp", shaders::ACCUMULATE_COMP),
                &bindings,
                push_constant_size,
                &[
                    flag(primary_rays),
                    flag(alpha_tested),
                    0,
                    flag(environment),
                    flag(chains),
                    flag(dispersion),
                    flag(layers),
                ],
            )?),
            TracePath::Pipeline => {
                let runs = if pixel_runs { ", pixel runs" } else { "" };
                let pipeline = Pipeline::ray_tracing(
                    device,
                    &RayTracingDesc {
                        name: &format!("accumulate ray-tracing pipeline{mode}{runs}"),
                        raygen: ("accumulate.rgen", shaders::ACCUMULATE_RGEN),
                        miss: ("accumulate.rmiss", shaders::ACCUMULATE_RMISS),
                        closest_hit: ("accumulate.rchit", shaders::ACCUMULATE_RCHIT),
                        any_hit: alpha_tested.then_some(("accumulate.rahit", shaders::ACCUMULATE_RAHIT)),
                        bindings: &bindings,
                        push_constant_size,
                        constants: &[
                            flag(primary_rays),
                            flag(alpha_tested),
                            flag(pixel_runs),
                            flag(environment),
                            flag(chains),
                            flag(dispersion),
                            flag(layers),
                        ],
                    },
                )?;
                let table = Box::new(ShaderBindingTable::new(device, &pipeline, table_shift)?);
                let commands = device.require_ray_tracing_pipelines("the accumulation pass")?.loader.clone();
                Tracer::Pipeline { pipeline, table, commands, pixel_runs }
            }
        };
        let gbuffer_sampler = Sampler::new(
            device,
            "gbuffer texel sampler",
            &SamplerDesc {
                mag_linear: false,
                min_linear: false,
                address_u: vk::SamplerAddressMode::CLAMP_TO_EDGE,
                address_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
                mipmaps: None,
            },
        )?;
        let specular_albedo = Buffer::with_data(
            device,
            "albedo tables",
            &crate::math::brdf::albedo_tables(),
            vk::BufferUsageFlags::STORAGE_BUFFER,
            16,
        )?;
        Ok(Self { tracer, gbuffer_sampler, specular_albedo, launch, device: device.clone() })
    }

    /// The pass's descriptor bindings, as its stages declare them (`shaders/include/accumulate_bindings.glsl`;
    /// every stage of both ways to trace reads the one set), read from their SPIR-V. `texture_array`: the most
    /// textures the texture array holds (`Device::texture_array_size`), filled per scene.
    pub fn bindings(texture_array: u32) -> Result<Vec<Binding>> {
        let stages = [
            ("accumulate.comp", shaders::ACCUMULATE_COMP),
            ("accumulate.rgen", shaders::ACCUMULATE_RGEN),
            ("accumulate.rchit", shaders::ACCUMULATE_RCHIT),
            ("accumulate.rahit", shaders::ACCUMULATE_RAHIT),
            ("accumulate.rmiss", shaders::ACCUMULATE_RMISS),
        ];
        crate::vk::spirv::descriptor_bindings(&stages, texture_array)
    }

    pub fn path(&self) -> TracePath {
        match self.tracer {
            Tracer::Query(_) => TracePath::Query,
            Tracer::Pipeline { .. } => TracePath::Pipeline,
        }
    }

    fn pipeline(&self) -> &Pipeline {
        match &self.tracer {
            Tracer::Query(pipeline) | Tracer::Pipeline { pipeline, .. } => pipeline,
        }
    }

    /// The stage the pass's shaders run in (for timestamps after it).
    /// The pass's debug label, which says how it traces.
    pub fn label(&self) -> &'static str {
        match self.tracer {
            Tracer::Query(_) => "accumulate pass (ray queries)",
            Tracer::Pipeline { .. } => "accumulate pass (ray-tracing pipeline)",
        }
    }

    pub fn stage(&self) -> vk::PipelineStageFlags2 {
        match self.tracer {
            Tracer::Query(_) => vk::PipelineStageFlags2::COMPUTE_SHADER,
            Tracer::Pipeline { .. } => vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR,
        }
    }

    /// The descriptor set for one frame: every binding stays the same across its samples.
    pub fn descriptor_set(&self, inputs: &AccumulateInputs<'_>) -> Result<DescriptorSet> {
        use crate::shaders::constants::*;
        let set =
            self.pipeline().new_descriptor_set_sized("accumulate set", inputs.textures.bindings().len() as u32)?;
        let gbuffer: Vec<(vk::ImageView, vk::Sampler)> = inputs
            .gbuffer
            .color
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != SURFACE_IDS)
            .map(|(_, image)| (image.view, self.gbuffer_sampler.raw))
            .collect();
        set.acceleration_structure(ACCUMULATE_BINDING_TLAS, inputs.tlas.raw)
            .combined_image_samplers(ACCUMULATE_BINDING_GBUFFER, &gbuffer)
            .combined_image_samplers(
                ACCUMULATE_BINDING_GBUFFER_IDS,
                &[(inputs.gbuffer.color[SURFACE_IDS].view, self.gbuffer_sampler.raw)],
            )
            .storage_buffer(ACCUMULATE_BINDING_SUMS, inputs.sums)
            .storage_buffer(ACCUMULATE_BINDING_MATERIALS, &inputs.materials.buffer)
            .storage_buffer(ACCUMULATE_BINDING_LIGHTS, inputs.lights)
            .storage_buffer(ACCUMULATE_BINDING_PRIMITIVES, inputs.primitives)
            .combined_image_samplers(ACCUMULATE_BINDING_TEXTURES, &inputs.textures.bindings())
            .storage_buffer(ACCUMULATE_BINDING_COUNTERS, inputs.counters)
            .storage_buffer(ACCUMULATE_BINDING_CAMERAS, inputs.cameras)
            .storage_buffer(ACCUMULATE_BINDING_ENVIRONMENT, inputs.environment)
            .storage_buffer(ACCUMULATE_BINDING_SPECULAR_ALBEDO, &self.specular_albedo);
        Ok(set)
    }

    /// Records one sample's dispatch (or trace), unlabelled: it is the work of the frame graph's accumulate pass
    /// (labelled [`Self::label`]), whose uses make the G-buffer readable and the TLAS built; the host zeroed the
    /// sample's counters (its queue starts at the first run).
    pub fn record(&self, cmd: vk::CommandBuffer, set: &DescriptorSet, push: &AccumulatePush) {
        let device = &self.device;
        let device_type = device.report.device_type;
        match &self.tracer {
            Tracer::Query(pipeline) => {
                let tiles = push.width.div_ceil(LOCAL_SIZE) * push.height.div_ceil(LOCAL_SIZE);
                let groups = match self.launch {
                    AccumulateLaunch::DeviceDefault => workgroups_for(tiles, device_type),
                    AccumulateLaunch::Workgroups(n) => n.clamp(1, MAX_WORKGROUPS),
                    AccumulateLaunch::OnePerTileOrPixel => workgroups_for(tiles, vk::PhysicalDeviceType::DISCRETE_GPU),
                };
                pipeline.bind(cmd, Some(set), bytemuck::bytes_of(push));
                unsafe { device.raw.cmd_dispatch(cmd, groups, 1, 1) };
            }
            Tracer::Pipeline { pipeline, table, commands, pixel_runs } => {
                // Runs are dealt to one row of invocations, 8 per workgroup; otherwise one invocation per pixel.
                let (width, height) = match (pixel_runs, self.launch) {
                    (false, _) => (push.width, push.height),
                    (true, AccumulateLaunch::Workgroups(n)) => (RUN_LENGTH * n.clamp(1, MAX_WORKGROUPS), 1),
                    (true, _) => (CPU_PIPELINE_INVOCATIONS, 1),
                };
                pipeline.bind(cmd, Some(set), bytemuck::bytes_of(push));
                unsafe {
                    commands.cmd_trace_rays(
                        cmd,
                        &table.raygen,
                        &table.miss,
                        &table.hit,
                        &table.callable,
                        width,
                        height,
                        1,
                    )
                };
            }
        }
    }
}

/// The pixels of a row one workgroup of the pipeline path shades together on a CPU device: lavapipe runs a
/// ray-tracing pipeline as a compute shader of 8-lane workgroups (lvp_ray_tracing_pipeline.c).
const RUN_LENGTH: u32 = crate::shaders::constants::ACCUMULATE_RUN_LENGTH;

/// Invocations a CPU device's ray-tracing launch gets when they deal out 8-pixel runs: as many of lavapipe's
/// workgroups as [`CPU_WORKGROUPS`] gives the compute path.
pub const CPU_PIPELINE_INVOCATIONS: u32 = RUN_LENGTH * CPU_WORKGROUPS;

/// The most workgroups one dispatch of the pass launches: the least `maxComputeWorkGroupCount[0]` the Vulkan
/// spec lets a device report. Each subgroup loops over runs, so fewer workgroups than tiles still cover the image.
const MAX_WORKGROUPS: u32 = 65_535;

/// Workgroups a CPU device gets: more than a CPU driver runs threads (llvmpipe caps them at its LP_MAX_THREADS),
/// so every thread has one, and few enough that the rest, which find the queue empty, cost next to nothing.
const CPU_WORKGROUPS: u32 = 256;

/// How many workgroups share a sample's `tiles` (8×8 pixels each). The shader takes runs of them from a queue, so
/// any number gives the same picture; what it changes is speed. A GPU gets one per tile (up to `MAX_WORKGROUPS`),
/// as many as it can keep resident. A CPU device runs one workgroup per thread at a time and pays for every one it
/// starts, so it gets only `CPU_WORKGROUPS`.
pub fn workgroups_for(tiles: u32, device_type: vk::PhysicalDeviceType) -> u32 {
    let wanted = if device_type == vk::PhysicalDeviceType::CPU { tiles.min(CPU_WORKGROUPS) } else { tiles };
    wanted.clamp(1, MAX_WORKGROUPS)
}

/// Bytes of counters (rays cast, the tile queue) for `slots` samples.
pub fn counter_bytes(slots: u32) -> u64 {
    u64::from(slots.max(1)) * (COUNTERS_PER_SLOT * 4) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cpu_device_gets_a_few_workgroups_and_a_gpu_one_per_tile() {
        let (cpu, gpu) = (vk::PhysicalDeviceType::CPU, vk::PhysicalDeviceType::DISCRETE_GPU);
        // 960x540: 120 x 68 tiles.
        assert_eq!(workgroups_for(8160, cpu), CPU_WORKGROUPS);
        assert_eq!(workgroups_for(8160, gpu), 8160);
        assert_eq!(workgroups_for(6, cpu), 6);
        assert_eq!(workgroups_for(0, gpu), 1);
        // 16384 x 16384: more tiles than one dispatch may launch; the queue covers the rest.
        assert_eq!(workgroups_for(2048 * 2048, gpu), MAX_WORKGROUPS);
    }
}
