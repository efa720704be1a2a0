// A pixel's samples summed in fixed point: each channel a 64-bit integer count of 2^-SUM_FRACTION_BITS. Integer
// addition is exact and associative, so the sum of a frame's samples does not depend on their order or grouping:
// the samples A..B of one run and B..N of another add up to the bits one run of 0..N makes (strata merge), and a
// render resumed from a checkpoint ends where an uninterrupted one does. The host side is src/partial/.
#ifndef FIXED_POINT_GLSL
#define FIXED_POINT_GLSL
#include "shared_constants.glsl"

const float SUM_SCALE = float(1u << SUM_FRACTION_BITS);
// The most one sample adds per channel (shared_constants.glsl says why).
const float SUM_MAX_SAMPLE = float(1u << SUM_MAX_SAMPLE_LOG2);

// A sample's value in counts, rounded to the nearest (negative values, which radiance never is, count as 0).
u64vec4 to_fixed_point(vec4 v) {
    return u64vec4(clamp(v, vec4(0.0), vec4(SUM_MAX_SAMPLE)) * SUM_SCALE + 0.5);
}

// The mean of `n` samples whose sum is `s`: the quotient and the remainder in integers, then one rounding each.
vec4 fixed_point_mean(u64vec4 s, uint n) {
    uint64_t n64 = uint64_t(max(n, 1u));
    u64vec4 q = s / n64;
    u64vec4 r = s - q * n64;
    return (vec4(q) + vec4(r) / float(max(n, 1u))) / SUM_SCALE;
}
#endif
