//! Perlin's improved gradient noise (Perlin 2002, "Improving Noise") with its analytic gradient, fBm and
//! turbulence (Perlin 1985). CPU twin of `shaders/include/noise.glsl`: same lattice hash, same gradient set,
//! same operation order, so the GPU agrees to float rounding.
use glam::{Vec3, Vec4};

/// Integer hash of a lattice cell, in place of Perlin's 256-entry permutation table: a table indexed per pixel is
/// slow on SIMD CPU rasterizers (lavapipe materializes and gathers it per call), a hash is a few multiplies on
/// any GPU. lowbias32 (Chris Wellons, "Prospecting for Hash Functions", 2018), nested per axis.
pub fn lattice_hash(x: i32, y: i32, z: i32) -> u32 {
    fn lowbias32(mut v: u32) -> u32 {
        v ^= v >> 16;
        v = v.wrapping_mul(0x7feb_352d);
        v ^= v >> 15;
        v = v.wrapping_mul(0x846c_a68b);
        v ^= v >> 16;
        v
    }
    lowbias32((x as u32).wrapping_add(lowbias32((y as u32).wrapping_add(lowbias32(z as u32)))))
}

/// The gradient of improved noise for hash `h`: Perlin's 2002 `grad()` written as a vector (12 cube edges, with
/// four repeated to make 16 cases): u is x for h < 8 else y; v is y for h < 4, x for h = 12 or 14, else z; the
/// low two bits negate u and v. Selects, not a table, for the same reason as [`lattice_hash`].
pub fn gradient(hash: u32) -> Vec3 {
    let h = hash & 15;
    let su = if h & 1 != 0 { -1.0 } else { 1.0 };
    let sv = if h & 2 != 0 { -1.0 } else { 1.0 };
    let v_is_x = h == 12 || h == 14;
    Vec3::new(
        if h < 8 {
            su
        } else if v_is_x {
            sv
        } else {
            0.0
        },
        if h < 8 {
            if h < 4 {
                sv
            } else {
                0.0
            }
        } else {
            su
        },
        if h < 8 {
            if h < 4 {
                0.0
            } else {
                sv
            }
        } else if v_is_x {
            0.0
        } else {
            sv
        },
    )
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
    // Gradients and offsets at the 8 corners (corner i has offset bits x = i&1, y = i&2, z = i&4).
    let corners: [(Vec3, Vec3); 8] = std::array::from_fn(|i| {
        let (dx, dy, dz) = ((i & 1) as i32, ((i >> 1) & 1) as i32, ((i >> 2) & 1) as i32);
        let g = gradient(lattice_hash(xi.wrapping_add(dx), yi.wrapping_add(dy), zi.wrapping_add(dz)));
        (g, f - Vec3::new(dx as f32, dy as f32, dz as f32))
    });
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
    fn gradients_are_perlins_twelve_edges() {
        // The 2002 reference grad(h, x, y, z) as dot products, case by case.
        let reference = |h: u32, p: Vec3| -> f32 {
            let h = h & 15;
            let u = if h < 8 { p.x } else { p.y };
            let v = if h < 4 {
                p.y
            } else if h == 12 || h == 14 {
                p.x
            } else {
                p.z
            };
            (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
        };
        let p = Vec3::new(0.3, -1.7, 2.9);
        for h in 0..16 {
            let g = gradient(h);
            assert_eq!(g.dot(p), reference(h, p), "h = {h}");
            assert_eq!(g.abs().element_sum(), 2.0, "h = {h}: a cube edge has two ±1 components");
        }
    }

    #[test]
    fn the_hash_spreads_neighbouring_cells_over_all_gradients() {
        let mut counts = [0u32; 16];
        for x in -8..8 {
            for y in -8..8 {
                for z in -8..8 {
                    counts[(lattice_hash(x, y, z) & 15) as usize] += 1;
                }
            }
        }
        // 4096 cells over 16 buckets: each near 256.
        assert!(counts.iter().all(|&c| (200..=312).contains(&c)), "{counts:?}");
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
