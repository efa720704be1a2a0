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
#extension GL_KHR_shader_subgroup_shuffle : require
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

// The lane that holds the n-th (from 0) set bit of a subgroup ballot.
uint nth_set_lane(uvec4 ballot, uint n) {
    for (uint word = 0u; word < 4u; word++) {
        uint bits = ballot[word];
        uint count = uint(bitCount(bits));
        if (n < count) {
            for (uint i = 0u; i < n; i++) bits &= bits - 1u;
            return word * 32u + uint(findLSB(bits));
        }
        n -= count;
    }
    return 0u;
}

// Lane `lane`'s chain ray, field by field (subgroupShuffle takes no structs): every field of ChainRay (path.glsl).
ChainRay shuffle_chain(ChainRay r, uint lane) {
    ChainRay s;
    s.origin = subgroupShuffle(r.origin, lane);
    s.pdf = subgroupShuffle(r.pdf, lane);
    s.dir = subgroupShuffle(r.dir, lane);
    s.pixel = subgroupShuffle(r.pixel, lane);
    s.throughput = subgroupShuffle(r.throughput, lane);
    s.cone = subgroupShuffle(r.cone, lane);
    s.t_range = subgroupShuffle(r.t_range, lane);
    s.depth = subgroupShuffle(r.depth, lane);
    s.gather_only = subgroupShuffle(r.gather_only, lane);
    s.channel = subgroupShuffle(r.channel, lane);
    return s;
}

// A path's chain between lanes: its ray and the value of the path's visible vertex, and whether there is one (a
// lane's own chain waiting for a slot, or a slot holding one).
struct PendingChain {
    ChainRay ray;
    vec4 value;
    bool present;
};

// The subgroup's next run from the sample's queue: false once the queue is past the last tile; else this lane's
// pixel of it (which may lie past the image's edge in a partial tile).
bool take_run(uint tiles_x, uint tiles, uint width, out uvec2 pixel) {
    uint run = 0u;
    if (subgroupElect()) run = atomicAdd(counters[COUNTERS_PER_SLOT * pc.counter_slot + COUNTER_NEXT_RUN], 1u);
    // The elected lane is the subgroup's first active one.
    run = subgroupBroadcastFirst(run);
    uint runs_per_tile = GROUP_SIZE / width;
    uint tile = run / runs_per_tile;
    uint lane = (run % runs_per_tile) * width + gl_SubgroupInvocationID;
    pixel = uvec2(tile % tiles_x, tile / tiles_x) * gl_WorkGroupSize.xy +
            uvec2(lane % gl_WorkGroupSize.x, lane / gl_WorkGroupSize.x);
    return tile < tiles;
}

// Moves the waiting chains (`fresh`, present) into free slots (`held`, not present), in lane order, as many as
// there are free; those that find none stay waiting. Returns how many slots are held now (`held_count` before).
uint gather_waiting(inout PendingChain fresh, inout PendingChain held, uint held_count, uint width) {
    uvec4 waiting = subgroupBallot(fresh.present);
    uint waiting_count = subgroupBallotBitCount(waiting);
    if (waiting_count == 0u) return held_count;
    uint moved = min(waiting_count, width - held_count);
    uint slot_rank = subgroupBallotExclusiveBitCount(subgroupBallot(!held.present));
    bool receives = !held.present && slot_rank < moved;
    uint source = receives ? nth_set_lane(waiting, slot_rank) : gl_SubgroupInvocationID;
    ChainRay ray = shuffle_chain(fresh.ray, source);
    vec4 value = subgroupShuffle(fresh.value, source);
    if (receives) held = PendingChain(ray, value, true);
    if (fresh.present && subgroupBallotExclusiveBitCount(waiting) < moved) fresh.present = false;
    return held_count + moved;
}

// Each subgroup shades runs of pixels until the sample's counter passes the last one (persistent threads: Aila and
// Laine, "Understanding the Efficiency of Ray Traversal on GPUs", HPG 2009). A run is a subgroup's width of an
// 8×8 tile's pixels in row order: on lavapipe (8 lanes) one row of a tile, on a GPU a few. Runs cost very
// different amounts (sky, a diffuse wall, glass), and lavapipe hands each thread one fixed, contiguous stretch of
// a dispatch's workgroups (lp_cs_tpool), so with fixed work per workgroup the thread with the costlier half of the
// image ran on alone for much of the pass (docs/performance.md); taken from a shared counter, runs go to whichever
// thread is free. A pixel's visible vertex always shares its SIMD vector with the same neighbours (lavapipe's
// texture filtering can round a lane differently by what the other lanes read), so which subgroup shades a run
// changes nothing in it, and the picture is accumulate.rgen's bits, whose 8-pixel runs are these rows.
//
// Chains are gathered: lavapipe runs a subgroup's lanes as one vector, so a chain in any lane makes every lane
// wait for it. With one path per camera sample a path whose chain goes on hands its chain ray to a free slot
// (any lane's, by shuffles) and its lane goes on to the next run; the slots' chains are shaded together once they
// fill the vector (and at the end), each then adding its path's value to its pixel. With several paths a pixel
// sums them in order, so each lane follows its own chains, as accumulate.rgen does.
//
// No workgroup barrier, and no shared memory: lavapipe compiles a compute shader whose module holds a barrier, even
// one never reached, so that each 8-lane vector can stop there, and that alone cost the pass about a quarter of its
// time (docs/performance.md, "No barrier in the accumulation pass"). Every branch on which subgroup operations
// follow is uniform in the subgroup.
void main() {
    uint tiles_x = (pc.width + gl_WorkGroupSize.x - 1u) / gl_WorkGroupSize.x;
    uint tiles = tiles_x * ((pc.height + gl_WorkGroupSize.y - 1u) / gl_WorkGroupSize.y);
    // Subgroup sizes are powers of two, so a width up to the workgroup's divides its 64 pixels.
    uint width = min(gl_SubgroupSize, GROUP_SIZE);
    uint shadow_rays = 0u;
    uint secondary_rays = 0u;
    // Uniform: a push constant (and without chain code, a constant, so none of the gathering is compiled).
    bool gather = CHAINS != 0u && pc.shading_samples == 1u;
    // The lane's pixel of the current run, the path of it shaded next (k == pc.shading_samples: take a new run) and
    // the sum of its paths so far.
    uvec2 pixel = uvec2(0u);
    bool in_image = false;
    uint k = pc.shading_samples;
    vec4 paths_sum = vec4(0.0);
    // The path whose visible vertex the lane shaded last (present: its chain waits for a slot), and the lane's slot.
    PendingChain fresh = PendingChain(start_path(uvec2(0u)), vec4(0.0), false);
    PendingChain held = fresh;
    // Uniform in the subgroup, as every condition below that subgroup operations follow.
    uint held_count = 0u;
    bool runs_left = true;
    for (;;) {
        bool chain_round = CHAINS != 0u && (held_count == width || (held_count > 0u && (!gather || !runs_left)));
        if (!chain_round) {
            if (!runs_left) break;
            if (k == pc.shading_samples) {
                runs_left = take_run(tiles_x, tiles, width, pixel);
                if (!runs_left) continue;
                in_image = pixel.x < pc.width && pixel.y < pc.height;
                k = 0u;
                paths_sum = vec4(0.0);
            }
            begin_path(k);
            fresh.ray = start_path(pixel);
        }
        ChainRay r = chain_round ? held.ray : fresh.ray;
        bool shading = chain_round ? held.present : in_image;
        bool goes_on = false;
        vec4 part = vec4(0.0);
        // The one call of the shading body (trace_path says why): a visible vertex, or a chain.
        if (shading) part = trace_path(r, goes_on, shadow_rays, secondary_rays);
        if (chain_round) {
            // The chain's own sum added to its visible vertex's, as accumulate.rgen adds them.
            vec4 value = held.value;
            value.rgb += part.rgb;
            uint p = held.ray.pixel;
            if (gather && held.present) accumulate_sample(uvec2(p % pc.width, p / pc.width), path_value(value), 1u);
            if (!gather && held.present) fresh.value = value;
            held.present = false;
            held_count = 0u;
        } else {
            fresh = PendingChain(r, part, shading && goes_on);
            if (gather && shading && !goes_on) accumulate_sample(pixel, path_value(part), 1u);
            // One path a pixel: the run's only path is shaded (its chain, if any, goes on from a slot).
            if (gather) k = pc.shading_samples;
        }
        if (gather) {
            held_count = gather_waiting(fresh, held, held_count, width);
        } else {
            // Several paths a pixel: its chain is its lane's own, shaded in the next round, before the next path.
            if (!chain_round) {
                held = fresh;
                held_count = CHAINS != 0u ? subgroupBallotBitCount(subgroupBallot(held.present)) : 0u;
            }
            if (chain_round || held_count == 0u) {
                if (in_image) paths_sum += path_value(fresh.value);
                k++;
                if (k == pc.shading_samples && in_image) accumulate_sample(pixel, paths_sum, pc.shading_samples);
            }
        }
    }
    uint slot = COUNTERS_PER_SLOT * pc.counter_slot;
    if (shadow_rays != 0u) atomicAdd(counters[slot + COUNTER_SHADOW_RAYS], shadow_rays);
    if (secondary_rays != 0u) atomicAdd(counters[slot + COUNTER_SECONDARY_RAYS], secondary_rays);
}
