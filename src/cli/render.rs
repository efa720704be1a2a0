//! `strata render`: load, render, write atomically, summarize.
use super::args::RenderArgs;
use super::print_stdout;
use super::progress::ProgressBar;
use super::summary::Summary;
use anyhow::{anyhow, bail, Context as _, Result};
use strata::vk::{Gpu, GpuOptions};

/// Set by Ctrl-C: the sample loop stops after the batch in flight; a second Ctrl-C exits at once (nothing has
/// been written either way: outputs are written atomically at the end).
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn install_interrupt_handler() {
    use std::sync::atomic::Ordering;
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            eprintln!("\nstrata: interrupted again; exiting without writing anything");
            std::process::exit(130);
        }
    });
}

pub fn render(args: RenderArgs) -> Result<()> {
    use std::io::IsTerminal as _;
    use std::sync::atomic::Ordering;
    install_interrupt_handler();
    let options = strata::LoadOptions { allow_any_uri: args.allow_any_uri.then_some(true) };
    let loaded = strata::load(&args.scene, &options)?;
    for warning in &loaded.scene.warnings {
        eprintln!("warning: {}: {warning}", args.scene.display());
    }
    let cli = strata::scene::settings::SettingsOverrides {
        width: args.size.map(|s| s.0),
        height: args.size.map(|s| s.1),
        spp: args.spp,
        sampler: args.sampler,
        seed: args.seed,
        background: args.background.map(glam::Vec3::from_array),
        exposure: args.exposure,
        tone_map: args.tone_map,
        primary: args.primary,
        indirect: if args.indirect { Some(true) } else { args.no_indirect.then_some(false) },
        bounces: args.bounces,
        trace: args.trace,
        output: args.output.clone(),
    };
    if let Some(ev) = args.exposure {
        if !ev.is_finite() || ev.abs() > 64.0 {
            bail!("--exposure {ev}: give a number of stops between -64 and 64");
        }
    }
    // Defaults, then the scene file, then the command line.
    let settings = strata::scene::settings::RenderSettings::default().with(&loaded.settings).with(&cli);
    let output = settings
        .output
        .clone()
        .ok_or_else(|| anyhow!("no output file: pass -o FILE (or set output in the scene file's [render] table)"))?;
    // Check the output names before any work, so a typo costs nothing.
    strata::output::OutputFormat::from_path(&output)?;
    strata::output::check_output_directory(&output)?;
    if let Some(exr) = &args.exr {
        if strata::output::OutputFormat::from_path(exr)? != strata::output::OutputFormat::Exr {
            bail!("--exr {}: the file name must end in .exr", exr.display());
        }
        strata::output::check_output_directory(exr)?;
    }
    let mut scene = loaded.scene;
    if !args.preview && !scene.has_light() {
        scene.add_default_light();
        eprintln!(
            "warning: {}: the scene has no lights or emissive surfaces; lighting it with a default key light \
             (add [[light]] tables in a scene file, see docs/scene-format.md)",
            args.scene.display()
        );
    }
    strata::scene::settings::CameraOverrides {
        aperture_radius: args.aperture,
        focus_distance: args.focus,
        shutter: args.shutter,
    }
    .apply(&mut scene)
    .with_context(|| format!("{}: applying the command line's camera options", args.scene.display()))?;
    let started = std::time::Instant::now();
    let gpu = Gpu::new(&GpuOptions {
        validation: args.gpu.validate,
        echo_messages: args.gpu.validate,
        device: args.gpu.device.clone(),
        needs: strata::render::accumulate::TracePath::device_needs(settings.trace),
    })?;
    let log = gpu.validation_log();
    // Geometry and textures go up once for every pass of this render.
    let on_gpu = strata::render::SceneOnGpu::upload(&gpu.device, &scene)?;
    let show_progress = !args.quiet && std::io::stderr().is_terminal();
    let mut bar = ProgressBar::new(show_progress);
    let picture = if args.preview {
        let preview = strata::render::PreviewSettings {
            width: settings.width,
            height: settings.height,
            background: settings.background.to_array(),
        };
        Picture::Preview(strata::render_preview(&gpu, &scene, &on_gpu, &preview)?)
    } else {
        let mut progress = |done: u32, total: u32| {
            bar.update(done, total);
            !INTERRUPTED.load(Ordering::SeqCst)
        };
        let frame_options = strata::render::frame::FrameOptions::default();
        let rendered = strata::render(&gpu, &scene, &on_gpu, &settings, &frame_options, &mut progress);
        bar.finish();
        Picture::Rendered(rendered?)
    };
    let aovs = match &args.aov {
        Some(list) => strata::render_aovs(&gpu, &scene, &on_gpu, settings.width, settings.height, &list.0)?,
        None => Vec::new(),
    };
    let device_name = gpu.device.report.name.clone();
    // Everything holding the device goes first, so its teardown messages arrive before the check.
    drop(on_gpu);
    drop(gpu);
    if args.gpu.validate {
        // Teardown messages (leaks) arrive when the device goes; check after it is gone, before writing.
        log.check().map_err(|report| anyhow!("{report}"))?;
    }
    write_outputs(&output, &picture, &aovs)?;
    if let Some(exr) = &args.exr {
        let layers: Vec<(&str, &strata::output::Frame)> = aovs.iter().map(|(aov, f)| (aov.name(), f)).collect();
        strata::output::write_frame_with_layers(exr, picture.linear(), &layers)?;
    }
    let seconds = started.elapsed().as_secs_f64();
    let mut written = vec![output.display().to_string()];
    written.extend(args.exr.iter().map(|p| p.display().to_string()));
    let summary = Summary {
        written,
        width: settings.width,
        height: settings.height,
        spp: if args.preview { 1 } else { settings.spp },
        sampler: if args.preview { "preview" } else { settings.sampler.name() },
        primary: if args.preview { "raster" } else { settings.primary.name() },
        trace: match &picture {
            Picture::Rendered(r) => r.stats.trace.name(),
            Picture::Preview(_) => "no",
        },
        indirect: settings.indirect && !args.preview,
        bounces: if args.preview { 0 } else { settings.bounces },
        seed: settings.seed,
        seconds,
        stats: match &picture {
            Picture::Rendered(r) => Some(r.stats.clone()),
            Picture::Preview(_) => None,
        },
        device: device_name,
        triangles: scene.triangle_count(),
        instances: scene.instances.len(),
    };
    if args.json {
        print_stdout(&format!("{}\n", summary.json()));
    }
    if !args.quiet {
        eprintln!("{}", summary.line());
    }
    Ok(())
}

/// What a render produced: the distributed-ray-traced frame, or the raster preview.
enum Picture {
    Rendered(strata::render::frame::RenderedFrame),
    Preview(strata::output::Frame),
}

impl Picture {
    fn linear(&self) -> &strata::output::Frame {
        match self {
            Picture::Rendered(r) => &r.linear,
            Picture::Preview(f) => f,
        }
    }
}

/// The beauty image, then the AOVs: layers of an EXR, or PNGs beside a PNG.
fn write_outputs(
    output: &std::path::Path,
    picture: &Picture,
    aovs: &[(strata::render::aov::Aov, strata::output::Frame)],
) -> Result<()> {
    use strata::output::{write_data_png, write_frame, write_frame_with_layers, write_png_rgba8, OutputFormat};
    if OutputFormat::from_path(output)? == OutputFormat::Exr {
        let layers: Vec<(&str, &strata::output::Frame)> = aovs.iter().map(|(aov, f)| (aov.name(), f)).collect();
        return write_frame_with_layers(output, picture.linear(), &layers);
    }
    match picture {
        Picture::Rendered(r) => write_png_rgba8(output, r.linear.width, r.linear.height, &r.display)?,
        Picture::Preview(frame) => write_frame(output, frame)?,
    }
    let stem = output.file_stem().and_then(|s| s.to_str()).unwrap_or("frame");
    for (aov, raw) in aovs {
        let path = output.with_file_name(format!("{stem}.{}.png", aov.name()));
        if aov.is_color() {
            write_frame(&path, raw)?;
        } else {
            write_data_png(&path, &aov.for_display(raw))?;
        }
        eprintln!("strata: wrote {}", path.display());
    }
    Ok(())
}
