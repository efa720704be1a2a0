// Numbers both languages read from this one file: GLSL includes it, and build.rs turns each line of the form
// `const uint NAME = VALUEu;` into `pub const NAME: u32 = VALUE;` in Rust (strata::shaders::constants; `const
// int` an i32, `const float` an f32). Nothing else belongs here: build.rs fails on a line it cannot read.
#ifndef SHARED_CONSTANTS_GLSL
#define SHARED_CONSTANTS_GLSL
// The accumulation pass's descriptor bindings (accumulate_bindings.glsl; render::accumulate::AccumulatePass).
const uint ACCUMULATE_BINDING_TLAS = 0u;
const uint ACCUMULATE_BINDING_GBUFFER = 1u;
const uint ACCUMULATE_BINDING_GBUFFER_IDS = 2u;
const uint ACCUMULATE_BINDING_SUMS = 3u;
const uint ACCUMULATE_BINDING_MATERIALS = 4u;
const uint ACCUMULATE_BINDING_LIGHTS = 5u;
const uint ACCUMULATE_BINDING_PRIMITIVES = 6u;
const uint ACCUMULATE_BINDING_COUNTERS = 8u;
const uint ACCUMULATE_BINDING_CAMERAS = 9u;
const uint ACCUMULATE_BINDING_ENVIRONMENT = 7u;
// The specular lobe's directional albedo table (math::brdf, brdf.glsl's diffuse_share).
const uint ACCUMULATE_BINDING_SPECULAR_ALBEDO = 10u;
// The texture array is the set's last binding: its size varies per scene (one pipeline serves every size).
const uint ACCUMULATE_BINDING_TEXTURES = 11u;
// The specular albedo table's size: view cosines at cell centres (k + 0.5) / MU_STEPS, roughness at
// j / (ROUGHNESS_STEPS - 1).
const uint SPECULAR_ALBEDO_MU_STEPS = 64u;
const uint SPECULAR_ALBEDO_ROUGHNESS_STEPS = 32u;
// The side of the accumulation compute shader's square workgroup, whose tile its subgroups split into runs.
const uint ACCUMULATE_TILE_SIZE = 8u;
// The pixels of an image row that one workgroup of the ray-tracing pipeline shades together on a CPU device
// (accumulate.rgen's PIXEL_RUNS; lavapipe runs a pipeline as a compute shader of 8-lane workgroups).
const uint ACCUMULATE_RUN_LENGTH = 8u;
// Counters per sample slot (binding 8): shadow rays, secondary rays, the next run of pixels to shade
// (accumulate.comp).
const uint COUNTER_SHADOW_RAYS = 0u;
const uint COUNTER_SECONDARY_RAYS = 1u;
const uint COUNTER_NEXT_RUN = 2u;
const uint COUNTERS_PER_SLOT = 3u;
// What pixels no surface covers show (pc.background.w; render::frame): the background colour, the environment,
// or nothing (alpha 0, no radiance).
const uint BACKGROUND_COLOUR = 0u;
const uint BACKGROUND_ENVIRONMENT = 1u;
const uint BACKGROUND_TRANSPARENT = 2u;
// The fixed point of the samples' sums (fixed_point.glsl; src/partial/): counts of 2^-24.
const uint SUM_FRACTION_BITS = 24u;
// The most one sample adds per channel is 2^SUM_MAX_SAMPLE_LOG2, so that MAX_SPP (65536) samples stay below 2^64
// counts; a part whose sums exceed samples × 2^(this + SUM_FRACTION_BITS) was not written by a render.
const uint SUM_MAX_SAMPLE_LOG2 = 23u;
// The accumulation pass's sabotage bits (pc.sabotage; render::frame::Sabotage): strata check's canaries.
const uint SABOTAGE_NO_SHADOW_RAYS = 1u;
const uint SABOTAGE_FLIPPED_NORMALS = 2u;

// The G-buffer's attachments (gbuffer_encoding.glsl; render::gbuffer_layout::ATTACHMENTS): the location each is
// written at, and its index in the accumulation pass's sampler array (binding 1) but the surface ids, which come
// last and alone (binding 2).
const uint GBUFFER_ATTACHMENT_POSITION = 0u;
const uint GBUFFER_ATTACHMENT_ALBEDO = 1u;
const uint GBUFFER_ATTACHMENT_MATERIAL = 2u;
const uint GBUFFER_ATTACHMENT_EMISSION = 3u;
const uint GBUFFER_ATTACHMENT_SPECULAR = 4u;
const uint GBUFFER_ATTACHMENT_SURFACE_IDS = 5u;

// Light kinds, in the w of a GpuLight's first vector (accumulate_layout.glsl; render::lights).
const float LIGHT_POINT = 0.0;
const float LIGHT_SPOT = 1.0;
const float LIGHT_DIRECTIONAL = 2.0;
const float LIGHT_QUAD = 3.0;
const float LIGHT_DISK = 4.0;
const float LIGHT_SPHERE = 5.0;
const float LIGHT_TRIANGLE = 6.0;
// The environment (environment.glsl), first of a sample's lights when present.
const float LIGHT_ENVIRONMENT = 7.0;
// Two emissive triangles making a quad, sampled whole (render/lights.rs).
const float LIGHT_PARALLELOGRAM = 8.0;
// The direct-light estimators (pc.direct_light; render::frame::DirectLight): light sampling and BSDF sampling
// combined by multiple importance sampling (Veach and Guibas 1995), or either alone. All three estimate the same
// integral, so the tests hold each to the others.
const uint DIRECT_MIS = 0u;
const uint DIRECT_LIGHT_SAMPLING = 1u;
const uint DIRECT_BSDF_SAMPLING = 2u;
// Bump height fields and how their derivatives are taken (Bump in bump.glsl; render::gbuffer_layout::GpuBump).
const int BUMP_NONE = -1;
const int BUMP_NOISE = 0;
const int BUMP_FBM = 1;
const int BUMP_TURBULENCE = 2;
const int BUMP_SINE = 3;
const int BUMP_CENTRAL_DIFFERENCES = 0;
const int BUMP_ANALYTIC = 1;
// A material's texture index where it has no such texture (GpuMaterial, PreviewDraw; shaders test `>= 0`).
const int NO_TEXTURE = -1;
// glTF alpha modes (GpuMaterial.alpha_mode; material.glsl's alpha test; render::gbuffer_layout::GpuMaterial).
const int ALPHA_OPAQUE = 0;
const int ALPHA_MASK = 1;
const int ALPHA_BLEND = 2;
// Sampler kinds (pc.sampler; sampling.glsl and its Rust twin math::sampling).
const uint SAMPLER_REGULAR = 0u;
const uint SAMPLER_RANDOM = 1u;
const uint SAMPLER_JITTERED = 2u;
const uint SAMPLER_MULTI_JITTERED = 3u;
const uint SAMPLER_SOBOL = 4u;
// Sampler dimensions (docs/architecture.md: pixel, time, lens, light, then bounces). The camera's (0-2) are
// drawn on the host for the whole image (render::sample_slots), except pixel and lens in the reference mode (per
// pixel, path_vertex.glsl); each path vertex draws its own from DIM_FIRST_VERTEX on.
const uint DIM_PIXEL = 0u;
const uint DIM_TIME = 1u;
const uint DIM_LENS = 2u;
const uint DIM_FIRST_VERTEX = 3u;

// The G-buffer pass's descriptor bindings (gbuffer_layout.glsl, gbuffer.frag; render::gbuffer::GBufferPass).
const uint GBUFFER_BINDING_DRAWS = 0u;
const uint GBUFFER_BINDING_MATERIALS = 1u;
const uint GBUFFER_BINDING_TEXTURES = 2u;

// The preview pass's descriptor bindings (preview_layout.glsl, preview.frag; render::preview::PreviewPass).
const uint PREVIEW_BINDING_DRAWS = 0u;
const uint PREVIEW_BINDING_TEXTURES = 1u;

// The resolve pass (resolve.comp; render::resolve::ResolvePass): its bindings and its square workgroup's side.
const uint RESOLVE_BINDING_ACCUMULATION = 0u;
const uint RESOLVE_BINDING_SUMS = 2u;
const uint RESOLVE_BINDING_DISPLAY = 1u;
const uint RESOLVE_TILE_SIZE = 8u;

// The probes' compute shaders (ray_probe.comp, noise_probe.comp, sampling_probe.comp): one workgroup size for
// all three (one invocation per ray or point), and their bindings.
const uint PROBE_WORKGROUP_SIZE = 64u;
const uint RAY_PROBE_BINDING_TLAS = 0u;
const uint RAY_PROBE_BINDING_RAYS = 1u;
const uint RAY_PROBE_BINDING_HITS = 2u;
const uint NOISE_PROBE_BINDING_POINTS = 0u;
const uint NOISE_PROBE_BINDING_RESULTS = 1u;
const uint SAMPLING_PROBE_BINDING_RESULTS = 0u;

// The skinning pass (skin.comp; render::skinning::SkinningPass): one invocation per vertex.
const uint SKIN_WORKGROUP_SIZE = 64u;
#endif
