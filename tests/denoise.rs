//! Denoising with Intel Open Image Denoise (issue 33): on the Cornell box at 8 spp the denoised picture's error
//! against a 1,024-path render is at most a third of the noisy one's and its mean within 2%; the host's display
//! image of a linear frame is the resolve pass's; and without the library `--denoise` is a clear error that says
//! how to install it. The library is not linked: where it is not installed the quality test says so and checks
//! only the error path, unless STRATA_REQUIRE_DENOISER is set (`.ci/run` installs it and sets it).
use crate::common;
use common::cli::{outcome, repo_file, strata, temp_dir};
use common::GpuTest;
use strata::denoise::Denoiser;
use strata::render::frame::{render_frame, FrameOptions};
use strata::scene::settings::{RenderSettings, ToneMap};

/// The image's side: large enough for the denoiser to see surfaces, not only edges.
const SIZE: u32 = 256;

fn luminance(p: &[f32; 4]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

#[test]
fn denoising_the_cornell_box_cuts_its_error_to_a_third_and_keeps_its_mean() {
    let denoiser = match Denoiser::load() {
        Ok(d) => d,
        Err(e) if std::env::var_os("STRATA_REQUIRE_DENOISER").is_none() => {
            let message = format!("{e:#}");
            assert!(message.contains("scripts/setup.sh --denoiser"), "{message}");
            eprintln!("NOTE: Open Image Denoise is not installed, so only its error was checked: {message}");
            return;
        }
        Err(e) => panic!("STRATA_REQUIRE_DENOISER is set but the denoiser does not load: {e:#}"),
    };
    let gpu = GpuTest::new();
    let mut scene = strata::load(&repo_file("scenes/cornell.toml"), &Default::default()).unwrap().scene;
    // The box as the bar of a third was set on it (issue 33): bumps by central differences, which at the default
    // step lose their finest octaves. With the exact gradient, the default since 2026-12-07, the walls carry fine
    // relief that the filter smooths with the noise: 0.00521 -> 0.00192, 0.37x (docs/outputs.md).
    for material in &mut scene.materials {
        if let Some(bump) = &mut material.bump {
            bump.derivative = strata::scene::BumpDerivative::CentralDifferences;
        }
    }
    let on_gpu = strata::render::SceneOnGpu::upload(gpu.device(), &scene).unwrap();
    // The noisy picture in the reference mode: each pixel draws its own sub-pixel point, so what is left at 8
    // samples is noise. In the raster mode every pixel shares each sample's jitter, and an edge's coverage from 8
    // shared points is an error no denoiser can tell from detail (docs/outputs.md: 2.75x there, against 3.2x here).
    use strata::scene::settings::Primary;
    let base = RenderSettings { width: SIZE, height: SIZE, tone_map: ToneMap::Filmic, ..RenderSettings::default() };
    let render = |spp: u32, shading_samples: u32, seed: u64, primary: Primary| {
        let settings = RenderSettings { spp, shading_samples, seed, primary, ..base.clone() };
        render_frame(gpu.device(), &scene, &on_gpu, &settings, &FrameOptions::default(), &mut |_, _| true).unwrap()
    };
    let noisy = render(8, 1, 1, Primary::Rays);
    // 1,024 paths a pixel: 64 sub-pixel points with 16 paths from each. The reference is rasterized: at 64 points
    // an edge pixel's coverage is as close in either mode (its own stratified points or the frame's), and the 16
    // paths of a point share one visible surface, where in the reference mode each traced its camera ray and
    // evaluated its hit's bump again. The errors read the same to three figures either way (noisy 0.00522,
    // denoised 0.00168; the mean 0.11% off against 0.08%) in two thirds of the time (52 s against 75-79 s on a
    // slow machine).
    let reference = render(64, 16, 2, Primary::Raster);
    let (albedo, normal) = strata::denoise_guides(gpu.device(), &scene, &on_gpu, (SIZE, SIZE)).unwrap();
    let denoised = denoiser.denoise(&noisy.linear, &albedo, &normal).unwrap();
    // Outside the light and the pixels its edge covers in part (as scripts/reference/equal_error_mitsuba.py
    // measures): the lamp is 25 times brighter than the walls, and its edge's coverage is not what the
    // denoiser's guides can tell apart from noise.
    let (w, h) = (SIZE as i64, SIZE as i64);
    let lamp: Vec<bool> = reference.linear.pixels.iter().map(|p| luminance(p) > 1.0).collect();
    let near_lamp = |i: usize| {
        let (x, y) = (i as i64 % w, i as i64 / w);
        (-2..=2).any(|dy| {
            (-2..=2).any(|dx| {
                let (u, v) = (x + dx, y + dy);
                (0..w).contains(&u) && (0..h).contains(&v) && lamp[(v * w + u) as usize]
            })
        })
    };
    let mask: Vec<usize> = (0..lamp.len()).filter(|&i| !near_lamp(i)).collect();
    let rmse = |f: &strata::output::Frame| {
        let sq = mask.iter().map(|&i| (luminance(&f.pixels[i]) - luminance(&reference.linear.pixels[i])).powi(2));
        (sq.sum::<f64>() / mask.len() as f64).sqrt()
    };
    let mean =
        |f: &strata::output::Frame| mask.iter().map(|&i| luminance(&f.pixels[i])).sum::<f64>() / mask.len() as f64;
    let (noisy_error, denoised_error) = (rmse(&noisy.linear), rmse(&denoised));
    let drift = (mean(&denoised) - mean(&reference.linear)).abs() / mean(&reference.linear);
    eprintln!(
        "RMSE against 1,024 paths: noisy {noisy_error:.5}, denoised {denoised_error:.5}; mean off by {:.2}%",
        100.0 * drift
    );
    assert!(denoised_error <= noisy_error / 3.0, "denoised {denoised_error} is not a third of noisy {noisy_error}");
    assert!(drift < 0.02, "the denoised mean is {:.2}% off the reference's", 100.0 * drift);

    // The host's display image (what -o gets for a denoised frame) is the resolve pass's, to rounding.
    let display = strata::output::display_rgba8(&noisy.linear, noisy.exposure, true, false);
    let worst = display.iter().zip(&noisy.display).map(|(a, b)| a.abs_diff(*b)).max().unwrap();
    assert!(worst <= 1, "the host's tone map is {worst}/255 off the resolve pass's");
    drop(on_gpu);
    gpu.finish().unwrap();
}

#[test]
fn denoise_without_the_library_is_a_clear_error_that_writes_nothing() {
    let dir = temp_dir("no-denoiser");
    let out = dir.join("cornell.png");
    let scene = repo_file("scenes/cornell.toml");
    let run = common::cli::command(&[
        "render".as_ref(),
        scene.as_os_str(),
        "--size".as_ref(),
        "32x32".as_ref(),
        "--spp".as_ref(),
        "1".as_ref(),
        "--denoise".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ])
    .env("STRATA_OIDN_LIBRARY", dir.join("missing/libOpenImageDenoise.so.2"))
    .output()
    .unwrap();
    assert!(!run.status.success() && !out.exists(), "{}", outcome(&run));
    assert!(outcome(&run).contains("scripts/setup.sh --denoiser"), "{}", outcome(&run));
    // --denoise is for whole frames.
    let part = strata(&[
        "render",
        scene.to_str().unwrap(),
        "--samples",
        "0..1",
        "--denoise",
        "-o",
        dir.join("p.exr").to_str().unwrap(),
    ]);
    assert!(!part.status.success() && outcome(&part).contains("whole frames"), "{}", outcome(&part));
}
