//! Sample points, as pure functions of (seed, pixel, sample index, dimension) — CPU twin of
//! `shaders/include/sampling.glsl`. Samplers after Cook, Porter and Carpenter (1984): `regular` (strata
//! centres), `random` (uniform), `jittered` (n×n strata, one random point in each), Kensler's correlated
//! multi-jittered sampling (2013), stratified in 2D and in each 1D projection, and Burley's shuffled,
//! Owen-scrambled Sobol points (2020), whose power-of-two prefixes are (0,m,2)-nets. Strata of different
//! dimensions, and of different pixels, are paired through hash-based random permutations (Cook's decorrelation).
use crate::scene::settings::SamplerKind;
use glam::Vec2;

/// PCG-family integer hash (RXS-M-XS; Jarzynski and Olano 2020, "Hash Functions for GPU Rendering").
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28).wrapping_add(4))) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// A key for (seed, pixel, dimension): what decorrelates permutations and jitter across pixels and dimensions.
pub fn key(seed: u32, pixel: u32, dimension: u32) -> u32 {
    pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(dimension.wrapping_add(0x9e37_79b9))))
}

/// A uniform float in [0, 1) from a hash: the top 24 bits, exactly representable.
pub fn unit_float(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Kensler's hash-based permutation of [0, l): element `i` of a random permutation chosen by `p` (CMJ paper,
/// Listing 3), without tables; cycle-walks to stay inside [0, l).
pub fn permute(mut i: u32, l: u32, p: u32) -> u32 {
    if l <= 1 {
        return 0;
    }
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            return i.wrapping_add(p) % l;
        }
    }
}

/// Kensler's hash to a float in [0, 1) (CMJ paper, Listing 4), kept for the CMJ construction.
fn randfloat(mut i: u32, p: u32) -> f32 {
    i ^= p;
    i ^= i >> 17;
    i ^= i >> 10;
    i = i.wrapping_mul(0xb365_34e5);
    i ^= i >> 12;
    i ^= i >> 21;
    i = i.wrapping_mul(0x93fc_4795);
    i ^= 0xdf6e_307f;
    i ^= i >> 17;
    i = i.wrapping_mul(1 | (p >> 18));
    (i as f32 * (1.0 / 4_294_967_808.0)).min(1.0 - f32::EPSILON / 2.0)
}

/// A Laine-Karras-style permutation of a bit-reversed value: each bit flips depending only on the bits below
/// it (odd multiplies, additions and x ^= x·even all have that property), so on reversed digits it is an Owen
/// scramble. Vegdahl's constants ("Building a Better LK Hash", 2021), which randomise the high digits that
/// Burley's (2020) leave nearly fixed: with Burley's, error fell only as fast as jittered sampling's.
fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Owen's nested uniform scramble of a 32-bit fraction, by hashing (Burley 2020, Listing 3): each digit is
/// flipped by a random function of the digits before it. On an index it shuffles while keeping aligned blocks.
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// The second dimension of Sobol's sequence as a 32-bit fraction (the first is the bit-reversed index):
/// direction numbers from the primitive polynomial x + 1, v₀ = ½ and v_k = v_(k−1) xor v_(k−1)/2.
pub fn sobol_second_dimension(index: u32) -> u32 {
    let mut v = 0x8000_0000u32;
    let mut result = 0;
    for bit in 0..32 {
        if index & (1 << bit) != 0 {
            result ^= v;
        }
        v ^= v >> 1;
    }
    result
}

/// Seeds of the two coordinates' scrambles, derived from the pair's key.
const SOBOL_X_SALT: u32 = 0x2545_f491;
const SOBOL_Y_SALT: u32 = 0x68e3_1da4;

/// Burley's sampler for one pair of dimensions: the index is shuffled by a nested uniform scramble (every
/// power-of-two prefix stays an aligned block of the sequence, hence a (0,m,2)-net) and each coordinate is
/// Owen-scrambled with its own seed. Pairs of other dimensions or pixels have other keys: Burley's padding.
fn sobol_2d(key: u32, index: u32) -> Vec2 {
    let i = nested_uniform_scramble(index, key);
    let y = nested_uniform_scramble(sobol_second_dimension(i), pcg_hash(key ^ SOBOL_Y_SALT));
    Vec2::new(sobol_first(key, i), unit_float(y))
}

/// The first coordinate of `sobol_2d` for an already shuffled index; alone, the 1D sampler (an Owen-scrambled
/// van der Corput sequence).
fn sobol_first(key: u32, shuffled: u32) -> f32 {
    unit_float(nested_uniform_scramble(shuffled.reverse_bits(), pcg_hash(key ^ SOBOL_X_SALT)))
}

/// Strata per side for `count` samples: the smallest n with n² ≥ count.
pub fn strata_per_side(count: u32) -> u32 {
    let mut n = (count.max(1) as f32).sqrt() as u32;
    while n * n < count.max(1) {
        n += 1;
    }
    n.max(1)
}

/// Sample `index` of `count` in the 2D dimension pair `dimension` for `pixel`.
pub fn sample_2d(kind: SamplerKind, seed: u32, pixel: u32, index: u32, count: u32, dimension: u32) -> Vec2 {
    let count = count.max(1);
    let k = key(seed, pixel, dimension);
    match kind {
        SamplerKind::Regular => {
            let n = strata_per_side(count);
            let s = index % (n * n);
            Vec2::new(((s % n) as f32 + 0.5) / n as f32, ((s / n) as f32 + 0.5) / n as f32)
        }
        SamplerKind::Random => {
            let h = pcg_hash(k ^ pcg_hash(index));
            Vec2::new(unit_float(h), unit_float(pcg_hash(h)))
        }
        SamplerKind::Sobol => sobol_2d(k, index),
        SamplerKind::Jittered => {
            let n = strata_per_side(count);
            // Cook's decorrelation: this dimension's strata are visited in their own random order.
            let s = permute(index % (n * n), n * n, k);
            let h = pcg_hash(k ^ pcg_hash(index));
            Vec2::new(
                ((s % n) as f32 + unit_float(h)) / n as f32,
                ((s / n) as f32 + unit_float(pcg_hash(h))) / n as f32,
            )
        }
        SamplerKind::MultiJittered => {
            // Correlated multi-jittered (Kensler 2013, Listing 5): m×n strata with m·n ≥ count; each 1D
            // projection is stratified into m·n intervals as well.
            let m = strata_per_side(count);
            let n = count.div_ceil(m);
            let s = permute(index % (m * n), m * n, k.wrapping_mul(0x5163_3e2d));
            let sx = permute(s % m, m, k.wrapping_mul(0xa511_e9b3));
            let sy = permute(s / m, n, k.wrapping_mul(0x63d8_3595));
            let jx = randfloat(s, k.wrapping_mul(0xa399_d265));
            let jy = randfloat(s, k.wrapping_mul(0x711a_d6a5));
            Vec2::new(
                ((s % m) as f32 + (sy as f32 + jx) / n as f32) / m as f32,
                ((s / m) as f32 + (sx as f32 + jy) / m as f32) / n as f32,
            )
        }
    }
}

/// Sample `index` of `count` in the 1D dimension `dimension` (e.g. shutter time): N strata visited in a random
/// order per pixel and dimension, jittered inside (regular: centres; random: uniform).
pub fn sample_1d(kind: SamplerKind, seed: u32, pixel: u32, index: u32, count: u32, dimension: u32) -> f32 {
    let count = count.max(1);
    let k = key(seed, pixel, dimension);
    let h = pcg_hash(k ^ pcg_hash(index));
    match kind {
        SamplerKind::Regular => ((index % count) as f32 + 0.5) / count as f32,
        SamplerKind::Random => unit_float(h),
        SamplerKind::Sobol => sobol_first(k, nested_uniform_scramble(index, k)),
        SamplerKind::Jittered | SamplerKind::MultiJittered => {
            (permute(index % count, count, k) as f32 + unit_float(h)) / count as f32
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [SamplerKind; 5] = [
        SamplerKind::Regular,
        SamplerKind::Random,
        SamplerKind::Jittered,
        SamplerKind::MultiJittered,
        SamplerKind::Sobol,
    ];

    #[test]
    fn permute_is_a_permutation() {
        for l in [1u32, 2, 3, 16, 17, 100] {
            for p in [0u32, 1, 0xdead_beef] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permute(i, l, p);
                    assert!(j < l && !seen[j as usize], "l = {l}, p = {p}: {i} → {j}");
                    seen[j as usize] = true;
                }
            }
        }
    }

    #[test]
    fn every_sample_lies_in_the_unit_square() {
        for kind in KINDS {
            for count in [1u32, 4, 7, 16, 64] {
                for i in 0..count {
                    let p = sample_2d(kind, 3, 11, i, count, 2);
                    assert!(p.cmpge(Vec2::ZERO).all() && p.cmplt(Vec2::ONE).all(), "{kind:?} {count}: {p}");
                    let t = sample_1d(kind, 3, 11, i, count, 1);
                    assert!((0.0..1.0).contains(&t));
                }
            }
        }
    }

    fn cells(points: &[Vec2], nx: u32, ny: u32) -> Vec<u32> {
        let mut c = vec![0u32; (nx * ny) as usize];
        for p in points {
            c[((p.y * ny as f32) as u32 * nx + (p.x * nx as f32) as u32) as usize] += 1;
        }
        c
    }

    #[test]
    fn jittered_puts_one_sample_in_each_stratum_and_decorrelates_dimensions() {
        let pts: Vec<Vec2> = (0..16).map(|i| sample_2d(SamplerKind::Jittered, 1, 5, i, 16, 0)).collect();
        assert!(cells(&pts, 4, 4).iter().all(|&c| c == 1));
        // Sample i sits in a different stratum in another dimension, and in another pixel (random pairing).
        let stratum = |p: Vec2| (p.y * 4.0) as u32 * 4 + (p.x * 4.0) as u32;
        let other_dim: Vec<u32> = (0..16).map(|i| stratum(sample_2d(SamplerKind::Jittered, 1, 5, i, 16, 1))).collect();
        let other_px: Vec<u32> = (0..16).map(|i| stratum(sample_2d(SamplerKind::Jittered, 1, 6, i, 16, 0))).collect();
        let same = |v: &[u32]| pts.iter().zip(v).filter(|(p, s)| stratum(**p) == **s).count();
        assert!(same(&other_dim) < 8 && same(&other_px) < 8, "{} {}", same(&other_dim), same(&other_px));
    }

    #[test]
    fn multi_jittered_is_stratified_in_2d_and_in_each_projection() {
        for count in [16u32, 64] {
            let n = strata_per_side(count);
            let pts: Vec<Vec2> =
                (0..count).map(|i| sample_2d(SamplerKind::MultiJittered, 9, 42, i, count, 3)).collect();
            assert!(cells(&pts, n, n).iter().all(|&c| c == 1), "{count}: 2D strata");
            assert!(cells(&pts, count, 1).iter().all(|&c| c == 1), "{count}: x projection");
            assert!(cells(&pts, 1, count).iter().all(|&c| c == 1), "{count}: y projection");
        }
    }

    #[test]
    fn regular_uses_the_same_centres_everywhere_and_random_is_uniform() {
        for pixel in [0u32, 17, 999] {
            let p = sample_2d(SamplerKind::Regular, 4, pixel, 5, 16, 2);
            assert_eq!(p, Vec2::new(0.375, 0.375));
        }
        let n = 20_000;
        let mean =
            (0..n).map(|i| sample_2d(SamplerKind::Random, 2, i, 0, 1, 0)).fold(Vec2::ZERO, |a, p| a + p) / n as f32;
        assert!((mean - Vec2::splat(0.5)).abs().max_element() < 0.01, "{mean}");
    }

    #[test]
    fn one_dimensional_strata_each_hold_one_sample() {
        let mut hit = [0u32; 16];
        for i in 0..16 {
            hit[(sample_1d(SamplerKind::Jittered, 8, 3, i, 16, 1) * 16.0) as usize] += 1;
        }
        assert!(hit.iter().all(|&h| h == 1), "{hit:?}");
    }

    #[test]
    fn sobols_second_dimension_starts_as_the_sequence_does() {
        let first: Vec<f32> = (0..8).map(|i| sobol_second_dimension(i) as f32 / 4_294_967_296.0).collect();
        assert_eq!(first, [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875]);
    }

    #[test]
    fn the_index_shuffle_keeps_power_of_two_blocks() {
        // Burley's shuffle maps the first 2^m indices onto one aligned block of 2^m, in some order.
        for key in [1u32, 0xdead_beef, 77] {
            for m in [1u32, 3, 6] {
                let shuffled: Vec<u32> = (0..1 << m).map(|i| nested_uniform_scramble(i, key)).collect();
                assert!(shuffled.iter().all(|s| s >> m == shuffled[0] >> m), "key {key}, 2^{m}: {shuffled:?}");
                let mut low: Vec<u32> = shuffled.iter().map(|s| s & ((1 << m) - 1)).collect();
                low.sort_unstable();
                assert!(low.iter().enumerate().all(|(i, &l)| l == i as u32), "key {key}, 2^{m}: {shuffled:?}");
            }
        }
    }

    #[test]
    fn sobol_prefixes_of_power_of_two_length_are_nets() {
        // A (0,m,2)-net: every elementary interval of area 2^-m (2^a × 2^(m−a) cells) holds exactly one point.
        for m in 0..=8u32 {
            let count = 1u32 << m;
            for (pixel, dimension) in [(0u32, 0u32), (5, 3), (1234, 8)] {
                let pts: Vec<Vec2> =
                    (0..count).map(|i| sample_2d(SamplerKind::Sobol, 7, pixel, i, count, dimension)).collect();
                for a in 0..=m {
                    let c = cells(&pts, 1 << a, 1 << (m - a));
                    assert!(c.iter().all(|&c| c == 1), "{count} points, {}x{} cells: {c:?}", 1 << a, 1 << (m - a));
                }
                let mut hit = vec![0u32; count as usize];
                for i in 0..count {
                    hit[(sample_1d(SamplerKind::Sobol, 7, pixel, i, count, dimension) * count as f32) as usize] += 1;
                }
                assert!(hit.iter().all(|&h| h == 1), "1D, {count} points: {hit:?}");
            }
        }
    }

    #[test]
    fn sobol_pairs_of_other_dimensions_and_pixels_are_scrambled_apart() {
        let stratum = |p: Vec2| (p.y * 4.0) as u32 * 4 + (p.x * 4.0) as u32;
        let strata = |pixel: u32, dimension: u32| -> Vec<u32> {
            (0..16).map(|i| stratum(sample_2d(SamplerKind::Sobol, 1, pixel, i, 16, dimension))).collect()
        };
        let base = strata(5, 0);
        let same = |v: Vec<u32>| base.iter().zip(&v).filter(|(a, b)| a == b).count();
        let (other_dim, other_px) = (same(strata(5, 1)), same(strata(6, 0)));
        assert!(other_dim < 8 && other_px < 8, "{other_dim} {other_px}");
    }
}
