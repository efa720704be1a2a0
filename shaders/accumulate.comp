#version 460
// The accumulation pass with ray queries (VK_KHR_ray_query): the shading body of path_tracer.glsl run by a
// compute shader whose workgroups take 8×8 tiles from a queue. accumulate.rgen runs the same body in a
// ray-tracing pipeline where ray queries are missing.
#extension GL_EXT_ray_query : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_nonuniform_qualifier : require
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

// The workgroup's chain rays, packed: lavapipe runs 8 lanes in lockstep, so chains scattered over the
// workgroup would keep every lane group looping; packed, only ceil(count / 8) groups follow them.
shared uint group_chain_count;
shared ChainRay group_chains[GROUP_SIZE];
shared vec3 group_chain_radiance[GROUP_SIZE];
shared uint group_shadow_rays;
shared uint group_secondary_rays;

// One path of each pixel of an 8×8 tile, shaded by the workgroup in two rounds: each lane its own pixel's visible
// vertex, then the first group_chain_count lanes the tile's chains, packed. Returns the lane's path value. Called
// in uniform control flow (`last_path` too): it holds the barriers around the packing. The rounds share one call
// of the shading body (trace_path says why).
vec4 shade_tile(uvec2 pixel, uint lane, bool last_path, inout uint shadow_rays, inout uint secondary_rays) {
    bool in_image = pixel.x < pc.width && pixel.y < pc.height;
    vec4 value = vec4(0.0);
    bool chain = false;
    ChainRay r = start_path(pixel, lane);
    // Uniform: CHAINS is a specialization constant; without chain code there is nothing to pack and no barrier.
    uint rounds = CHAINS != 0u ? 2u : 1u;
    for (uint round = 0u; round < rounds; round++) {
        bool shading = round == 0u ? in_image : lane < group_chain_count;
        if (round == 1u && shading) r = group_chains[lane];
        bool goes_on = false;
        vec4 part = vec4(0.0);
        if (shading) part = trace_path(r, goes_on, shadow_rays, secondary_rays);
        if (round == 0u) {
            value = part;
            chain = goes_on;
            if (goes_on) group_chains[atomicAdd(group_chain_count, 1u)] = r;
        } else if (shading) {
            group_chain_radiance[r.lane] = part.rgb;
        }
        if (CHAINS != 0u) {
            memoryBarrierShared();
            barrier();
        }
    }
    if (CHAINS == 0u) return path_value(value);

    if (chain) value.rgb += group_chain_radiance[lane];
    if (!last_path) {
        // Every lane has read its chain's radiance before the tile's next path packs its own (after the last,
        // taking the next tile does this).
        barrier();
        if (lane == 0u) group_chain_count = 0u;
        memoryBarrierShared();
        barrier();
    }
    return path_value(value);
}

// A tile's camera sample: pc.shading_samples paths from each pixel's visible surface, their mean into the sums.
void shade_tile_sample(uvec2 pixel, uint lane, inout uint shadow_rays, inout uint secondary_rays) {
    vec4 paths_sum = vec4(0.0);
    // Uniform: a push constant.
    for (uint k = 0u; k < pc.shading_samples; k++) {
        begin_path(k);
        paths_sum += shade_tile(pixel, lane, k + 1u == pc.shading_samples, shadow_rays, secondary_rays);
    }
    if (pixel.x < pc.width && pixel.y < pc.height) accumulate_sample(pixel, paths_sum, pc.shading_samples);
}

// The tile the workgroup shades next, row by row over the image, from this sample's tile counter.
shared uint group_tile;

// Each workgroup shades tiles until the sample's counter passes the last one (persistent threads: Aila and Laine,
// "Understanding the Efficiency of Ray Traversal on GPUs", HPG 2009). Tiles cost very different amounts (sky,
// a diffuse wall, glass), and lavapipe hands each thread one fixed, contiguous run of a dispatch's workgroups
// (lp_cs_tpool), so with one tile per workgroup the thread with the costlier half of the image ran on alone for
// much of the pass (docs/performance.md); taken from a shared counter, tiles go to whichever thread is free.
// Which workgroup shades a tile changes nothing in it: the picture is the same bits.
void main() {
    uint lane = gl_LocalInvocationIndex;
    uint tiles_x = (pc.width + gl_WorkGroupSize.x - 1u) / gl_WorkGroupSize.x;
    uint tiles = tiles_x * ((pc.height + gl_WorkGroupSize.y - 1u) / gl_WorkGroupSize.y);
    uint slot = COUNTERS_PER_SLOT * pc.counter_slot;
    uint shadow_rays = 0u;
    uint secondary_rays = 0u;
    if (lane == 0u) {
        group_shadow_rays = 0u;
        group_secondary_rays = 0u;
    }
    for (;;) {
        if (lane == 0u) {
            group_tile = atomicAdd(counters[slot + COUNTER_NEXT_TILE], 1u);
            group_chain_count = 0u;
        }
        memoryBarrierShared();
        barrier();
        uint tile = group_tile;
        if (tile >= tiles) break;
        shade_tile_sample(uvec2(tile % tiles_x, tile / tiles_x) * gl_WorkGroupSize.xy + gl_LocalInvocationID.xy,
                          lane, shadow_rays, secondary_rays);
        // Every lane has read the tile and its chains' radiance before lane 0 takes the next.
        barrier();
    }

    atomicAdd(group_shadow_rays, shadow_rays);
    atomicAdd(group_secondary_rays, secondary_rays);
    memoryBarrierShared();
    barrier();
    if (lane == 0u) {
        atomicAdd(counters[slot + COUNTER_SHADOW_RAYS], group_shadow_rays);
        atomicAdd(counters[slot + COUNTER_SECONDARY_RAYS], group_secondary_rays);
    }
}
