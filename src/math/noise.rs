//! Perlin's improved gradient noise (Perlin 2002, "Improving Noise") with its analytic gradient, fBm and
//! turbulence (Perlin 1985). CPU twin of `shaders/include/noise.glsl`: same permutation, same gradient set,
//! same operation order, so the GPU agrees to float rounding.
use glam::{Vec3, Vec4};

/// Ken Perlin's reference permutation of 0..=255 (Perlin 2002).
#[rustfmt::skip]
pub const PERMUTATION: [u8; 256] = [
    151,160,137,91,90,15,131,13,201,95,96,53,194,233,7,225,140,36,103,30,69,142,8,99,37,240,21,10,23,190,6,148,
    247,120,234,75,0,26,197,62,94,252,219,203,117,35,11,32,57,177,33,88,237,149,56,87,174,20,125,136,171,168,68,175,
    74,165,71,134,139,48,27,166,77,146,158,231,83,111,229,122,60,211,133,230,220,105,92,41,55,46,245,40,244,102,143,54,
    65,25,63,161,1,216,80,73,209,76,132,187,208,89,18,169,200,196,135,130,116,188,159,86,164,100,109,198,173,186,3,64,
    52,217,226,250,124,123,5,202,38,147,118,126,255,82,85,212,207,206,59,227,47,16,58,17,182,189,28,42,223,183,170,213,
    119,248,152,2,44,154,163,70,221,153,101,155,167,43,172,9,129,22,39,253,19,98,108,110,79,113,224,232,178,185,112,104,218,
    246,97,228,251,34,242,193,238,210,144,12,191,179,162,241,81,51,145,235,249,14,239,107,49,192,214,31,181,199,106,157,184,
    84,204,176,115,121,50,45,127,4,150,254,138,236,205,93,222,114,67,29,24,72,243,141,128,195,78,66,215,61,156,180,
];

fn perm(i: i32) -> i32 {
    i32::from(PERMUTATION[(i & 255) as usize])
}

/// The 12 cube-edge gradients of improved noise, picked by the low 4 bits of the hash (16 cases, four repeated).
fn gradient(hash: i32) -> Vec3 {
    match hash & 15 {
        0 => Vec3::new(1.0, 1.0, 0.0),
        1 => Vec3::new(-1.0, 1.0, 0.0),
        2 => Vec3::new(1.0, -1.0, 0.0),
        3 => Vec3::new(-1.0, -1.0, 0.0),
        4 => Vec3::new(1.0, 0.0, 1.0),
        5 => Vec3::new(-1.0, 0.0, 1.0),
        6 => Vec3::new(1.0, 0.0, -1.0),
        7 => Vec3::new(-1.0, 0.0, -1.0),
        8 => Vec3::new(0.0, 1.0, 1.0),
        9 => Vec3::new(0.0, -1.0, 1.0),
        10 => Vec3::new(0.0, 1.0, -1.0),
        11 => Vec3::new(0.0, -1.0, -1.0),
        12 => Vec3::new(1.0, 1.0, 0.0),
        13 => Vec3::new(0.0, -1.0, 1.0),
        14 => Vec3::new(-1.0, 1.0, 0.0),
        _ => Vec3::new(0.0, -1.0, -1.0),
    }
}

/// Quintic fade 6t⁵ − 15t⁴ + 10t³ (Perlin 2002) and its derivative 30t⁴ − 60t³ + 30t².
fn fade(t: f32) -> (f32, f32) {
    (t * t * t * (t * (t * 6.0 - 15.0) + 10.0), 30.0 * t * t * (t * (t - 2.0) + 1.0))
}

/// Noise value in `w` and its gradient in `xyz`. Zero at every integer lattice point.
pub fn noise_with_gradient(p: Vec3) -> Vec4 {
    let cell = p.floor();
    let (xi, yi, zi) = (cell.x as i32, cell.y as i32, cell.z as i32);
    let f = p - cell;
    let (u, du) = fade(f.x);
    let (v, dv) = fade(f.y);
    let (w, dw) = fade(f.z);
    let a = perm(xi) + yi;
    let (aa, ab) = (perm(a) + zi, perm(a + 1) + zi);
    let b = perm(xi + 1) + yi;
    let (ba, bb) = (perm(b) + zi, perm(b + 1) + zi);
    // Gradients and offsets at the 8 corners.
    let corners = [
        (gradient(perm(aa)), f),
        (gradient(perm(ba)), f - Vec3::new(1.0, 0.0, 0.0)),
        (gradient(perm(ab)), f - Vec3::new(0.0, 1.0, 0.0)),
        (gradient(perm(bb)), f - Vec3::new(1.0, 1.0, 0.0)),
        (gradient(perm(aa + 1)), f - Vec3::new(0.0, 0.0, 1.0)),
        (gradient(perm(ba + 1)), f - Vec3::new(1.0, 0.0, 1.0)),
        (gradient(perm(ab + 1)), f - Vec3::new(0.0, 1.0, 1.0)),
        (gradient(perm(bb + 1)), f - Vec3::new(1.0, 1.0, 1.0)),
    ];
    let n: [f32; 8] = std::array::from_fn(|i| corners[i].0.dot(corners[i].1));
    // Trilinear blend written out as polynomial coefficients, so the gradient is exact:
    // value = k0 + k1 u + k2 v + k3 w + k4 uv + k5 vw + k6 wu + k7 uvw.
    let k0 = n[0];
    let k1 = n[1] - n[0];
    let k2 = n[2] - n[0];
    let k3 = n[4] - n[0];
    let k4 = n[0] - n[1] - n[2] + n[3];
    let k5 = n[0] - n[2] - n[4] + n[6];
    let k6 = n[0] - n[1] - n[4] + n[5];
    let k7 = -n[0] + n[1] + n[2] - n[3] + n[4] - n[5] - n[6] + n[7];
    let value = k0 + k1 * u + k2 * v + k3 * w + k4 * u * v + k5 * v * w + k6 * w * u + k7 * u * v * w;
    // d/dp of Σ weight·(g·d) = Σ (d weight)·(g·d) + Σ weight·g.
    let g: [Vec3; 8] = std::array::from_fn(|i| corners[i].0);
    let blended_gradient = g[0]
        + (g[1] - g[0]) * u
        + (g[2] - g[0]) * v
        + (g[4] - g[0]) * w
        + (g[0] - g[1] - g[2] + g[3]) * (u * v)
        + (g[0] - g[2] - g[4] + g[6]) * (v * w)
        + (g[0] - g[1] - g[4] + g[5]) * (w * u)
        + (-g[0] + g[1] + g[2] - g[3] + g[4] - g[5] - g[6] + g[7]) * (u * v * w);
    let weight_gradient = Vec3::new(
        du * (k1 + k4 * v + k6 * w + k7 * v * w),
        dv * (k2 + k4 * u + k5 * w + k7 * u * w),
        dw * (k3 + k5 * v + k6 * u + k7 * u * v),
    );
    (blended_gradient + weight_gradient).extend(value)
}

pub fn noise(p: Vec3) -> f32 {
    noise_with_gradient(p).w
}

/// Fractional Brownian motion Σᵢ gainⁱ · noise(lacunarityⁱ · p) and its gradient (value in `w`).
pub fn fbm_with_gradient(p: Vec3, octaves: u32, lacunarity: f32, gain: f32) -> Vec4 {
    let (mut sum, mut amplitude, mut frequency) = (Vec4::ZERO, 1.0f32, 1.0f32);
    for _ in 0..octaves {
        let n = noise_with_gradient(p * frequency);
        sum += Vec4::new(n.x * frequency, n.y * frequency, n.z * frequency, n.w) * amplitude;
        amplitude *= gain;
        frequency *= lacunarity;
    }
    sum
}

/// Turbulence Σᵢ gainⁱ · |noise(lacunarityⁱ · p)| (Perlin 1985 with gain ½, lacunarity 2) and its gradient
/// (sign(noise) · ∇noise per octave; the kinks where noise crosses zero have gradient of either side).
pub fn turbulence_with_gradient(p: Vec3, octaves: u32, lacunarity: f32, gain: f32) -> Vec4 {
    let (mut sum, mut amplitude, mut frequency) = (Vec4::ZERO, 1.0f32, 1.0f32);
    for _ in 0..octaves {
        let n = noise_with_gradient(p * frequency);
        let s = if n.w < 0.0 { -1.0 } else { 1.0 };
        sum += Vec4::new(s * n.x * frequency, s * n.y * frequency, s * n.z * frequency, n.w.abs()) * amplitude;
        amplitude *= gain;
        frequency *= lacunarity;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(n: usize) -> impl Iterator<Item = Vec3> {
        // A fixed low-discrepancy-ish walk: deterministic, covers many cells and signs.
        (0..n).map(|i| {
            let t = i as f32;
            Vec3::new(
                (t * 0.754_877_7).fract() * 40.0 - 20.0,
                (t * 0.569_840_3).fract() * 40.0 - 20.0,
                (t * 0.362_001).fract() * 8.0 - 4.0,
            )
        })
    }

    #[test]
    fn the_table_is_a_permutation() {
        let mut seen = [false; 256];
        for &v in &PERMUTATION {
            assert!(!seen[v as usize], "{v} appears twice");
            seen[v as usize] = true;
        }
        // Spot checks against Perlin's reference listing.
        assert_eq!((PERMUTATION[0], PERMUTATION[160], PERMUTATION[255]), (151, 119, 180));
    }

    #[test]
    fn zero_at_every_lattice_point() {
        for x in -5..5 {
            for y in -5..5 {
                for z in -3..3 {
                    assert_eq!(noise(Vec3::new(x as f32, y as f32, z as f32)), 0.0);
                }
            }
        }
    }

    #[test]
    fn bounded() {
        // Improved noise is bounded by about ±1 (each corner term |g·d| ≤ 2, the blend contracts it).
        let max = points(100_000).map(|p| noise(p).abs()).fold(0.0, f32::max);
        assert!(max <= 1.05, "max |noise| {max}");
        assert!(max > 0.6, "noise is suspiciously flat: max {max}");
    }

    #[test]
    fn analytic_gradient_matches_central_differences_to_second_order() {
        // Central differences err by O(ε²): shrinking ε 4× shrinks the error ~16×.
        let error = |eps: f32| {
            points(2000)
                .map(|p| {
                    let g = noise_with_gradient(p).truncate();
                    let fd = Vec3::new(
                        noise(p + Vec3::X * eps) - noise(p - Vec3::X * eps),
                        noise(p + Vec3::Y * eps) - noise(p - Vec3::Y * eps),
                        noise(p + Vec3::Z * eps) - noise(p - Vec3::Z * eps),
                    ) / (2.0 * eps);
                    (g - fd).length()
                })
                .fold(0.0, f32::max)
        };
        let (coarse, fine) = (error(0.02), error(0.005));
        assert!(coarse < 0.05, "gradient error at ε = 0.02: {coarse}");
        assert!(fine < coarse / 6.0, "error should fall ~16× for ε/4: {coarse} → {fine}");
    }

    #[test]
    fn fbm_and_turbulence_sum_their_octaves() {
        let p = Vec3::new(1.3, -2.7, 0.4);
        let one = fbm_with_gradient(p, 1, 2.0, 0.5);
        assert_eq!(one, noise_with_gradient(p));
        let three = fbm_with_gradient(p, 3, 2.0, 0.5).w;
        let by_hand = noise(p) + 0.5 * noise(p * 2.0) + 0.25 * noise(p * 4.0);
        assert!((three - by_hand).abs() < 1e-6);
        let turb = turbulence_with_gradient(p, 3, 2.0, 0.5).w;
        let by_hand = noise(p).abs() + 0.5 * noise(p * 2.0).abs() + 0.25 * noise(p * 4.0).abs();
        assert!((turb - by_hand).abs() < 1e-6);
        assert!(turb >= 0.0);
    }
}
