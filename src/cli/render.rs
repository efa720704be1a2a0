//! `strata render`: load, render, write atomically, summarize.
use super::args::{ExposureArg, RenderArgs};
use super::print_stdout;
use super::progress::ProgressBar;
use super::scale_out::{self, FramePart};
use super::sequence;
use super::summary::Summary;
use anyhow::{anyhow, bail, Context as _, Result};
use strata::scene::framing::Framing;
use strata::vk::Gpu;
use strata::{Renderer, RendererOptions};

/// Set by Ctrl-C: the sample loop stops after the batch in flight; a second Ctrl-C exits at once (nothing has
/// been written either way: outputs are written atomically at the end).
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Set by SIGTERM (what schedulers send before they kill a job): stop like Ctrl-C, and with --checkpoint exit
/// with [`scale_out::EXIT_TERMINATED`] once the checkpoint is written.
static TERMINATED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

extern "C" fn on_sigterm(_: libc::c_int) {
    // Only atomic stores: async-signal-safe.
    TERMINATED.store(true, std::sync::atomic::Ordering::SeqCst);
    INTERRUPTED.store(true, std::sync::atomic::Ordering::SeqCst);
}

/// Whether SIGTERM stopped the run.
pub fn terminated() -> bool {
    TERMINATED.load(std::sync::atomic::Ordering::SeqCst)
}

fn install_interrupt_handler() {
    use std::sync::atomic::Ordering;
    let _ = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            eprintln!("\nstrata: interrupted again; exiting without writing anything");
            std::process::exit(130);
        }
    });
    let handler: extern "C" fn(libc::c_int) = on_sigterm;
    // SAFETY: the handler only stores to atomics.
    unsafe { libc::signal(libc::SIGTERM, handler as libc::sighandler_t) };
}

pub fn render(args: RenderArgs) -> Result<()> {
    install_interrupt_handler();
    let several = args.scenes.len() > 1;
    scale_out::check_options(&args, several)?;
    if several {
        let named = |p: &Option<std::path::PathBuf>| p.as_ref().is_none_or(|p| p.to_string_lossy().contains("{name}"));
        if args.output.is_none() || !named(&args.output) || !named(&args.exr) {
            bail!(
                "{} scenes need {{name}} in -o (and --exr), e.g. -o 'thumbs/{{name}}.png', so that each gets its own file",
                args.scenes.len()
            );
        }
        check_batch(args_output(&args), &args)?;
    }
    // One device and one set of pipelines for every scene; made by the first scene that gets that far.
    let mut renderer: Option<Renderer> = None;
    let mut failed: Vec<String> = Vec::new();
    for scene_path in &args.scenes {
        match render_scene(&args, scene_path, &mut renderer, several) {
            Ok(()) => {}
            Err(e) if several && e.downcast_ref::<strata::render::frame::Interrupted>().is_none() => {
                // Loading errors name their file already; others get it in front.
                let text = format!("{e:#}");
                let named = scene_path.display().to_string();
                if text.starts_with(&named) {
                    eprintln!("error: {text}");
                } else {
                    eprintln!("error: {named}: {text}");
                }
                failed.push(scene_path.display().to_string());
            }
            Err(e) => return Err(e),
        }
    }
    let log = renderer.as_ref().map(|r| r.gpu().validation_log());
    drop(renderer);
    if let (true, Some(log)) = (args.gpu.validate, log) {
        log.check().map_err(|report| anyhow!("{report}"))?;
    }
    if !failed.is_empty() {
        bail!("{} of {} scenes failed: {}", failed.len(), args.scenes.len(), failed.join(", "));
    }
    Ok(())
}

/// `{name}` in an output path: the scene file's name without its extension. A name that would climb out of or
/// stay in the output's directory (`..` from `...gltf`, `.`, nothing) is refused, naming the scene.
fn for_scene(path: &std::path::Path, scene: &std::path::Path) -> Result<std::path::PathBuf> {
    let text = path.to_string_lossy();
    if !text.contains("{name}") {
        return Ok(path.to_path_buf());
    }
    let name = scene.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    if name.is_empty() || name == "." || name == ".." {
        bail!("{}: its name {name:?} cannot stand for {{name}} in {text} (rename the file)", scene.display());
    }
    Ok(std::path::PathBuf::from(text.replace("{name}", &name)))
}

/// `-o` as given (a batch needs it).
fn args_output(args: &RenderArgs) -> &std::path::Path {
    args.output.as_deref().expect("a batch has -o (checked)")
}

/// The AOVs asked for.
fn aov_list(args: &RenderArgs) -> &[strata::render::aov::Aov] {
    args.aov.as_ref().map(|list| &list.0[..]).unwrap_or(&[])
}

/// Where an AOV of a PNG output goes: beside it, `x.<aov>.png`.
fn aov_png_path(output: &std::path::Path, aov: strata::render::aov::Aov) -> std::path::PathBuf {
    let stem = output.file_stem().and_then(|s| s.to_str()).unwrap_or("frame");
    output.with_file_name(format!("{stem}.{}.png", aov.name()))
}

/// The files one frame writes: the output, its AOV PNGs (beside a PNG output; an EXR holds them as layers), and
/// --exr.
fn frame_files(
    output: &std::path::Path,
    exr: Option<&std::path::Path>,
    aovs: &[strata::render::aov::Aov],
    camera_json: Option<&std::path::Path>,
) -> Result<Vec<(&'static str, std::path::PathBuf)>> {
    let mut files = vec![("-o", output.to_path_buf())];
    if strata::output::OutputFormat::from_path(output)? == strata::output::OutputFormat::Png {
        files.extend(aovs.iter().map(|&aov| ("an --aov file", aov_png_path(output, aov))));
    }
    files.extend(exr.map(|e| ("--exr", e.to_path_buf())));
    files.extend(camera_json.map(|c| ("--camera-json", c.to_path_buf())));
    Ok(files)
}

/// `--camera-json` for `scene`: its `{name}` filled in; it must name a .json file.
fn camera_json_for(args: &RenderArgs, scene: &std::path::Path) -> Result<Option<std::path::PathBuf>> {
    let Some(path) = &args.camera_json else { return Ok(None) };
    let path = for_scene(path, scene)?;
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) {
        bail!("--camera-json {}: the file name must end in .json", path.display());
    }
    Ok(Some(path))
}

/// The camera a frame was rendered with, at its time (the shutter's opening), and the exposure it was shown at.
fn camera_metadata(job: &SceneJob, picture: &Picture) -> strata::scene::camera::CameraMetadata {
    strata::scene::camera::CameraMetadata {
        width: job.settings.width,
        height: job.settings.height,
        camera: job.scene.camera_at(job.scene.shutter.0),
        time: job.scene.shutter.0,
        exposure: match picture {
            Picture::Rendered(r) => r.exposure,
            Picture::Preview(_) => job.settings.exposure,
        },
    }
}

/// Writes a frame's camera (`--camera-json`) whole or not at all.
fn write_camera_json(path: &std::path::Path, metadata: &strata::scene::camera::CameraMetadata) -> Result<()> {
    let staged = strata::output::stage(path, |file| {
        serde_json::to_writer_pretty(&mut *file, &metadata.to_json())?;
        std::io::Write::write_all(file, b"\n")?;
        Ok(())
    })?;
    staged.commit()
}

/// Before a batch renders: every scene's files are its own (two `Box.gltf` from two folders would write one
/// `out/Box.png`), and each name can stand for `{name}`.
fn check_batch(output: &std::path::Path, args: &RenderArgs) -> Result<()> {
    let mut plan = strata::write_plan::WritePlan::new();
    for scene in &args.scenes {
        let exr = args.exr.as_ref().map(|e| for_scene(e, scene)).transpose()?;
        let camera_json = camera_json_for(args, scene)?;
        for (role, path) in
            frame_files(&for_scene(output, scene)?, exr.as_deref(), aov_list(args), camera_json.as_deref())?
        {
            plan.writes(&format!("{role} of {}", scene.display()), &path)?;
        }
    }
    plan.check(&|_, _| false)
}

/// Everything one scene's run writes, reads and removes, checked as files before the device is made.
fn check_scene_plan(
    args: &RenderArgs,
    frames: &[sequence::FramePlan],
    output: &std::path::Path,
    exr: Option<&std::path::Path>,
    camera_json: Option<&std::path::Path>,
) -> Result<()> {
    let mut plan = strata::write_plan::WritePlan::new();
    if let Some(environment) = args.environment.as_ref().filter(|e| e.as_os_str() != "studio") {
        plan.reads("--environment", environment);
    }
    if let Some(resume) = &args.resume {
        plan.reads("--resume", resume);
    }
    for frame in frames {
        let (output, exr) = match frame.number {
            Some(n) => (sequence::numbered(output, n), exr.map(|e| sequence::numbered(e, n))),
            None => (output.to_path_buf(), exr.map(std::path::Path::to_path_buf)),
        };
        let camera_json = numbered_for(camera_json, frame.number);
        for (role, path) in frame_files(&output, exr.as_deref(), aov_list(args), camera_json.as_deref())? {
            plan.writes(role, &path)?;
        }
    }
    if let Some(checkpoint) = &args.checkpoint {
        plan.writes_then_removes("--checkpoint", checkpoint)?;
    }
    // Going on from one's own checkpoint is what --checkpoint does.
    plan.check(&|a, b| matches!((a, b), ("--checkpoint", "--resume") | ("--resume", "--checkpoint")))
}

/// A frame's file: `path` numbered as the frame is (None: a single frame keeps its name).
fn numbered_for(path: Option<&std::path::Path>, number: Option<u32>) -> Option<std::path::PathBuf> {
    path.map(|p| number.map_or_else(|| p.to_path_buf(), |n| sequence::numbered(p, n)))
}

/// What one scene renders, once loaded and checked: its settings and camera framing, the frames of this shard,
/// the files they write.
struct SceneJob {
    scene: strata::scene::Scene,
    settings: strata::scene::settings::RenderSettings,
    framing: Framing,
    /// The scene's lens, kept when a framing replaces the camera.
    lens: Option<strata::scene::camera::Lens>,
    plans: Vec<sequence::FramePlan>,
    /// A single frame's share of the samples (--samples, --shard, --checkpoint, --resume), if any.
    part_plan: Option<FramePart>,
    output: std::path::PathBuf,
    exr_output: Option<std::path::PathBuf>,
    camera_json: Option<std::path::PathBuf>,
}

/// Loads a scene and lays the command line over it (defaults, then the scene file, then the command line);
/// checks every output name and the files the run writes, reads and removes before any work. None: this shard
/// has nothing to do.
fn prepare_scene(args: &RenderArgs, scene_path: &std::path::Path) -> Result<Option<SceneJob>> {
    let options = strata::LoadOptions {
        allow_any_uri: args.allow_any_uri.then_some(true),
        animation: args.animation.clone(),
        variant: args.variant.clone(),
    };
    let loaded = strata::load(scene_path, &options)?;
    for warning in &loaded.scene.warnings {
        eprintln!("warning: {}: {warning}", scene_path.display());
    }
    if !args.quiet {
        for note in &loaded.scene.notes {
            eprintln!("note: {}: {note}", scene_path.display());
        }
    }
    let mut settings =
        strata::scene::settings::RenderSettings::default().with(&loaded.settings).with(&args.overrides());
    settings.auto_exposure = args.exposure == Some(ExposureArg::Auto);
    let output = settings
        .output
        .clone()
        .ok_or_else(|| anyhow!("no output file: pass -o FILE (or set output in the scene file's [render] table)"))?;
    let output = for_scene(&output, scene_path)?;
    let exr_output = args.exr.as_ref().map(|e| for_scene(e, scene_path)).transpose()?;
    // Check the output names before any work, so a typo costs nothing (the write plan below checks the rest).
    strata::output::OutputFormat::from_path(&output)?;
    if let Some(exr) = &exr_output {
        if strata::output::OutputFormat::from_path(exr)? != strata::output::OutputFormat::Exr {
            bail!("--exr {}: the file name must end in .exr", exr.display());
        }
    }
    let sequence = sequence_of(args)?;
    let mut scene = loaded.scene;
    light_the_scene(args, &mut scene, &settings, scene_path)?;
    let framing = Framing::of(&args.view(), &scene, settings.width as f32 / settings.height as f32)?;
    framing.apply(&mut scene);
    args.camera_overrides()
        .apply(&mut scene)
        .with_context(|| format!("{}: applying the command line's camera options", scene_path.display()))?;
    let lens = scene.camera.as_ref().map(|c| c.lens);
    let every_frame = sequence::plan(sequence, args.fps, args.shutter_angle);
    // One frame splits its samples; a sequence (even one whose shard holds a single frame) splits its frames.
    let one_frame = every_frame.len() == 1;
    let plans = scale_out::frames_of_shard(args, every_frame)?;
    if plans.is_empty() {
        eprintln!("strata: this shard has no frames (more shards than frames); nothing to do");
        return Ok(None);
    }
    // What the run writes, reads and removes, as files, before anything is read from a checkpoint or rendered.
    let camera_json = camera_json_for(args, scene_path)?;
    check_scene_plan(args, &plans, &output, exr_output.as_deref(), camera_json.as_deref())?;
    let part_plan = if one_frame && !args.preview { FramePart::of(args, settings.spp, &output)? } else { None };
    if part_plan.as_ref().is_some_and(FramePart::is_empty) {
        return Ok(None);
    }
    Ok(Some(SceneJob { scene, settings, framing, lens, plans, part_plan, output, exr_output, camera_json }))
}

/// One scene: load, frame, render its frame or frames, write them. A single frame is written once the device's
/// teardown has passed the layer; with `several` scenes or a sequence, each frame as it finishes (an interrupted
/// run keeps every finished frame) and the device stays for the next.
fn render_scene(
    args: &RenderArgs,
    scene_path: &std::path::Path,
    gpu_slot: &mut Option<Renderer>,
    several: bool,
) -> Result<()> {
    use std::sync::atomic::Ordering;
    let Some(mut job) = prepare_scene(args, scene_path)? else {
        return Ok(());
    };
    let denoiser = load_denoiser(args, &job)?;
    let started = std::time::Instant::now();
    if gpu_slot.is_none() {
        let trace = if several { args.trace.unwrap_or_default() } else { job.settings.trace };
        *gpu_slot = Some(Renderer::new(&RendererOptions {
            validation: args.gpu.validate,
            echo_messages: args.gpu.validate,
            device: args.gpu.device.clone(),
            trace,
        })?);
    }
    let gpu = gpu_slot.as_ref().expect("made above").gpu();
    let log = gpu.validation_log();
    let check_log = || if args.gpu.validate { log.check().map_err(|report| anyhow!("{report}")) } else { Ok(()) };
    // Geometry, textures and the environment go up once for every frame and pass of this run.
    let on_gpu = strata::render::SceneOnGpu::upload(&gpu.device, &job.scene)?;
    let single = job.plans.len() == 1 && !several;
    let mut finished: Vec<String> = Vec::new();
    for (k, plan) in job.plans.iter().enumerate() {
        if INTERRUPTED.load(Ordering::SeqCst) {
            return interrupted(finished, job.plans.len(), on_gpu, gpu_slot.take());
        }
        // This frame's camera and shutter; everything else stays as uploaded.
        if let Some(camera) = job.framing.camera(plan.theta_degrees) {
            job.scene.camera = Some(strata::scene::Camera { lens: job.lens.unwrap_or(camera.lens), ..camera });
        }
        if let Some(shutter) = plan.shutter {
            job.scene.shutter = shutter;
        }
        let (output, exr) = match plan.number {
            Some(n) => (sequence::numbered(&job.output, n), job.exr_output.as_ref().map(|e| sequence::numbered(e, n))),
            None => (job.output.clone(), job.exr_output.clone()),
        };
        if job.plans.len() > 1 && !args.quiet {
            eprintln!("strata: frame {} of {} ({})", k + 1, job.plans.len(), output.display());
        }
        let frame_started = std::time::Instant::now();
        let (picture, part) = match render_picture(args, gpu, &job, &on_gpu)? {
            Some(rendered) => rendered,
            None => {
                // Interrupted: a checkpoint keeps the samples so far, a sequence its finished frames.
                if let Some(plan) = job.part_plan.as_ref().filter(|p| p.checkpoint().is_some()) {
                    let checkpoint = plan.checkpoint().expect("filtered");
                    return stopped_with_checkpoint(checkpoint, plan.last_save_failed(), on_gpu, gpu_slot.take());
                }
                if !finished.is_empty() {
                    return interrupted(finished, job.plans.len(), on_gpu, gpu_slot.take());
                }
                return Err(strata::render::frame::Interrupted.into());
            }
        };
        let frame = FrameOutputs::make(args, gpu, &job, &on_gpu, denoiser.as_ref(), picture)?;
        // What the layer said so far; teardown messages are checked once the device is gone.
        check_log()?;
        let device_name = gpu.device.report.name.clone();
        let written = FrameReport {
            output: &output,
            exr: exr.as_deref(),
            seconds: if single { started } else { frame_started }.elapsed().as_secs_f64(),
            device: device_name,
            part: None,
        };
        if single {
            drop(on_gpu);
            drop(gpu_slot.take());
            check_log()?;
            match &part {
                Some(part) => strata::partial::file::write_part(&output, part)?,
                None => frame.write(&output, exr.as_deref())?,
            }
            frame.write_camera(&job, plan.number)?;
            if let Some(plan) = &job.part_plan {
                plan.finish()?;
            }
            let part = job.part_plan.as_ref().filter(|p| p.writes_part).map(FramePart::target);
            report(args, &job.settings, &job.scene, &frame.picture, FrameReport { part, ..written });
            return Ok(());
        }
        frame.write(&output, exr.as_deref())?;
        frame.write_camera(&job, plan.number)?;
        finished.push(output.display().to_string());
        report(args, &job.settings, &job.scene, &frame.picture, written);
    }
    drop(on_gpu);
    check_log()?;
    if job.plans.len() > 1 && !args.quiet {
        eprintln!("strata: {} frames in {:.1} s", finished.len(), started.elapsed().as_secs_f64());
    }
    Ok(())
}

/// The denoiser `--denoise` needs, loaded before any work, so that a missing library costs nothing.
fn load_denoiser(args: &RenderArgs, job: &SceneJob) -> Result<Option<strata::denoise::Denoiser>> {
    if !args.denoise {
        return Ok(None);
    }
    if job.part_plan.as_ref().is_some_and(|p| p.writes_part) {
        bail!("--denoise works on whole frames, not on a part of one's samples (--samples, --shard)");
    }
    Ok(Some(strata::denoise::Denoiser::load()?))
}

/// What one frame writes: its picture (denoised with `--denoise`, the noisy one kept), and its AOVs.
struct FrameOutputs {
    picture: Picture,
    aovs: Vec<(strata::render::aov::Aov, strata::output::Frame)>,
    noisy: Option<strata::output::Frame>,
}

impl FrameOutputs {
    /// The frame's AOVs and, with a denoiser, its picture denoised.
    fn make(
        args: &RenderArgs,
        gpu: &Gpu,
        job: &SceneJob,
        on_gpu: &strata::render::SceneOnGpu,
        denoiser: Option<&strata::denoise::Denoiser>,
        mut picture: Picture,
    ) -> Result<Self> {
        let aovs = match &args.aov {
            Some(list) => {
                let size = (job.settings.width, job.settings.height);
                // Motion looks one frame ahead: 1 / --fps.
                strata::render_aovs(&gpu.device, &job.scene, on_gpu, size, &list.0, 1.0 / args.fps)?
            }
            None => Vec::new(),
        };
        let noisy = match (denoiser, &mut picture) {
            (Some(denoiser), Picture::Rendered(rendered)) => {
                Some(strata::denoise_frame(denoiser, &gpu.device, &job.scene, on_gpu, &job.settings, rendered)?)
            }
            _ => None,
        };
        Ok(Self { picture, aovs, noisy })
    }

    fn write(&self, output: &std::path::Path, exr: Option<&std::path::Path>) -> Result<()> {
        write_picture(output, exr, &self.picture, &self.aovs, self.noisy.as_ref())
    }

    /// The frame's `--camera-json`, if asked for, numbered as the frame is.
    fn write_camera(&self, job: &SceneJob, number: Option<u32>) -> Result<()> {
        match numbered_for(job.camera_json.as_deref(), number) {
            Some(path) => write_camera_json(&path, &camera_metadata(job, &self.picture)),
            None => Ok(()),
        }
    }
}

/// One frame's picture: the preview, or the render (of the part `job.part_plan` asks for, with the part it
/// makes), with a progress bar on a terminal. None: Ctrl-C or SIGTERM stopped it.
fn render_picture(
    args: &RenderArgs,
    gpu: &Gpu,
    job: &SceneJob,
    on_gpu: &strata::render::SceneOnGpu,
) -> Result<Option<(Picture, Option<strata::partial::file::Part>)>> {
    use std::io::IsTerminal as _;
    use std::sync::atomic::Ordering;
    let (scene, settings) = (&job.scene, &job.settings);
    if args.preview {
        let preview = strata::render::PreviewSettings {
            width: settings.width,
            height: settings.height,
            background: settings.background.to_array(),
        };
        return Ok(Some((Picture::Preview(strata::render_preview(gpu, scene, on_gpu, &preview)?), None)));
    }
    let mut bar = ProgressBar::new(!args.quiet && std::io::stderr().is_terminal());
    let mut progress = |done: u32, total: u32| {
        bar.update(done, total);
        !INTERRUPTED.load(Ordering::SeqCst)
    };
    let rendered = match &job.part_plan {
        None => {
            let frame_options = strata::render::frame::FrameOptions::default();
            strata::render(gpu, scene, on_gpu, settings, &frame_options, &mut progress).map(|r| (r, None))
        }
        Some(plan) => plan.render(gpu, scene, on_gpu, settings, &mut progress),
    };
    bar.finish();
    match rendered {
        Ok((r, part)) => Ok(Some((Picture::Rendered(Box::new(r)), part))),
        Err(e) if e.downcast_ref::<strata::render::frame::Interrupted>().is_some() => Ok(None),
        Err(e) => Err(e),
    }
}

/// The environment the command line names (with its rotation and intensity), and a default key light for a scene
/// with no light at all.
fn light_the_scene(
    args: &RenderArgs,
    scene: &mut strata::scene::Scene,
    settings: &strata::scene::settings::RenderSettings,
    scene_path: &std::path::Path,
) -> Result<()> {
    if let Some(path) = &args.environment {
        scene.environment = Some(strata::scene::environment::Environment::named(path)?);
    }
    if let Some(environment) = &mut scene.environment {
        if let Some(r) = args.environment_rotation {
            environment.rotation_degrees = r;
        }
        if let Some(i) = args.environment_intensity {
            environment.intensity = i;
        }
    } else if args.environment_rotation.is_some() || args.environment_intensity.is_some() {
        bail!("--environment-rotation and --environment-intensity need an environment (--environment FILE)");
    }
    if args.preview {
        return Ok(());
    }
    if let Some(warning) = scene.light_for_render(settings.backdrop)? {
        eprintln!("warning: {}: {warning}", scene_path.display());
    }
    Ok(())
}

/// Ctrl-C between or during the frames of a sequence: the finished frames stay, the one in flight is dropped.
fn interrupted(
    finished: Vec<String>,
    total: usize,
    on_gpu: strata::render::SceneOnGpu,
    gpu: Option<Renderer>,
) -> Result<()> {
    drop(on_gpu);
    drop(gpu);
    eprintln!(
        "strata: {} after {} of {total} frames; the finished frames are kept ({}), none is half-written",
        if terminated() { "stopped by SIGTERM" } else { "interrupted" },
        finished.len(),
        if finished.is_empty() { "none".to_string() } else { finished.join(", ") }
    );
    std::process::exit(if terminated() { 143 } else { 130 });
}

/// Ctrl-C or SIGTERM during a render with --checkpoint: the samples so far are in the checkpoint (written by the
/// render as it stopped); say so and exit, 75 after SIGTERM (run the same command again), 130 after Ctrl-C.
fn stopped_with_checkpoint(
    checkpoint: &std::path::Path,
    save_failed: bool,
    on_gpu: strata::render::SceneOnGpu,
    gpu: Option<Renderer>,
) -> Result<()> {
    drop(on_gpu);
    drop(gpu);
    let terminated = TERMINATED.load(std::sync::atomic::Ordering::SeqCst);
    let why = if terminated { "stopped by SIGTERM" } else { "interrupted" };
    if save_failed {
        eprintln!(
            "strata: {why}; the last checkpoint could not be written (see the warning above){}",
            if checkpoint.is_file() { ", so the one there holds fewer samples" } else { "" }
        );
    } else if checkpoint.is_file() {
        eprintln!(
            "strata: {why}; the samples so far are saved in {} (run the same command again to go on from them)",
            checkpoint.display()
        );
    } else {
        eprintln!("strata: {why} before the first checkpoint; nothing was written");
    }
    std::process::exit(if terminated { i32::from(scale_out::EXIT_TERMINATED) } else { 130 });
}

/// What `--time`, `--turntable` and `--frames` ask for (at most one of them).
fn sequence_of(args: &RenderArgs) -> Result<sequence::Sequence> {
    use sequence::Sequence;
    let asked = [args.time.is_some(), args.turntable.is_some(), args.frames.is_some()];
    if asked.iter().filter(|a| **a).count() > 1 {
        bail!("--time, --turntable and --frames each make their own frames: give one of them");
    }
    if args.shutter.is_some() && (args.time.is_some() || args.frames.is_some()) {
        bail!("--shutter sets one still frame's shutter; with --time and --frames use --shutter-angle");
    }
    Ok(match (args.time, args.turntable, args.frames) {
        (Some(t), _, _) => Sequence::Time(t),
        (_, Some(views), _) => {
            Sequence::Turntable { views, first_theta: args.orbit.map(|o| o.theta_degrees).unwrap_or(0.0) }
        }
        (_, _, Some((first, last))) => Sequence::Frames { first, last },
        _ => Sequence::Single,
    })
}

/// What one finished frame wrote, for its summary line.
struct FrameReport<'a> {
    output: &'a std::path::Path,
    exr: Option<&'a std::path::Path>,
    seconds: f64,
    device: String,
    /// The samples of the frame a part holds, when the run wrote a part.
    part: Option<(u32, u32)>,
}

/// The summary line (and JSON) of one written frame.
fn report(
    args: &RenderArgs,
    settings: &strata::scene::settings::RenderSettings,
    scene: &strata::scene::Scene,
    picture: &Picture,
    frame: FrameReport<'_>,
) {
    let FrameReport { output, exr, seconds, device, part } = frame;
    let mut written = vec![output.display().to_string()];
    written.extend(exr.map(|p| p.display().to_string()));
    let summary = Summary {
        written,
        width: settings.width,
        height: settings.height,
        spp: if args.preview { 1 } else { settings.spp },
        part,
        sampler: if args.preview { "preview" } else { settings.sampler.name() },
        primary: if args.preview { "raster" } else { settings.primary.name() },
        trace: match picture {
            Picture::Rendered(r) => r.stats.trace.name(),
            Picture::Preview(_) => "no",
        },
        indirect: settings.indirect && !args.preview,
        bounces: if args.preview { 0 } else { settings.bounces },
        shading_samples: if args.preview { 1 } else { settings.shading_samples },
        seed: settings.seed,
        seconds,
        stats: match picture {
            Picture::Rendered(r) => Some(r.stats.clone()),
            Picture::Preview(_) => None,
        },
        device,
        triangles: scene.triangle_count(),
        instances: scene.instances.len(),
        exposure: match picture {
            Picture::Rendered(r) => r.exposure,
            Picture::Preview(_) => settings.exposure,
        },
        auto_exposure: settings.auto_exposure && !args.preview,
    };
    if args.json {
        print_stdout(&format!("{}\n", summary.json()));
    }
    if !args.quiet {
        eprintln!("{}", summary.line());
    }
}

/// The picture at `output` (with its AOVs) and, when asked, the linear radiance and AOV layers at `exr`: every
/// file written in full first, then all put in place, so that a failure leaves none of them behind.
fn write_picture(
    output: &std::path::Path,
    exr: Option<&std::path::Path>,
    picture: &Picture,
    aovs: &[(strata::render::aov::Aov, strata::output::Frame)],
    noisy: Option<&strata::output::Frame>,
) -> Result<()> {
    let mut staged = stage_outputs(output, picture, aovs, noisy)?;
    if let Some(exr) = exr {
        staged.push(strata::output::stage_frame_with_layers(exr, picture.linear(), &exr_layers(aovs, noisy))?);
    }
    for file in staged {
        let path = file.path().to_path_buf();
        file.commit()?;
        if path != output && Some(path.as_path()) != exr {
            eprintln!("strata: wrote {}", path.display());
        }
    }
    Ok(())
}

/// An EXR's extra layers: the AOVs, and the noisy picture when the beauty is denoised.
fn exr_layers<'a>(
    aovs: &'a [(strata::render::aov::Aov, strata::output::Frame)],
    noisy: Option<&'a strata::output::Frame>,
) -> Vec<(&'a str, &'a strata::output::Frame)> {
    let mut layers: Vec<(&str, &strata::output::Frame)> = aovs.iter().map(|(aov, f)| (aov.name(), f)).collect();
    layers.extend(noisy.map(|f| ("noisy", f)));
    layers
}

/// What a render produced: the distributed-ray-traced frame, or the raster preview.
enum Picture {
    Rendered(Box<strata::render::frame::RenderedFrame>),
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

/// The beauty image, then the AOVs: layers of an EXR, or PNGs beside a PNG; staged, not yet in place.
fn stage_outputs(
    output: &std::path::Path,
    picture: &Picture,
    aovs: &[(strata::render::aov::Aov, strata::output::Frame)],
    noisy: Option<&strata::output::Frame>,
) -> Result<Vec<strata::output::Staged>> {
    use strata::output::{stage_data_png, stage_frame_with_layers, stage_png_rgba8, OutputFormat};
    if OutputFormat::from_path(output)? == OutputFormat::Exr {
        return Ok(vec![stage_frame_with_layers(output, picture.linear(), &exr_layers(aovs, noisy))?]);
    }
    let mut staged = vec![match picture {
        Picture::Rendered(r) => stage_png_rgba8(output, r.linear.width, r.linear.height, &r.display)?,
        Picture::Preview(frame) => stage_frame_with_layers(output, frame, &[])?,
    }];
    for (aov, raw) in aovs {
        let path = aov_png_path(output, *aov);
        staged.push(if aov.is_color() {
            stage_frame_with_layers(&path, raw, &[])?
        } else {
            stage_data_png(&path, &aov.for_display(raw))?
        });
    }
    Ok(staged)
}
