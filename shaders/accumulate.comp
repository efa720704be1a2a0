#version 460
// The accumulation pass with ray queries (VK_KHR_ray_query): the shading body of path_tracer.glsl run by a
// compute shader whose subgroups take runs of pixels from a queue. accumulate.rgen runs the same body in a
// ray-tracing pipeline where ray queries are missing.
#extension GL_EXT_ray_query : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_nonuniform_qualifier : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#define GBUFFER_LAYOUT_STRUCTS_ONLY
#include "gbuffer_layout.glsl"
#include "accumulate_layout.glsl"
#include "sampling.glsl"
#include "brdf.glsl"
#include "lights.glsl"
#include "accumulate_bindings.glsl"
#include "hit_geometry.glsl"
#include "trace_query.glsl"
#include "path_tracer.glsl"

layout(local_size_x = ACCUMULATE_TILE_SIZE, local_size_y = ACCUMULATE_TILE_SIZE) in;
const uint GROUP_SIZE = gl_WorkGroupSize.x * gl_WorkGroupSize.y;

// Each subgroup shades runs of pixels until the sample's counter passes the last one (persistent threads: Aila and
// Laine, "Understanding the Efficiency of Ray Traversal on GPUs", HPG 2009). A run is a subgroup's width of an
// 8×8 tile's pixels in row order: on lavapipe (8 lanes) one row of a tile, on a GPU a few. Runs cost very
// different amounts (sky, a diffuse wall, glass), and lavapipe hands each thread one fixed, contiguous stretch of
// a dispatch's workgroups (lp_cs_tpool), so with fixed work per workgroup the thread with the costlier half of the
// image ran on alone for much of the pass (docs/performance.md); taken from a shared counter, runs go to whichever
// thread is free. Which subgroup shades a run changes nothing in it, and a pixel always shares its SIMD vector with
// the same neighbours (lavapipe's texture filtering can round a lane differently by what the other lanes read), so
// the picture is the same bits, and the same as accumulate.rgen's, whose 8-pixel runs are these rows.
//
// No workgroup barrier: lavapipe compiles a compute shader whose module holds one, even one never reached, so that
// each 8-lane vector can stop there, and that alone cost the pass about a quarter of its time (docs/performance.md,
// "No barrier in the accumulation pass").
void main() {
    uint tiles_x = (pc.width + gl_WorkGroupSize.x - 1u) / gl_WorkGroupSize.x;
    uint tiles = tiles_x * ((pc.height + gl_WorkGroupSize.y - 1u) / gl_WorkGroupSize.y);
    uint slot = COUNTERS_PER_SLOT * pc.counter_slot;
    // Subgroup sizes are powers of two, so a width up to the workgroup's divides its 64 pixels.
    uint width = min(gl_SubgroupSize, GROUP_SIZE);
    uint runs_per_tile = GROUP_SIZE / width;
    uint shadow_rays = 0u;
    uint secondary_rays = 0u;
    for (;;) {
        uint run = 0u;
        if (subgroupElect()) run = atomicAdd(counters[slot + COUNTER_NEXT_RUN], 1u);
        // Uniform in the subgroup: the elected lane is its first active one.
        run = subgroupBroadcastFirst(run);
        uint tile = run / runs_per_tile;
        if (tile >= tiles) break;
        uint lane = (run % runs_per_tile) * width + gl_SubgroupInvocationID;
        uvec2 pixel = uvec2(tile % tiles_x, tile / tiles_x) * gl_WorkGroupSize.xy +
                      uvec2(lane % gl_WorkGroupSize.x, lane / gl_WorkGroupSize.x);
        if (pixel.x < pc.width && pixel.y < pc.height) shade_pixel(pixel, shadow_rays, secondary_rays);
    }
    if (shadow_rays != 0u) atomicAdd(counters[slot + COUNTER_SHADOW_RAYS], shadow_rays);
    if (secondary_rays != 0u) atomicAdd(counters[slot + COUNTER_SECONDARY_RAYS], secondary_rays);
}
