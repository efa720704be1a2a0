// The accumulation pass's data; mirrored by src/render/accumulate_layout.rs (size/offset tests there).
#ifndef ACCUMULATE_LAYOUT_GLSL
#define ACCUMULATE_LAYOUT_GLSL
// Light kinds (LIGHT_*) and direct-light estimators (DIRECT_*) are shared constants.
#include "shared_constants.glsl"

struct GpuLight {
    vec4 position_kind;  // xyz centre or first vertex, w kind
    vec4 axis_u;         // xyz half extent u / radius * u axis / edge 1, w radius
    vec4 axis_v;         // xyz half extent v / radius * v axis / edge 2, w area
    vec4 normal;         // xyz direction of travel, w two-sided
    vec4 emission;       // rgb, w selection CDF (inclusive)
    vec4 cone;           // x cos outer, y cos inner, z range of points and spots (0: infinite), w selection probability
    vec4 uv01;           // emissive triangles: TEXCOORD_0 of p0 (xy) and p1 (zw), untransformed
    vec4 uv2_material;   // emissive triangles: TEXCOORD_0 of p2 (xy), z material (-1: not geometry)
    vec4 corner_alpha;   // emissive triangles: COLOR_0 alpha at p0, p1, p2 (xyz)
    vec4 uv1_01;         // emissive triangles: TEXCOORD_1 of p0 (xy) and p1 (zw)
    vec4 uv1_2;          // emissive triangles: TEXCOORD_1 of p2 (xy)
};

struct GpuPrimitiveRecord {
    uint64_t positions;
    uint64_t normals;
    uint64_t uvs;
    uint64_t indices;
    uint64_t colors;
    uint64_t dpdu;
    uint64_t dpdv;
    uint material;
    uint pad0;
    uint64_t uvs1;  // TEXCOORD_1 (TEXCOORD_0's values without it)
};

struct GpuCamera {
    mat4 world_from_camera;
    vec4 lens;   // xy half image extent at distance 1 (or in metres, orthographic), z aperture, w focus distance
    vec4 range;  // x near, y far, z 1 orthographic
};

// Counters per sample slot (binding 8): shared_constants.glsl.
#include "shared_constants.glsl"

layout(push_constant, std430) uniform AccumulatePush {
    vec4 eye;          // w: 1 orthographic
    vec4 forward;
    vec4 background;
    uint width;
    uint height;
    uint sample_index;
    uint sample_count;
    uint sampler_kind;
    uint seed;
    uint light_offset;
    uint light_count;
    uint analytic_light_count;
    uint counter_slot;
    uint max_depth;
    float total_light_power;  // the sum the selection probabilities were divided by
    uint64_t ray_log;         // where to record every ray cast (RayLog, the benchmark's replay probe), or 0
    uint indirect;            // 1: paths also go on by the diffuse lobe (diffuse interreflection, Kajiya 1986)
    uint direct_light;        // how direct light is estimated: DIRECT_MIS, DIRECT_LIGHT_SAMPLING, DIRECT_BSDF_SAMPLING
    uint alpha_moment;        // 1: alpha accumulates each sample's squared luminance instead of coverage
    uint sabotage;            // SABOTAGE_* bits: strata check's canaries break the render on purpose; 0 otherwise
    uint shading_samples;  // paths traced from each camera sample's visible surface (1 or more)
    uint pad_end1;  // to the Rust struct's 16-byte multiple
} pc;

#endif
