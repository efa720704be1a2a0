// The accumulation pass's specialization constants, descriptor bindings and buffer-reference types, shared by
// its compute shader (ray queries) and its ray-tracing pipeline's shaders; the Rust side is
// src/render/accumulate.rs. Include after accumulate_layout.glsl and gbuffer_layout.glsl.
#ifndef ACCUMULATE_BINDINGS_GLSL
#define ACCUMULATE_BINDINGS_GLSL
#include "shared_constants.glsl"
// 1: trace each pixel's own primary ray instead of reading the G-buffer (a specialization constant, so each
// pipeline holds only its own path).
layout(constant_id = 0) const uint PRIMARY_RAYS = 0u;
// 1: some geometry is alpha-tested (glTF MASK or BLEND) and built non-opaque, so ray queries stop at its
// candidate triangles to test them; 0: every ray is forced opaque and the pipeline holds no alpha test.
layout(constant_id = 1) const uint ALPHA_TESTED = 0u;
// 1: the scene has an environment (environment.glsl); 0: none, and the pipeline holds none of its code (a
// larger shader costs lavapipe pipeline-creation time and registers even where the code never runs).
// constant_id 2 is accumulate.rgen's PIXEL_RUNS.
layout(constant_id = 3) const uint HAS_ENVIRONMENT = 0u;
// 1: paths may go on past the visible surface (--bounces above 0, or BSDF sampling alone, whose rays gather
// light past the last vertex); 0: they never do, and the pipeline holds no chain code. Direct light alone then
// costs less per sample and about 0.25 s less pipeline creation (docs/performance.md).
layout(constant_id = 4) const uint CHAINS = 1u;
// 1: some transmissive material disperses (KHR_materials_dispersion, dispersion.glsl); 0: none, and the pipeline
// holds none of its code (which also keeps every other scene's pixels the bits they were before it).
layout(constant_id = 5) const uint DISPERSION = 0u;
// 1: some material has a layer over its base (KHR_materials_clearcoat, _sheen; layers.glsl); 0: none, and the
// pipeline holds none of the layers' code.
layout(constant_id = 6) const uint LAYERS = 0u;
// The flags every ray starts with, besides its own: with no alpha-tested geometry every ray is opaque and the
// alpha test is never reached.
const uint TRACE_FLAGS = ALPHA_TESTED != 0u ? 0u : gl_RayFlagsOpaqueEXT;

layout(set = 0, binding = ACCUMULATE_BINDING_TLAS) uniform accelerationStructureEXT tlas;
// The G-buffer's attachments and how to read them.
#define GBUFFER_DECODE
#include "gbuffer_encoding.glsl"
// Per pixel, the sum of its samples in fixed point (fixed_point.glsl), row-major.
layout(set = 0, binding = ACCUMULATE_BINDING_SUMS, std430) buffer Sums { u64vec4 sums[]; };
layout(set = 0, binding = ACCUMULATE_BINDING_MATERIALS, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = ACCUMULATE_BINDING_LIGHTS, std430) readonly buffer Lights { GpuLight lights[]; };
layout(set = 0, binding = ACCUMULATE_BINDING_PRIMITIVES, std430) readonly buffer Primitives { GpuPrimitiveRecord primitives[]; };
layout(set = 0, binding = ACCUMULATE_BINDING_TEXTURES) uniform sampler2D textures[];
// Directional albedo tables per (roughness, view cosine), roughness-major (math::brdf::albedo_tables): the GGX
// lobe's terms (E1, E5), then from SHEEN_ALBEDO_TABLE on the sheen lobe's (E, 0).
layout(set = 0, binding = ACCUMULATE_BINDING_SPECULAR_ALBEDO, std430) readonly buffer AlbedoTables {
    vec2 albedo_tables[];
};
const uint SHEEN_ALBEDO_TABLE = SPECULAR_ALBEDO_MU_STEPS * SPECULAR_ALBEDO_ROUGHNESS_STEPS;
layout(set = 0, binding = ACCUMULATE_BINDING_COUNTERS, std430) buffer Counters { uint counters[]; };
layout(set = 0, binding = ACCUMULATE_BINDING_CAMERAS, std430) readonly buffer Cameras { GpuCamera cameras[]; };
// The environment (environment.glsl; src/render/environment.rs): a header, then texels and the sampling CDFs.
layout(set = 0, binding = ACCUMULATE_BINDING_ENVIRONMENT, std430) readonly buffer Environment {
    uint env_width;
    uint env_height;
    uint env_present;  // 0: no environment (the header alone)
    uint env_uniform;  // 1: sample directions uniformly over the sphere instead (for the tests' comparison)
    vec4 env_params;   // cos and sin of the rotation about +Y, intensity, unused
    float env_data[];
};

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer Vec3Array { vec3 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer Vec2Array { vec2 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer Vec4Array { vec4 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer UintArray { uint v[]; };
#endif
