//! The `strata` command line.
use anyhow::{anyhow, bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use strata::vk::{Gpu, GpuOptions};

#[derive(Parser)]
#[command(
    name = "strata",
    version,
    about = "A headless Vulkan renderer: distributed ray tracing with ray queries, validated on lavapipe",
    long_about = "strata renders glTF 2.0 scenes without a window through raw Vulkan and writes PNG or OpenEXR.\n\
                  It needs a Vulkan 1.3 device with VK_KHR_ray_query: on a machine without a GPU, run\n\
                  scripts/setup.sh to install Mesa's lavapipe. `strata info` shows what it finds.",
    after_help = "Examples:\n  strata info\n  strata render scenes/showcase.toml -o showcase.png\n  \
                  strata render model.glb -o frame.exr --size 1920x1080 --validate"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene with distributed ray tracing (depth of field, motion blur, soft shadows, gloss,
    /// translucency) to a PNG (8-bit sRGB, tone-mapped) or OpenEXR (32-bit float linear radiance) file.
    #[command(after_help = "Each of the --spp samples rasterizes a G-buffer at its own lens point, shutter time and \
                            sub-pixel jitter, then a compute pass casts shadow, gloss and translucency rays with \
                            ray queries. The output format follows the extension of -o (.png or .exr); files are \
                            written atomically, so a failed or interrupted render (Ctrl-C) leaves nothing behind.\n\n\
                            Examples:\n  strata render scenes/showcase.toml -o showcase.png\n  \
                            strata render scenes/dof.toml -o dof.png --spp 64 --aperture 0.05 --focus 3\n  \
                            strata render scenes/motion.toml -o motion.exr --shutter 0:0.5 --sampler multi-jittered\n  \
                            strata render Box.gltf -o box.png --size 512x512 --json --quiet --validate")]
    Render(RenderArgs),
    /// List every Vulkan device with its driver, API version and ray-query support, and whether the
    /// Khronos validation layer is installed.
    Info(InfoArgs),
    /// Measure pass times with GPU timestamps and print figures (no pass/fail): the G-buffer pass per sample for
    /// the Cornell box and a 1M-triangle mesh at 512x512 and 1280x720, the cost of bump-mapping derivatives; and
    /// whole frames (per-pass times; rays/s against bare ray-query probes: camera rays, and a replay of the very
    /// rays one sample cast; scaling with spp and pixels; memory).
    #[command(after_help = "Figures vary with the machine and its load; compare the ratios printed in one run.\n\n\
                            Examples:\n  strata bench\n  strata bench --samples 9 --scene scenes/cornell.toml\n  \
                            strata bench --only frame --size 64x64 --spp 2 --validate   # is the benchmark sound?")]
    Bench(BenchArgs),
}

#[derive(Args)]
struct BenchArgs {
    /// Samples timed per case (the median is reported), after one warm-up.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    samples: u32,
    /// The scene file of the "cornell" cases.
    #[arg(long, value_name = "FILE", default_value = "scenes/cornell.toml")]
    scene: PathBuf,
    /// The second scene of the frame benchmark.
    #[arg(long, value_name = "FILE", default_value = "scenes/showcase.toml")]
    showcase: PathBuf,
    /// Which benchmark: gbuffer (pass times and bump cost), frame (whole distributed-ray-traced frames, the
    /// ray-query ceiling, scaling and memory), or all.
    #[arg(long, value_name = "WHICH", default_value = "all", value_parser = ["all", "gbuffer", "frame"])]
    only: String,
    /// Samples per pixel of the frame benchmark.
    #[arg(long, value_name = "N", default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=4096))]
    spp: u32,
    /// Image size of the frame benchmark (its scaling runs use a quarter, half and all of it).
    #[arg(long, value_name = "WxH", default_value = "512x512", value_parser = parse_size)]
    size: (u32, u32),
    /// Run under the Khronos validation layer and exit non-zero on any error or warning: a check that the
    /// benchmark itself is sound (the layer slows everything, so the figures mean nothing then).
    #[arg(long)]
    validate: bool,
    /// Use this device: its index in `strata info`, or part of its name.
    #[arg(long, value_name = "NAME|INDEX")]
    device: Option<String>,
}

#[derive(Args)]
struct GpuArgs {
    /// Run under the Khronos validation layer (synchronization validation and best practices on) and print
    /// its messages; exit non-zero if it reports any error or warning.
    #[arg(long)]
    validate: bool,
    /// Use this device: its index in `strata info`, or part of its name (e.g. "llvmpipe").
    #[arg(long, value_name = "NAME|INDEX")]
    device: Option<String>,
}

#[derive(Args)]
struct RenderArgs {
    /// The scene: a glTF 2.0 file (.gltf or .glb), or a scene file (.toml, see docs/scene-format.md) that names
    /// one and adds camera, lights, materials, motion and render settings.
    scene: PathBuf,
    /// Output file, .png (exposed, tone-mapped, 8-bit sRGB) or .exr (linear radiance, 32-bit float)
    /// [default: the scene file's render.output].
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// Also write the linear radiance to this OpenEXR file (with the --aov layers, if any).
    #[arg(long, value_name = "FILE")]
    exr: Option<PathBuf>,
    /// Image size in pixels [default: the scene file's, else 960x540].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// Samples per pixel: each is a G-buffer pass at its own lens point, shutter time and sub-pixel jitter plus
    /// an accumulation pass [default: the scene file's, else 16].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    spp: Option<u32>,
    /// How sample points are placed: regular (strata centres; aliases), random, jittered (one random point in
    /// each of n x n strata, Cook 1984), multi-jittered (Kensler 2013) [default: the scene file's, else jittered].
    #[arg(long, value_name = "NAME", value_parser = parse_sampler)]
    sampler: Option<strata::scene::settings::SamplerKind>,
    /// Seed of every random choice; the same scene, options and seed give the same bits on the same device
    /// [default: the scene file's, else 0].
    #[arg(long, value_name = "S")]
    seed: Option<u64>,
    /// Thin-lens aperture radius in metres; 0 is a pinhole (everything sharp) [default: the scene's camera].
    #[arg(long, value_name = "METRES", value_parser = parse_non_negative, allow_hyphen_values = true)]
    aperture: Option<f32>,
    /// Distance in metres of the plane in focus [default: the scene's camera].
    #[arg(long, value_name = "METRES", value_parser = parse_non_negative, allow_hyphen_values = true)]
    focus: Option<f32>,
    /// Shutter interval in seconds; motion during it blurs. OPEN:CLOSE with equal times is a still frame
    /// [default: the scene file's, else 0:0].
    #[arg(long, value_name = "OPEN:CLOSE", value_parser = parse_shutter)]
    shutter: Option<(f32, f32)>,
    /// Exposure in stops: the PNG's radiance is scaled by 2^EV before tone mapping [default: 0].
    #[arg(long, value_name = "EV", allow_hyphen_values = true)]
    exposure: Option<f32>,
    /// Tone map for the PNG: clamp (none), or filmic (an ACES fit) [default: the scene file's, else filmic].
    #[arg(long, value_name = "NAME", value_parser = parse_tone_map)]
    tone_map: Option<strata::scene::settings::ToneMap>,
    /// Where each sample's visible surface comes from: raster (the G-buffer pass; fast, but each sample's pixel
    /// jitter and lens point are shared by all pixels, so fine regular patterns can show moiré) or rays (a ray
    /// per pixel with its own jitter and lens point: noise instead of moiré, the reference the raster mode is
    /// tested against; the shutter time is still shared per sample) [default: the scene file's, else raster].
    #[arg(long, value_name = "MODE", value_parser = parse_primary)]
    primary: Option<strata::scene::settings::Primary>,
    /// Linear RGB background colour of pixels no surface covers, as R,G,B [default: the scene file's, else
    /// 0.02,0.02,0.025].
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb)]
    background: Option<[f32; 3]>,
    /// Also write G-buffer channels (comma-separated): normal, geometric-normal, albedo, depth, height, position,
    /// emission, material. With an .exr they are layers of the EXR (raw values); with -o x.png each is a PNG
    /// beside it, x.<name>.png (normals as ½+½n, depth and height scaled to their range).
    #[arg(long, value_name = "LIST", value_parser = parse_aovs)]
    aov: Option<AovList>,
    /// Render the fast raster preview (one sample, simple shading, no ray queries) instead.
    #[arg(long)]
    preview: bool,
    /// No progress bar and no summary line (errors and warnings still go to stderr).
    #[arg(short, long)]
    quiet: bool,
    /// Print the summary as one JSON object on stdout (for scripts).
    #[arg(long)]
    json: bool,
    /// Let the glTF read files outside its own directory (absolute paths, ".."). Network URIs are never fetched.
    #[arg(long)]
    allow_any_uri: bool,
    #[command(flatten)]
    gpu: GpuArgs,
}

#[derive(Args)]
struct InfoArgs {
    /// Also print the devices' validation messages (creates an instance with the layer when installed).
    #[arg(long)]
    validate: bool,
}

use strata::scene::settings::MAX_IMAGE_SIDE as MAX_SIDE;
use strata::scene::settings::MAX_SPP;

fn parse_sampler(text: &str) -> Result<strata::scene::settings::SamplerKind, String> {
    strata::scene::settings::SamplerKind::parse(text).map_err(|e| e.to_string())
}

fn parse_primary(text: &str) -> Result<strata::scene::settings::Primary, String> {
    strata::scene::settings::Primary::parse(text).map_err(|e| e.to_string())
}

fn parse_tone_map(text: &str) -> Result<strata::scene::settings::ToneMap, String> {
    strata::scene::settings::ToneMap::parse(text).map_err(|e| e.to_string())
}

fn parse_non_negative(text: &str) -> Result<f32, String> {
    let v: f32 = text.trim().parse().map_err(|_| format!("\"{text}\" is not a number"))?;
    if !v.is_finite() || v < 0.0 {
        return Err(format!("{v} must be a finite number, 0 or more"));
    }
    Ok(v)
}

fn parse_shutter(text: &str) -> Result<(f32, f32), String> {
    let (open, close) = text.split_once(':').ok_or_else(|| format!("\"{text}\" is not OPEN:CLOSE, e.g. 0:0.25"))?;
    let time = |s: &str| -> Result<f32, String> {
        let v: f32 = s.trim().parse().map_err(|_| format!("\"{s}\" is not a time in seconds"))?;
        if !v.is_finite() {
            return Err(format!("{v} is not a finite time"));
        }
        Ok(v)
    };
    let (open, close) = (time(open)?, time(close)?);
    if close < open {
        return Err(format!("the shutter closes ({close}) before it opens ({open})"));
    }
    Ok((open, close))
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| format!("\"{text}\" is not WIDTHxHEIGHT, e.g. 960x540"))?;
    let side = |s: &str| -> Result<u32, String> {
        let v: u32 = s.trim().parse().map_err(|_| format!("\"{s}\" is not a whole number of pixels"))?;
        if v == 0 || v > MAX_SIDE {
            return Err(format!("{v} pixels is outside 1..={MAX_SIDE}"));
        }
        Ok(v)
    };
    Ok((side(w)?, side(h)?))
}

/// The parsed `--aov` list (a newtype: clap reads a bare `Vec` as a multi-value option).
#[derive(Clone)]
struct AovList(Vec<strata::render::aov::Aov>);

fn parse_aovs(text: &str) -> Result<AovList, String> {
    strata::render::aov::Aov::parse_list(text).map(AovList).map_err(|e| e.to_string())
}

fn parse_rgb(text: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("\"{text}\" is not R,G,B (three numbers)"));
    }
    let mut rgb = [0.0; 3];
    for (slot, part) in rgb.iter_mut().zip(parts) {
        let v: f32 = part.trim().parse().map_err(|_| format!("\"{part}\" is not a number"))?;
        if !v.is_finite() || v < 0.0 {
            return Err(format!("{v} is not a finite non-negative radiance"));
        }
        *slot = v;
    }
    Ok(rgb)
}

fn main() -> ExitCode {
    strata::fatal_signals::report_fatal_signals();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render(args),
        Command::Info(args) => info(args),
        Command::Bench(args) => bench(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<strata::render::frame::Interrupted>().is_some() => {
            eprintln!("strata: interrupted; nothing was written");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

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

fn render(args: RenderArgs) -> Result<()> {
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
        ..Default::default()
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

/// The end-of-render summary, as a line for people and JSON for scripts.
struct Summary {
    written: Vec<String>,
    width: u32,
    height: u32,
    spp: u32,
    sampler: &'static str,
    /// Where visible surfaces came from: "raster" or "rays".
    primary: &'static str,
    seed: u64,
    seconds: f64,
    stats: Option<strata::render::frame::FrameStats>,
    device: String,
    triangles: usize,
    instances: usize,
}

impl Summary {
    /// (camera rays, shadow rays, secondary rays).
    fn rays(&self) -> (u64, u64, u64) {
        self.stats.as_ref().map(|s| (s.camera_rays, s.shadow_rays, s.secondary_rays)).unwrap_or((0, 0, 0))
    }

    fn line(&self) -> String {
        let (camera, shadow, secondary) = self.rays();
        let render_seconds = self.stats.as_ref().map(|s| s.seconds).unwrap_or(self.seconds).max(1e-9);
        let camera_part = if camera > 0 { format!("{camera} camera + ") } else { String::new() };
        format!(
            "strata: wrote {} ({}x{}, {} spp {}, {} primary, {} triangles) on {} in {:.2} s: {:.2} samples/s, \
             {:.2} M rays/s ({camera_part}{} shadow + {} secondary rays)",
            self.written.join(" and "),
            self.width,
            self.height,
            self.spp,
            self.sampler,
            self.primary,
            self.triangles,
            self.device,
            self.seconds,
            f64::from(self.spp) / render_seconds,
            (camera + shadow + secondary) as f64 / render_seconds / 1e6,
            shadow,
            secondary
        )
    }

    fn json(&self) -> serde_json::Value {
        let (camera, shadow, secondary) = self.rays();
        let render_seconds = self.stats.as_ref().map(|s| s.seconds).unwrap_or(self.seconds).max(1e-9);
        serde_json::json!({
            "outputs": self.written,
            "width": self.width,
            "height": self.height,
            "spp": self.spp,
            "sampler": self.sampler,
            "primary": self.primary,
            "seed": self.seed,
            "seconds": self.seconds,
            "render_seconds": render_seconds,
            "samples_per_second": f64::from(self.spp) / render_seconds,
            "camera_rays": camera,
            "shadow_rays": shadow,
            "secondary_rays": secondary,
            "rays_per_second": (camera + shadow + secondary) as f64 / render_seconds,
            "device": self.device,
            "triangles": self.triangles,
            "instances": self.instances,
        })
    }
}

/// A one-line progress bar on stderr: samples done of N, elapsed time and the estimate of what is left.
struct ProgressBar {
    enabled: bool,
    started: std::time::Instant,
}

impl ProgressBar {
    fn new(enabled: bool) -> Self {
        let bar = Self { enabled, started: std::time::Instant::now() };
        if enabled {
            eprint!("\r[{}] 0 samples, starting ...", " ".repeat(30));
        }
        bar
    }

    fn update(&mut self, done: u32, total: u32) {
        if !self.enabled || total == 0 {
            return;
        }
        let elapsed = self.started.elapsed().as_secs_f64();
        let fraction = f64::from(done) / f64::from(total);
        let filled = (fraction * 30.0).round() as usize;
        let eta = if done > 0 { elapsed / f64::from(done) * f64::from(total - done) } else { 0.0 };
        eprint!(
            "\r\x1b[2K[{}{}] {done}/{total} samples  {elapsed:.1} s elapsed  ETA {eta:.1} s",
            "=".repeat(filled),
            " ".repeat(30 - filled.min(30))
        );
    }

    fn finish(&mut self) {
        if self.enabled {
            eprint!("\r\x1b[2K");
        }
    }
}

fn bench(args: BenchArgs) -> Result<()> {
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
    if args.only != "frame" {
        run(bench_gbuffer)?;
    }
    if args.only != "gbuffer" {
        if args.only == "all" {
            println!();
        }
        run(bench_frame)?;
    }
    Ok(())
}

fn bench_frame(args: &BenchArgs, gpu: Gpu) -> Result<()> {
    use strata::bench::{fitted_exponent, time_frame};
    use strata::scene::settings::Primary;
    let (w, h) = args.size;
    let pixels = f64::from(w) * f64::from(h);
    println!(
        "Frames of distributed ray tracing at {w}x{h}, {} spp (jittered), on {}",
        args.spp, gpu.device.report.name
    );
    for path in [&args.scene, &args.showcase] {
        let mut scene = strata::load_scene(path)?;
        if !scene.has_light() {
            scene.add_default_light();
        }
        eprint!("\r{} ...", path.display());
        let f = time_frame(&gpu, &scene, (w, h), args.spp, Primary::Raster, true)?;
        let traced = time_frame(&gpu, &scene, (w, h), args.spp, Primary::Rays, false)?;
        eprint!("\r\x1b[2K");
        let s = &f.stats;
        let t = s.pass_times.unwrap_or_default();
        let n = f64::from(s.samples);
        let total = t.total_ms();
        let rays = (s.shadow_rays + s.secondary_rays) as f64;
        let accumulate_rays_per_s = rays / (t.accumulate_ms / 1e3);
        let probe_rays_per_s = f.probe_rays as f64 / (f.probe_ms / 1e3);
        let frame_bytes = s.device_bytes.saturating_sub(f.scene_bytes);
        println!("{}:", path.display());
        println!(
            "  GPU ms per sample: TLAS {:.2}, G-buffer {:.2}, accumulate {:.2}; resolve {:.2} per frame",
            t.tlas_ms / n,
            t.gbuffer_ms / n,
            t.accumulate_ms / n,
            t.resolve_ms
        );
        println!(
            "  {:.2} samples/s (GPU time), {:.2} s wall; TLAS + G-buffer = {:.1}% of the frame (target < 33.3%)",
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
        println!(
            "  accumulate {:.2} M rays/s vs bare ray-query probe {:.2} M rays/s ({} camera rays, closest hit): {:.1}% \
             (target >= 60%)",
            accumulate_rays_per_s / 1e6,
            probe_rays_per_s / 1e6,
            f.probe_rays,
            100.0 * accumulate_rays_per_s / probe_rays_per_s
        );
        let replay_rays_per_s = f.replay_rays as f64 / (f.replay_ms / 1e3);
        println!(
            "  accumulate vs the probe replaying one sample's own rays ({} shadow rays, first hit; {} closest hit), \
             no shading: {:.2} M rays/s, {:.1}%",
            f.replay_shadow_rays,
            f.replay_rays - f.replay_shadow_rays,
            replay_rays_per_s / 1e6,
            100.0 * accumulate_rays_per_s / replay_rays_per_s
        );
        let traced_times = traced.stats.pass_times.unwrap_or_default();
        println!(
            "  reference mode (--primary rays): accumulate {:.2} ms per sample with its camera rays, frame {:.2}x the \
             raster frame's GPU time, {:.1} bytes/pixel",
            traced_times.accumulate_ms / n,
            traced_times.total_ms() / total,
            traced.stats.device_bytes.saturating_sub(traced.scene_bytes) as f64 / pixels
        );
        println!(
            "  device memory: scene {:.2} MiB, frame {:.2} MiB = {:.1} bytes/pixel (images alone {:.1}; target < 100)",
            f.scene_bytes as f64 / 1048576.0,
            frame_bytes as f64 / 1048576.0,
            frame_bytes as f64 / pixels,
            s.image_bytes as f64 / pixels
        );
    }
    // Scaling: total GPU time against spp at a fixed size, and against pixels at a fixed spp.
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
        let f = time_frame(&gpu, &scene, half, spp, Primary::Raster, false)?;
        by_spp.push((f64::from(spp), f.stats.pass_times.unwrap_or_default().total_ms()));
    }
    let mut by_pixels = Vec::new();
    for size in [quarter, half, (w, h)] {
        eprint!("\rscaling: {}x{} ...", size.0, size.1);
        let f = time_frame(&gpu, &scene, size, 8, Primary::Raster, false)?;
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

fn info(args: InfoArgs) -> Result<()> {
    let mut text = String::new();
    macro_rules! out {
        ($($arg:tt)*) => {{
            use std::fmt::Write as _;
            let _ = writeln!(text, $($arg)*);
        }};
    }
    let loader = strata::vk::instance::loader_info()?;
    out!("Vulkan loader: {}", strata::vk::instance::version_string(loader.loader_version));
    match &loader.validation_layer {
        Some(layer) => out!("Validation layer: {layer}"),
        None => out!("Validation layer: not installed (run scripts/setup.sh for vulkan-validationlayers)"),
    }
    print_stdout(&text);
    text.clear();
    let instance = strata::vk::instance::Instance::new(&strata::vk::instance::InstanceOptions {
        validation: args.validate && loader.validation_layer.is_some(),
        echo_messages: args.validate,
    })
    .context("creating a Vulkan instance")?;
    let reports = strata::vk::device::enumerate_devices(&instance)?;
    if reports.is_empty() {
        print_stdout(&text);
        bail!("no Vulkan devices found; run scripts/setup.sh to install Mesa's lavapipe");
    }
    let chosen = strata::vk::device::select_device(&reports, None, strata::vk::DeviceNeeds::RayQueries).ok();
    out!("Devices:");
    for r in &reports {
        let marker = if Some(r.index) == chosen { " (default)" } else { "" };
        out!("  [{}] {}{marker}", r.index, r.name);
        out!("      type:      {}", r.type_name());
        out!("      driver:    {} {}", r.driver_name, r.driver_info);
        out!("      Vulkan:    {}", r.api_version_string());
        out!("      ray query: {}", if r.ray_query { "yes" } else { "no" });
        if r.qualifies() {
            out!("      strata:    usable");
        } else {
            out!("      strata:    not usable, lacks {}", r.missing.join(", "));
        }
    }
    print_stdout(&text);
    if chosen.is_none() {
        bail!("no device can run strata; run scripts/setup.sh to install Mesa's lavapipe with VK_KHR_ray_query");
    }
    Ok(())
}

/// Prints to stdout; a closed pipe (`strata info | head`) is not an error.
fn print_stdout(text: &str) {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    let _ = stdout.write_all(text.as_bytes()).and_then(|_| stdout.flush());
}
