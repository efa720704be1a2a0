//! `shaders/include/noise.glsl` on the GPU equals its CPU twin `strata::math::noise` within 1e-5, for noise,
//! fBm and turbulence values and gradients, at 100,000 points; and its value-only functions give exactly the
//! values of the functions with gradients (central-difference bump mapping uses them).
use crate::common;

use glam::Vec3;
use strata::math::noise::{fbm_with_gradient, noise_with_gradient, turbulence_with_gradient};
use strata::render::noise_probe::NoiseProbe;

#[test]
fn gpu_noise_equals_the_rust_twin_at_100k_points() {
    let gpu = common::GpuTest::raster_only();
    let probe = NoiseProbe::new(gpu.device()).unwrap();
    // A deterministic scatter over many lattice cells, negative coordinates included.
    let points: Vec<Vec3> = (0..100_000u32)
        .map(|i| {
            let h = |k: u32| {
                (i.wrapping_mul(2_654_435_761).wrapping_add(k.wrapping_mul(40_503)) >> 8) as f32 / 16_777_216.0
            };
            Vec3::new(h(1) * 64.0 - 32.0, h(2) * 64.0 - 32.0, h(3) * 16.0 - 8.0)
        })
        .collect();
    let (octaves, lacunarity, gain) = (5, 2.0, 0.5);
    let gpu_values = probe.evaluate(&points, octaves, lacunarity, gain).unwrap();
    let mut worst = [0.0f32; 3];
    let mut value_only_differs = Vec::new();
    for (p, g) in points.iter().zip(&gpu_values) {
        let with_gradients = Vec3::new(g[0].w, g[1].w, g[2].w);
        if g[3].truncate().to_array().map(f32::to_bits) != with_gradients.to_array().map(f32::to_bits) {
            value_only_differs.push((*p, g[3].truncate(), with_gradients));
        }
        let cpu = [
            noise_with_gradient(*p),
            fbm_with_gradient(*p, octaves, lacunarity, gain),
            turbulence_with_gradient(*p, octaves, lacunarity, gain),
        ];
        for k in 0..3 {
            // Gradients of the higher octaves scale with frequency; compare relative to that scale.
            let scale = if k == 0 { 1.0 } else { lacunarity.powi(octaves as i32 - 1) };
            let value = (cpu[k].w - g[k].w).abs();
            let gradient = (cpu[k].truncate() - g[k].truncate()).abs().max_element() / scale;
            worst[k] = worst[k].max(value.max(gradient));
        }
    }
    drop(probe);
    gpu.finish().unwrap();
    eprintln!("worst |GPU − CPU|: noise {:.2e}, fBm {:.2e}, turbulence {:.2e}", worst[0], worst[1], worst[2]);
    assert!(worst.iter().all(|&w| w < 1e-5), "GPU and CPU noise differ by up to {worst:?}");
    assert!(
        value_only_differs.is_empty(),
        "{} points where the value-only functions differ from the values with gradients, e.g. {:?}",
        value_only_differs.len(),
        &value_only_differs[..value_only_differs.len().min(3)]
    );
}
