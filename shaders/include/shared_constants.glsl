// Numbers both languages read from this one file: GLSL includes it, and build.rs turns each line of the form
// `const uint NAME = VALUEu;` into `pub const NAME: u32 = VALUE;` in Rust (strata::shaders::constants). Nothing
// else belongs here: build.rs fails on a line it cannot read.
#ifndef SHARED_CONSTANTS_GLSL
#define SHARED_CONSTANTS_GLSL
// The accumulation pass's descriptor bindings (accumulate_bindings.glsl; render::accumulate::AccumulatePass).
const uint ACCUMULATE_BINDING_TLAS = 0u;
const uint ACCUMULATE_BINDING_GBUFFER = 1u;
const uint ACCUMULATE_BINDING_GBUFFER_IDS = 2u;
const uint ACCUMULATE_BINDING_ACCUMULATION = 3u;
const uint ACCUMULATE_BINDING_MATERIALS = 4u;
const uint ACCUMULATE_BINDING_LIGHTS = 5u;
const uint ACCUMULATE_BINDING_PRIMITIVES = 6u;
const uint ACCUMULATE_BINDING_TEXTURES = 7u;
const uint ACCUMULATE_BINDING_COUNTERS = 8u;
const uint ACCUMULATE_BINDING_CAMERAS = 9u;
// The side of the accumulation compute shader's square workgroup: one tile of its tile queue.
const uint ACCUMULATE_TILE_SIZE = 8u;
// Counters per sample slot (binding 8): shadow rays, secondary rays, the next tile to shade.
const uint COUNTER_SHADOW_RAYS = 0u;
const uint COUNTER_SECONDARY_RAYS = 1u;
const uint COUNTER_NEXT_TILE = 2u;
const uint COUNTERS_PER_SLOT = 3u;
#endif
