//! `strata bench`: pass times from GPU timestamps and the frame benchmark's figures (docs/performance.md).
use super::args::BenchArgs;
use anyhow::{anyhow, Result};
use strata::vk::{Gpu, GpuOptions};

pub fn bench(args: BenchArgs) -> Result<()> {
    // Each benchmark on its own device; the device goes before its validation log is read, so teardown messages
    // count too.
    let run = |benchmark: fn(&BenchArgs, Gpu) -> Result<()>| -> Result<()> {
        let gpu = Gpu::new(&GpuOptions {
            validation: args.validate,
            echo_messages: args.validate,
            device: args.device.clone(),
            ..Default::default()
        })?;
        let log = gpu.validation_log();
        benchmark(&args, gpu)?;
        if args.validate {
            log.check().map_err(|report| anyhow!("{report}"))?;
        }
        Ok(())
    };
    if args.only == "all" || args.only == "gbuffer" {
        run(bench_gbuffer)?;
    }
    if args.only == "all" || args.only == "frame" {
        if args.only == "all" {
            println!();
        }
        run(bench_frame)?;
    }
    if args.only == "all" || args.only == "scale-out" {
        if args.only == "all" {
            println!();
        }
        run(bench_scale_out)?;
    }
    if args.only == "all" || args.only == "deform" {
        if args.only == "all" {
            println!();
        }
        run(bench_deform)?;
    }
    Ok(())
}

/// What deformed meshes cost per sample (docs/architecture.md, "Deformed meshes"): a skinned tube of 4,096
/// triangles bending and MorphStressTest's animated weights (2,412 triangles), each against its own geometry frozen
/// at the shutter's opening (the same triangles, nothing deformed), in one run: the host's work per sample (joint
/// matrices, morphs) beside its twin of the whole deformation, the GPU's time per sample before the G-buffer (the
/// skinning pass, the deformed BLAS rebuilds and the TLAS), and the whole frame.
fn bench_deform(args: &BenchArgs, gpu: Gpu) -> Result<()> {
    use strata::bench::time_frame_with;
    use strata::scene::fixtures::{frozen_at, skinned_tube};
    let (w, h) = (args.size.0.min(256), args.size.1.min(256));
    println!("Deformed meshes at {w}x{h}, {} spp, shutter 0 to 0.5 s, on {}", args.spp, gpu.device.report.name);
    let mut morphing = strata::load_scene(&args.morph)?;
    if let Some(clip) = morphing.animations.first() {
        morphing.shutter = (0.0, 0.5f32.min(clip.duration()));
    }
    let mut tube = skinned_tube(64, 32);
    tube.shutter = (0.0, 0.5);
    for (name, scene) in
        [("skinned tube (4,096 triangles)", &mut tube), (&*args.morph.to_string_lossy(), &mut morphing)]
    {
        if !scene.has_light() {
            scene.add_default_light();
        }
        scene.camera = Some(scene.camera_or_default());
        let frozen = frozen_at(scene, scene.shutter.0);
        // The host's share per sample, as `DeformedStreams::write_slot` does it: a skinned instance's joint
        // matrices (and its morph where the clip animates its weights), a morphing one's morph; and, for
        // comparison, the host twin of the whole deformation (what the host did per sample before the skinning
        // pass).
        let deformed = scene.deformed_instances();
        let time_of =
            |k: u32| scene.shutter.0 + (scene.shutter.1 - scene.shutter.0) * (k as f32 + 0.5) / args.spp as f32;
        let per_sample_ms = |work: &dyn Fn(f32, &[glam::Mat4], usize)| {
            let started = std::time::Instant::now();
            for k in 0..args.spp {
                let t = time_of(k);
                let node_world = scene.node_world_transforms(Some(t));
                deformed.iter().for_each(|&i| work(t, &node_world, i));
            }
            started.elapsed().as_secs_f64() * 1e3 / f64::from(args.spp)
        };
        let host_ms = per_sample_ms(&|t, node_world, i| match scene.instance_skin(i) {
            Some(skin) => {
                std::hint::black_box(skin.joint_matrices(node_world));
                if scene.has_animated_weights(i) {
                    std::hint::black_box(scene.morph_instance(i, Some(t)));
                }
            }
            None => {
                std::hint::black_box(scene.morph_instance(i, Some(t)));
            }
        });
        let twin_ms = per_sample_ms(&|t, node_world, i| {
            std::hint::black_box(scene.deform_instance(i, node_world, Some(t)));
        });
        let settings = strata::scene::settings::RenderSettings {
            width: w,
            height: h,
            spp: args.spp,
            sampler: strata::scene::settings::SamplerKind::Jittered,
            ..Default::default()
        };
        // Neither timed frame pays for compiling the pipelines: `time_frame_with` readies them first.
        let moving = time_frame_with(&gpu, scene, &settings, false)?.stats;
        let still = time_frame_with(&gpu, &frozen, &settings, false)?.stats;
        let per_sample = |s: &strata::render::frame::FrameStats| {
            s.pass_times.unwrap_or_default().tlas_ms / f64::from(s.samples.max(1))
        };
        println!("{name}: {} triangles deformed", scene.triangle_count());
        println!(
            "  host per sample {:.1} µs (its twin of the whole deformation: {:.1} µs)",
            host_ms * 1e3,
            twin_ms * 1e3
        );
        println!(
            "  GPU per sample before the G-buffer: {:.3} ms deformed (skinning, BLAS rebuilds, TLAS), {:.3} ms frozen (TLAS)",
            per_sample(&moving),
            per_sample(&still)
        );
        println!(
            "  frame wall time: {:.2} s deformed, {:.2} s frozen ({:.2}x)",
            moving.seconds,
            still.seconds,
            moving.seconds / still.seconds
        );
    }
    Ok(())
}

/// What scale-out costs besides rendering: a checkpoint (reading the sums back and writing the part), and
/// merging N parts (reading, adding, resolving, writing the PNG), at the frame benchmark's size, against the
/// wall time of the frame itself (docs/scale-out.md).
fn bench_scale_out(args: &BenchArgs, gpu: Gpu) -> Result<()> {
    use std::time::Instant;
    use strata::partial::file::{write_part, Part, PartLook};
    use strata::render::frame::{render_samples, Continuation, FrameOptions};
    let (w, h) = args.size;
    let mut scene = strata::load_scene(&args.showcase)?;
    if !scene.has_light() {
        scene.add_default_light();
    }
    let settings = strata::scene::settings::RenderSettings { width: w, height: h, spp: args.spp, ..Default::default() };
    println!("Scale-out at {w}x{h}, {} spp, {} on {}", args.spp, args.showcase.display(), gpu.device.report.name);
    let on_gpu = strata::render::SceneOnGpu::upload(&gpu.device, &scene)?;
    let options = FrameOptions { keep_sums: true, ..Default::default() };
    let started = Instant::now();
    let frame =
        render_samples(&gpu.device, &scene, &on_gpu, &settings, &options, Continuation::default(), &mut |_, _| true)?;
    let frame_s = started.elapsed().as_secs_f64();
    let sums = frame.sums.ok_or_else(|| anyhow!("the render kept no sums"))?;
    let t = Instant::now();
    let provenance = strata::part_provenance(&gpu, &scene, &settings)?;
    let fingerprint_ms = t.elapsed().as_secs_f64() * 1e3;
    // The fingerprint hashes the scene's whole content: what it costs a large mesh, once per part.
    let mut big = strata::scene::Scene::default();
    big.meshes.push(strata::scene::Mesh {
        name: "1M sphere".into(),
        primitives: vec![strata::scene::shapes::uv_sphere(1.0, 1000, 500, Some(0))],
    });
    let t = Instant::now();
    strata::part_provenance(&gpu, &big, &settings)?;
    println!(
        "  fingerprint of the scene (once per part): {fingerprint_ms:.1} ms; a 1M-triangle mesh {:.0} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    let look = PartLook { exposure: 0.0, tone_map: settings.tone_map, transparent: false, auto_exposure: false };
    let dir = std::env::temp_dir().join(format!("strata-bench-scale-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let result = (|| -> Result<()> {
        // A checkpoint: the sums back from the device, then the part written (atomically, compressed).
        let buffer = strata::vk::Buffer::with_data(
            &gpu.device,
            "bench sums",
            &sums.counts,
            ash::vk::BufferUsageFlags::TRANSFER_SRC,
            16,
        )?;
        let mut read_ms = Vec::new();
        let mut write_ms = Vec::new();
        let part_path = dir.join("checkpoint.exr");
        for _ in 0..args.samples {
            let t = Instant::now();
            let back: Vec<u64> =
                strata::vk::readback::read_buffer(&gpu.device, &buffer, strata::vk::commands::Access::NONE)?;
            read_ms.push(t.elapsed().as_secs_f64() * 1e3);
            let part = Part {
                provenance: provenance.clone(),
                look,
                sums: strata::partial::PartialSums {
                    width: sums.width,
                    height: sums.height,
                    spp: sums.spp,
                    samples: sums.samples.clone(),
                    counts: back,
                },
            };
            let t = Instant::now();
            write_part(&part_path, &part)?;
            write_ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let (read, write) = (strata::bench::median(read_ms), strata::bench::median(write_ms));
        let bytes = std::fs::metadata(&part_path)?.len();
        println!(
            "  checkpoint: read back {read:.1} ms + write {write:.1} ms ({:.1} MiB, {:.1} B/px) = {:.1}% of the frame's \
             {frame_s:.2} s; every 60 s it costs {:.2}% of a render",
            bytes as f64 / 1048576.0,
            bytes as f64 / (f64::from(w) * f64::from(h)),
            100.0 * (read + write) / 1e3 / frame_s,
            100.0 * (read + write) / 1e3 / 60.0
        );
        // Merges of N parts (the same sums under N disjoint sample ranges: merging does not look at values). A part
        // holds at least one sample (an empty one is refused), so at most --spp parts.
        for n in [2u32, 4, 8, 16] {
            if n > args.spp {
                println!(
                    "  merge of {n:>2} parts: skipped (--spp {} splits into at most {} parts)",
                    args.spp, args.spp
                );
                continue;
            }
            let paths: Vec<std::path::PathBuf> = (0..n)
                .map(|k| {
                    let path = dir.join(format!("part-{k}.exr"));
                    let samples = strata::partial::SampleSet::range(args.spp * k / n, args.spp * (k + 1) / n);
                    let part = Part {
                        provenance: provenance.clone(),
                        look,
                        sums: strata::partial::PartialSums { samples, ..sums.clone() },
                    };
                    write_part(&path, &part).map(|_| path)
                })
                .collect::<Result<_>>()?;
            let t = Instant::now();
            let merged = strata::partial::merge::merge_parts(&paths, true)?;
            let read_add = t.elapsed().as_secs_f64() * 1e3;
            let t = Instant::now();
            let look =
                strata::render::resolve::DisplayLook { exposure: 0.0, tone_map: settings.tone_map, transparent: false };
            let resolved = strata::render::resolve::resolve_sums(&gpu.device, &merged.sums, look, false)?;
            strata::output::write_png_rgba8(&dir.join("merged.png"), w, h, &resolved.display)?;
            let resolve_write = t.elapsed().as_secs_f64() * 1e3;
            println!(
                "  merge of {n:>2} parts: read + add {read_add:.0} ms ({:.1} ms per part), resolve + write PNG {resolve_write:.0} ms",
                read_add / f64::from(n)
            );
        }
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn bench_frame(args: &BenchArgs, gpu: Gpu) -> Result<()> {
    use strata::bench::time_pipeline_creation;
    use strata::render::accumulate::TracePath;
    use strata::scene::settings::Trace;
    let (w, h) = args.size;
    println!(
        "Frames of distributed ray tracing at {w}x{h}, {} spp (jittered), on {}",
        args.spp, gpu.device.report.name
    );
    // Every way the device can trace, the one auto takes first; the bare probe needs ray queries.
    let paths = TracePath::available(&gpu.device);
    let auto = TracePath::choose(Trace::Auto, &gpu.device)?;
    let creation: Vec<String> = paths
        .iter()
        .map(|p| Ok(format!("{} {:.0} ms", p.name(), time_pipeline_creation(&gpu, *p)?)))
        .collect::<Result<_>>()?;
    println!("accumulate pipeline creation (alpha-tested variant, wall clock): {}", creation.join(", "));
    for path in [&args.scene, &args.showcase] {
        bench_scene_frames(args, &gpu, path, &paths, auto)?;
    }
    bench_scaling(args, &gpu)
}

/// One scene's frames: the raster and reference modes by the way `auto` traces (with the bare probe's figures
/// where there are ray queries), and by every other way the device traces.
fn bench_scene_frames(
    args: &BenchArgs,
    gpu: &Gpu,
    path: &std::path::Path,
    paths: &[strata::render::accumulate::TracePath],
    auto: strata::render::accumulate::TracePath,
) -> Result<()> {
    use strata::bench::{time_frame, time_frame_with};
    use strata::render::accumulate::TracePath;
    use strata::scene::settings::Primary;
    let (w, h) = args.size;
    let mut scene = strata::load_scene(path)?;
    if !scene.has_light() {
        scene.add_default_light();
    }
    eprint!("\r{} ...", path.display());
    let probe = auto == TracePath::Query;
    let f = time_frame(gpu, &scene, (w, h), args.spp, Primary::Raster, auto.as_trace(), probe)?;
    let traced = time_frame(gpu, &scene, (w, h), args.spp, Primary::Rays, auto.as_trace(), false)?;
    // The other ways to trace, both primary modes, for the side-by-side line.
    let mut by_path = Vec::new();
    for other in paths {
        let (raster, rays) = if *other == auto {
            (f.stats.clone(), traced.stats.clone())
        } else {
            let t = other.as_trace();
            let raster = time_frame(gpu, &scene, (w, h), args.spp, Primary::Raster, t, false)?.stats;
            (raster, time_frame(gpu, &scene, (w, h), args.spp, Primary::Rays, t, false)?.stats)
        };
        by_path.push((*other, raster, rays));
    }
    let paths = time_frame_with(gpu, &scene, &shading_samples_settings(args, auto), false)?;
    eprint!("\r\x1b[2K");
    println!("{}:", path.display());
    print_frame_figures(gpu, args.size, &f, &traced, probe);
    print_paths_side_by_side(&by_path);
    print_shading_samples(args.spp, &f.stats, &paths.stats);
    Ok(())
}

/// Paths per camera sample in the shading-samples comparison: the same paths per pixel in a quarter of the
/// camera samples.
const BENCH_SHADING_SAMPLES: u32 = 4;

/// The raster frame again with `BENCH_SHADING_SAMPLES` paths per camera sample and as many paths per pixel.
fn shading_samples_settings(
    args: &BenchArgs,
    auto: strata::render::accumulate::TracePath,
) -> strata::scene::settings::RenderSettings {
    strata::scene::settings::RenderSettings {
        width: args.size.0,
        height: args.size.1,
        spp: (args.spp / BENCH_SHADING_SAMPLES).max(1),
        shading_samples: BENCH_SHADING_SAMPLES,
        sampler: strata::scene::settings::SamplerKind::Jittered,
        trace: auto.as_trace(),
        ..Default::default()
    }
}

/// One camera sample per path against `BENCH_SHADING_SAMPLES` paths per camera sample, the same paths per pixel.
fn print_shading_samples(
    spp: u32,
    one: &strata::render::frame::FrameStats,
    several: &strata::render::frame::FrameStats,
) {
    let (a, b) = (one.pass_times.unwrap_or_default(), several.pass_times.unwrap_or_default());
    let share = |t: &strata::render::frame::PassTimes| 100.0 * (t.tlas_ms + t.gbuffer_ms) / t.total_ms();
    println!(
        "  --shading-samples {k}: {} x {k} paths in {:.0} GPU ms ({:.2} s wall), against {spp} x 1 in {:.0} ms \
         ({:.2} s): {:.2}x; TLAS + G-buffer {:.1}% of the frame (target < 20%), {:.1}% with one path a sample",
        several.samples,
        b.total_ms(),
        several.seconds,
        a.total_ms(),
        one.seconds,
        a.total_ms() / b.total_ms(),
        share(&b),
        share(&a),
        k = BENCH_SHADING_SAMPLES,
    );
}

/// The raster frame's pass times, rays, probe ratios and memory, and the reference mode's beside it.
fn print_frame_figures(
    gpu: &Gpu,
    (w, h): (u32, u32),
    f: &strata::bench::FrameFigure,
    traced: &strata::bench::FrameFigure,
    probe: bool,
) {
    let pixels = f64::from(w) * f64::from(h);
    let s = &f.stats;
    let t = s.pass_times.unwrap_or_default();
    let n = f64::from(s.samples);
    let total = t.total_ms();
    let rays = (s.shadow_rays + s.secondary_rays) as f64;
    let accumulate_rays_per_s = rays / (t.accumulate_ms / 1e3);
    let probe_rays_per_s = f.probe_rays as f64 / (f.probe_ms / 1e3);
    let frame_bytes = s.device_bytes.saturating_sub(f.scene_bytes);
    println!(
        "  GPU ms per sample: TLAS {:.2}, G-buffer {:.2}, accumulate {:.2}; resolve {:.2} per frame",
        t.tlas_ms / n,
        t.gbuffer_ms / n,
        t.accumulate_ms / n,
        t.resolve_ms
    );
    println!(
        "  {:.2} samples/s (GPU time), {:.2} s wall; TLAS + G-buffer = {:.1}% of the frame (target < 20%)",
        n / (total / 1e3),
        s.seconds,
        100.0 * (t.tlas_ms + t.gbuffer_ms) / total
    );
    println!(
        "  rays per sample {:.0} shadow + {:.0} secondary; {:.2} M shadow rays/s, {:.2} M secondary rays/s",
        s.shadow_rays as f64 / n,
        s.secondary_rays as f64 / n,
        s.shadow_rays as f64 / (t.accumulate_ms / 1e3) / 1e6,
        s.secondary_rays as f64 / (t.accumulate_ms / 1e3) / 1e6
    );
    if probe {
        println!(
            "  accumulate {:.2} M rays/s vs bare ray-query probe {:.2} M rays/s ({} camera rays, closest hit, \
             cast between the frame's batches): {:.1}% (target >= 60%)",
            accumulate_rays_per_s / 1e6,
            probe_rays_per_s / 1e6,
            f.probe_rays,
            100.0 * accumulate_rays_per_s / probe_rays_per_s
        );
        let replay_rays_per_s = f.replay_rays as f64 / (f.replay_ms / 1e3);
        println!(
            "  accumulate vs the probe replaying one sample's own rays ({} shadow rays, first hit; {} closest \
             hit), no shading: {:.2} M rays/s, {:.1}%",
            f.replay_shadow_rays,
            f.replay_rays - f.replay_shadow_rays,
            replay_rays_per_s / 1e6,
            100.0 * accumulate_rays_per_s / replay_rays_per_s
        );
    } else {
        println!("  (no bare ray-query probe: {} has no ray queries)", gpu.device.report.name);
    }
    let traced_times = traced.stats.pass_times.unwrap_or_default();
    println!(
        "  reference mode (--primary rays): accumulate {:.2} ms per sample with its camera rays, frame {:.2}x the \
         raster frame's GPU time, {:.1} bytes/pixel",
        traced_times.accumulate_ms / n,
        traced_times.total_ms() / total,
        traced.stats.device_bytes.saturating_sub(traced.scene_bytes) as f64 / pixels
    );
    println!(
        "  device memory: scene {:.2} MiB, frame {:.2} MiB = {:.1} bytes/pixel (images alone {:.1}, 32 of them the \
         fixed-point sums; target <= 100 with them, docs/performance.md)",
        f.scene_bytes as f64 / 1048576.0,
        frame_bytes as f64 / 1048576.0,
        frame_bytes as f64 / pixels,
        s.image_bytes as f64 / pixels
    );
}

/// Scaling: total GPU time against spp at a fixed size, and against pixels at a fixed spp.
fn bench_scaling(args: &BenchArgs, gpu: &Gpu) -> Result<()> {
    use strata::bench::{fitted_exponent, time_frame};
    use strata::scene::settings::{Primary, Trace};
    let (w, h) = args.size;
    let mut scene = strata::load_scene(&args.scene)?;
    if !scene.has_light() {
        scene.add_default_light();
    }
    // At the default 512x512: spp over 8-32 at 256x256, pixels over 128^2-512^2 at 8 spp.
    let part = |divisor: u32| ((w / divisor).max(1), (h / divisor).max(1));
    let (quarter, half) = (part(4), part(2));
    let mut by_spp = Vec::new();
    for spp in [8u32, 16, 32] {
        eprint!("\rscaling: {spp} spp ...");
        let f = time_frame(gpu, &scene, half, spp, Primary::Raster, Trace::Auto, false)?;
        by_spp.push((f64::from(spp), f.stats.pass_times.unwrap_or_default().total_ms()));
    }
    let mut by_pixels = Vec::new();
    for size in [quarter, half, (w, h)] {
        eprint!("\rscaling: {}x{} ...", size.0, size.1);
        let f = time_frame(gpu, &scene, size, 8, Primary::Raster, Trace::Auto, false)?;
        by_pixels.push((f64::from(size.0 * size.1), f.stats.pass_times.unwrap_or_default().total_ms()));
    }
    eprint!("\r\x1b[2K");
    println!(
        "scaling ({}): GPU frame time ~ spp^{:.2} (8-32 spp at {}x{}), ~ pixels^{:.2} ({}x{} to {w}x{h} at 8 spp)",
        args.scene.display(),
        fitted_exponent(&by_spp),
        half.0,
        half.1,
        fitted_exponent(&by_pixels),
        quarter.0,
        quarter.1
    );
    Ok(())
}

/// One line per primary mode: each way to trace's accumulate ms per sample and rays/s, and pipeline/query.
fn print_paths_side_by_side(
    by_path: &[(
        strata::render::accumulate::TracePath,
        strata::render::frame::FrameStats,
        strata::render::frame::FrameStats,
    )],
) {
    use strata::render::accumulate::TracePath;
    for (mode, pick) in [("raster", 0usize), ("rays", 1)] {
        let mut parts = Vec::new();
        let mut ms_of = Vec::new();
        for (path, raster, rays) in by_path {
            let s = if pick == 0 { raster } else { rays };
            let t = s.pass_times.unwrap_or_default();
            let ms = t.accumulate_ms / f64::from(s.samples.max(1));
            let rays = (s.camera_rays + s.shadow_rays + s.secondary_rays) as f64 / (t.accumulate_ms / 1e3);
            parts.push(format!("{} {ms:.2} ms/sample, {:.2} M rays/s", path.name(), rays / 1e6));
            ms_of.push((*path, ms));
        }
        let ms = |want: TracePath| ms_of.iter().find(|(p, _)| *p == want).map(|(_, ms)| *ms);
        let ratio = match (ms(TracePath::Pipeline), ms(TracePath::Query)) {
            (Some(p), Some(q)) => format!("; pipeline/query {:.2}x (target <= 1.25x)", p / q),
            _ => String::new(),
        };
        println!("  ways to trace, --primary {mode}: {}{ratio}", parts.join(" | "));
    }
}

fn bench_gbuffer(args: &BenchArgs, gpu: Gpu) -> Result<()> {
    use strata::bench::{time_gbuffer, BumpSetting};
    use strata::scene::BumpDerivative::{Analytic, CentralDifferences};
    let cornell = strata::load_scene(&args.scene)?;
    // About a million triangles: a UV sphere of 1000 x 500 quads with an fBm bump, framed by the default camera.
    let mut big = strata::scene::Scene::default();
    let mut sphere = strata::scene::shapes::uv_sphere(1.0, 1000, 500, Some(0));
    strata::scene::surface::compute_surface_derivatives(&mut sphere);
    big.meshes.push(strata::scene::Mesh { name: "1M sphere".into(), primitives: vec![sphere] });
    big.materials.push(strata::scene::Material {
        name: "fbm".into(),
        bump: Some(strata::scene::BumpMap::default()),
        ..Default::default()
    });
    big.instances.push(strata::scene::Instance {
        name: "1M sphere".into(),
        mesh: 0,
        node: None,
        world_from_object: glam::Mat4::IDENTITY,
        node_from_object: glam::Mat4::IDENTITY,
    });
    println!("G-buffer pass, GPU time per sample (median of {} samples) on {}", args.samples, gpu.device.report.name);
    println!("{:<12} {:>10} {:>10} {:<22} {:>10}", "scene", "size", "triangles", "bump", "ms/sample");
    let cases = [
        ("cornell", &cornell, 512, 512, BumpSetting::AsGiven),
        ("cornell", &cornell, 1280, 720, BumpSetting::AsGiven),
        ("1M sphere", &big, 512, 512, BumpSetting::AsGiven),
        ("1M sphere", &big, 1280, 720, BumpSetting::AsGiven),
        ("cornell", &cornell, 512, 512, BumpSetting::Off),
        ("cornell", &cornell, 512, 512, BumpSetting::All(CentralDifferences)),
        ("cornell", &cornell, 512, 512, BumpSetting::All(Analytic)),
    ];
    let mut figures = Vec::new();
    for (i, (name, scene, w, h, bump)) in cases.into_iter().enumerate() {
        eprint!("\r[{}/{}] {name} {w}x{h} ...", i + 1, cases.len());
        let f = time_gbuffer(&gpu, name, scene, w, h, bump, args.samples)?;
        eprint!("\r\x1b[2K");
        println!("{:<12} {:>10} {:>10} {:<22} {:>10.3}", f.scene, format!("{w}x{h}"), f.triangles, f.bump, f.median_ms);
        figures.push(f);
    }
    let (none, central, analytic) = (figures[4].median_ms, figures[5].median_ms, figures[6].median_ms);
    println!();
    println!("bump cost at 512x512, every material bumped (fBm, 4 octaves):");
    println!("  central differences / analytic gradient = {:.2}x", central / analytic);
    println!("  central differences / no bump           = {:.2}x", central / none);
    println!("  analytic gradient / no bump             = {:.2}x", analytic / none);
    println!(
        "  bump work alone (pass minus the no-bump pass): central / analytic = {:.2}x ({:.2} vs {:.2} ms)",
        (central - none) / (analytic - none).max(1e-9),
        central - none,
        analytic - none
    );
    Ok(())
}
