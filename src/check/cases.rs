//! The cases of `strata check`, and how one runs inside its child process ([`run_case`]).
//!
//! Adding a case: give it one entry in [`all`]: its name `kind/what`, whether `--quick` runs it, one line on what
//! it proves, and how it runs ([`Run`]: the optics check, the scene and settings, the breakage); a golden or AOV
//! case then needs its golden, made with `strata check --bless --cases '^kind/what$'` (docs/check.md).
use super::golden::{self, file_name, Goldens, Rgba8};
use super::{optics, CaseReport, Figure, Status};
use crate::render::aov::Aov;
use crate::render::frame::{render_frame, FrameOptions, RenderedFrame, Sabotage};
use crate::render::SceneOnGpu;
use crate::scene::settings::{Primary, RenderSettings, SettingsOverrides, Trace};
use crate::scene::Scene;
use crate::vk::Gpu;
use anyhow::{bail, Context as _, Result};
use std::path::{Path, PathBuf};

/// What a case checks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Optics,
    Golden,
    Aov,
    Determinism,
    Canary,
    /// Hidden cases that misbehave on purpose, for the suite's own tests (`--test-cases`).
    Test,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Optics => "optics",
            Kind::Golden => "golden",
            Kind::Aov => "aov",
            Kind::Determinism => "determinism",
            Kind::Canary => "canary",
            Kind::Test => "test",
        }
    }
}

/// One case of the suite, registered once in [`all`].
#[derive(Debug, Clone, Copy)]
pub struct Case {
    pub name: &'static str,
    /// Part of `--quick`. Canaries run in every check.
    pub quick: bool,
    pub about: &'static str,
    pub run: Run,
}

/// How a case runs: what tells it from the other cases of its kind.
#[derive(Debug, Clone, Copy)]
pub enum Run {
    /// Renders what the check asks for and measures figures that follow from geometry and optics.
    Optics(fn(&mut optics::Renderer<'_>) -> Result<Vec<Figure>>),
    /// Renders a scene and compares the picture with its golden.
    Golden(SceneSpec),
    /// Renders a scene's AOVs and compares them with their goldens.
    Aov(SceneSpec),
    /// Renders a scene twice in one process: the same bits.
    Determinism(SceneSpec),
    /// Renders the golden case `golden` broken in a known way: its comparison must fail.
    Canary { golden: &'static str, breakage: Breakage },
    /// Misbehaves on purpose, for the suite's own tests.
    Test(TestBehaviour),
}

/// How a canary breaks its render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Breakage {
    NoShadowRays,
    FlippedNormals,
    OnePixelShift,
    WrongSrgbCurve,
}

/// What a hidden test case does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TestBehaviour {
    Pass,
    Fail,
    Crash,
    Hang,
    /// Fails on its first attempt, passes on its second.
    Flaky,
    ValidationError,
}

impl Case {
    pub fn kind(&self) -> Kind {
        match self.run {
            Run::Optics(_) => Kind::Optics,
            Run::Golden(_) => Kind::Golden,
            Run::Aov(_) => Kind::Aov,
            Run::Determinism(_) => Kind::Determinism,
            Run::Canary { .. } => Kind::Canary,
            Run::Test(_) => Kind::Test,
        }
    }
}

const fn case(name: &'static str, quick: bool, about: &'static str, run: Run) -> Case {
    Case { name, quick, about, run }
}

/// Every case, in the order a run takes them (the hidden test cases only with `include_test_cases`).
pub fn all(include_test_cases: bool) -> Vec<Case> {
    use Breakage::*;
    use Run::*;
    let cornell = spec("cornell", 64, 64, 128);
    let showcase = spec("showcase", 96, 54, 64);
    let canary = |breakage| Canary { golden: "golden/cornell", breakage };
    let mut cases = vec![
        case(
            "optics/penumbra",
            false,
            "a quad light's penumbra is as wide as similar triangles say",
            Optics(optics::penumbra),
        ),
        case(
            "optics/disk-light-radiance",
            true,
            "a disk light's reflected radiance equals its closed form",
            Optics(optics::disk_light_radiance),
        ),
        case(
            "optics/circle-of-confusion",
            false,
            "a defocused edge spreads over the circle of confusion",
            Optics(optics::circle_of_confusion),
        ),
        case(
            "optics/motion-blur-ramp",
            false,
            "a moving square smears into a linear ramp v·T long",
            Optics(optics::motion_blur_ramp),
        ),
        case(
            "optics/furnace",
            false,
            "a glowing box sums the bounces' geometric series",
            Optics(|render| optics::glowing_box_series(render, &[3, 1])),
        ),
        case("golden/cornell", true, "the Cornell box, Cook's effects", Golden(cornell)),
        case(
            "golden/cornell-indirect",
            false,
            "the Cornell box with diffuse interreflection",
            Golden(SceneSpec { indirect: true, ..cornell }),
        ),
        case("golden/showcase", false, "the showcase: every effect at once", Golden(showcase)),
        case(
            "golden/showcase-rays",
            false,
            "the showcase through traced primary rays",
            Golden(SceneSpec { primary: Primary::Rays, ..showcase }),
        ),
        case("golden/dof", false, "depth of field", Golden(spec("dof", 96, 54, 128))),
        case("golden/motion", false, "motion blur", Golden(spec("motion", 96, 54, 128))),
        case("golden/soft-shadows", false, "soft shadows", Golden(spec("soft-shadows", 96, 54, 128))),
        case("aov/cornell", true, "the Cornell box's normals, depth and bump height", Aov(spec("cornell", 64, 64, 1))),
        case("aov/showcase", false, "the showcase's normals, depth and bump height", Aov(spec("showcase", 96, 54, 1))),
        case(
            "determinism/cornell",
            true,
            "the Cornell box twice in one process, the same bits",
            Determinism(spec("cornell", 64, 64, 16)),
        ),
        case(
            "determinism/showcase-indirect",
            false,
            "the showcase with --indirect twice, the same bits",
            Determinism(SceneSpec { indirect: true, ..spec("showcase", 96, 54, 8) }),
        ),
        case(
            "canary/shadow-rays-off",
            true,
            "soft shadows with every shadow ray unoccluded must fail",
            Canary { golden: "golden/soft-shadows", breakage: NoShadowRays },
        ),
        case("canary/normals-flipped", true, "the Cornell box with flipped normals must fail", canary(FlippedNormals)),
        case("canary/one-pixel-shift", true, "the Cornell box moved one pixel must fail", canary(OnePixelShift)),
        case(
            "canary/wrong-srgb-curve",
            true,
            "the Cornell box without the sRGB curve must fail",
            canary(WrongSrgbCurve),
        ),
    ];
    if include_test_cases {
        use TestBehaviour as T;
        cases.extend([
            case("test/pass", true, "passes", Test(T::Pass)),
            case("test/fail", true, "fails a figure", Test(T::Fail)),
            case("test/crash", true, "aborts its process", Test(T::Crash)),
            case("test/hang", true, "never finishes", Test(T::Hang)),
            case("test/flaky", true, "fails on its first attempt, passes on its second", Test(T::Flaky)),
            case("test/validation-error", true, "provokes a validation error", Test(T::ValidationError)),
        ]);
    }
    cases
}

/// Looks a case up by name (hidden test cases included).
pub fn find(name: &str) -> Option<Case> {
    all(true).into_iter().find(|c| c.name == name)
}

/// A scene from `scenes/` at settings of its own, rendered by golden, determinism and canary cases.
#[derive(Debug, Clone, Copy)]
pub struct SceneSpec {
    pub scene: &'static str,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub primary: Primary,
    pub indirect: bool,
}

/// The seed every golden is rendered with (`--calibrate` renders others).
pub const GOLDEN_SEED: u64 = 1;

const fn spec(scene: &'static str, width: u32, height: u32, spp: u32) -> SceneSpec {
    SceneSpec { scene, width, height, spp, primary: Primary::Raster, indirect: false }
}

/// What a golden case renders.
pub fn golden_spec(case: &str) -> Option<SceneSpec> {
    match find(case)?.run {
        Run::Golden(spec) => Some(spec),
        _ => None,
    }
}

/// What a child process needs to run a case.
pub struct CaseContext<'a> {
    pub gpu: &'a Gpu,
    pub trace: Trace,
    /// The run's output directory (the embedded scenes are written to its `scenes/`).
    pub out: PathBuf,
    /// This case's own directory in it.
    pub dir: PathBuf,
    pub goldens: &'a Goldens,
    /// 1 on the first run, 2 on the re-run of a failure.
    pub attempt: u32,
    /// `--calibrate`: also render other seeds and propose perceptual thresholds.
    pub calibrate: bool,
    /// `--device` as given, for the reproduce commands.
    pub device_arg: Option<String>,
}

impl CaseContext<'_> {
    /// The device that runs the case, as goldens name it: its name and driver.
    pub fn device_key(&self) -> String {
        device_key(&self.gpu.device.report)
    }
}

/// How goldens name a device: name / driver info.
pub fn device_key(report: &crate::vk::device::DeviceReport) -> String {
    format!("{} / {}", report.name, report.driver_info)
}

/// A directory name for a case: its name with `/` as `-`.
pub fn slug(case: &str) -> String {
    case.replace('/', "-")
}

/// Runs one case in this process and returns its report (the verdict before validation and expectations).
pub fn run_case(case: &Case, ctx: &CaseContext<'_>) -> Result<CaseReport> {
    std::fs::create_dir_all(&ctx.dir).with_context(|| format!("creating {}", ctx.dir.display()))?;
    let mut report = CaseReport { case: case.name.into(), device: ctx.device_key(), ..Default::default() };
    report.reproduce = check_command(ctx, case.name);
    let started = std::time::Instant::now();
    let result = match case.run {
        Run::Optics(check) => optics_case(check, ctx, &mut report),
        Run::Golden(spec) => golden_case(case.name, &spec, ctx, &mut report),
        Run::Aov(spec) => aov_case(case.name, &spec, ctx, &mut report),
        Run::Determinism(spec) => determinism_case(&spec, ctx, &mut report),
        Run::Canary { golden, breakage } => canary_case(golden, breakage, ctx, &mut report),
        Run::Test(behaviour) => test_case(behaviour, ctx, &mut report),
    };
    if let Err(e) = result {
        let text = format!("{e:#}");
        report.verdict = Some(if text.contains("ERROR_DEVICE_LOST") { Status::Crash } else { Status::Fail });
        report.message = text;
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// The `strata check` command that runs this case alone on the same device.
fn check_command(ctx: &CaseContext<'_>, case: &str) -> String {
    let mut command = format!("strata check --cases '^{case}$' --trace {}", ctx.trace.name());
    if case.starts_with("test/") {
        command.push_str(" --test-cases");
    }
    if let Some(d) = &ctx.device_arg {
        command.push_str(&format!(" --device '{d}'"));
    }
    command
}

/// Sets the verdict from figures: Pass when every one is within tolerance, else Fail naming the first that is not.
fn judge_figures(report: &mut CaseReport, figures: Vec<Figure>) {
    let failed: Vec<String> = figures.iter().filter(|f| !f.passes()).map(|f| f.to_string()).collect();
    report.verdict = Some(if failed.is_empty() { Status::Pass } else { Status::Fail });
    report.message =
        if failed.is_empty() { format!("{} figure(s) within tolerance", figures.len()) } else { failed.join("; ") };
    report.figures = figures;
}

fn render_on(
    ctx: &CaseContext<'_>,
    scene: &Scene,
    settings: &RenderSettings,
    options: &FrameOptions,
) -> Result<RenderedFrame> {
    let on_gpu = SceneOnGpu::upload(&ctx.gpu.device, scene)?;
    let settings = RenderSettings { trace: ctx.trace, ..settings.clone() };
    render_frame(&ctx.gpu.device, scene, &on_gpu, &settings, options, &mut |_, _| true)
}

fn optics_case(
    check: fn(&mut optics::Renderer<'_>) -> Result<Vec<Figure>>,
    ctx: &CaseContext<'_>,
    report: &mut CaseReport,
) -> Result<()> {
    let mut render =
        |scene: &Scene, settings: &RenderSettings| render_on(ctx, scene, settings, &FrameOptions::default());
    let figures = check(&mut render)?;
    judge_figures(report, figures);
    report.tier = Some("optics".into());
    Ok(())
}

/// A scene of `scenes/` (written from the binary into the run's directory) and its settings at `spec`.
fn load_spec(ctx: &CaseContext<'_>, spec: &SceneSpec, seed: u64) -> Result<(Scene, RenderSettings, PathBuf)> {
    let path = super::embedded::write_scene(&ctx.out.join("scenes"), spec.scene)?;
    let loaded = crate::load(&path, &crate::LoadOptions::default())?;
    let ours = SettingsOverrides {
        width: Some(spec.width),
        height: Some(spec.height),
        spp: Some(spec.spp),
        seed: Some(seed),
        primary: Some(spec.primary),
        indirect: Some(spec.indirect),
        trace: Some(ctx.trace),
        ..Default::default()
    };
    let settings = RenderSettings::default().with(&loaded.settings).with(&ours);
    Ok((loaded.scene, settings, path))
}

/// The `strata render` command that renders what a scene case renders.
fn render_command(ctx: &CaseContext<'_>, spec: &SceneSpec, path: &Path, output: &Path) -> String {
    let mut command = format!(
        "strata render {} --size {}x{} --spp {} --seed {GOLDEN_SEED} --primary {} --trace {} --validate -o {}",
        path.display(),
        spec.width,
        spec.height,
        spec.spp,
        spec.primary.name(),
        ctx.trace.name(),
        output.display()
    );
    if spec.indirect {
        command.push_str(" --indirect");
    }
    if let Some(d) = &ctx.device_arg {
        command.push_str(&format!(" --device '{d}'"));
    }
    command
}

fn display_image(frame: &RenderedFrame) -> Rgba8 {
    Rgba8 { width: frame.linear.width, height: frame.linear.height, pixels: frame.display.clone() }
}

fn write_png(dir: &Path, name: &str, image: &Rgba8) -> Result<()> {
    crate::output::write_png_rgba8(&dir.join(name), image.width, image.height, &image.pixels)
}

/// How an image compared with a golden.
struct Judgement {
    verdict: Status,
    tier: Option<String>,
    message: String,
    figures: Vec<Figure>,
    images: Vec<(String, String)>,
}

/// The two tiers for an image against the golden of `golden_case`: bit-identical (the golden's own pixels on the
/// device that made it, or a hash this device blessed), else ꟻLIP against the case's thresholds. Writes
/// `actual.png`, and `reference.png` and `flip.png` when it gets that far.
fn judge_image(ctx: &CaseContext<'_>, golden_case: &str, actual: &Rgba8) -> Result<Judgement> {
    write_png(&ctx.dir, "actual.png", actual)?;
    let mut images = vec![("actual".to_string(), "actual.png".to_string())];
    let name = file_name(golden_case, "png");
    let Some(bytes) = ctx.goldens.read(&name)? else {
        return Ok(Judgement {
            verdict: Status::Missing,
            tier: None,
            message: format!(
                "no golden {name} in {} (make it: strata check --bless --cases '^{golden_case}$')",
                ctx.goldens.describe()
            ),
            figures: Vec::new(),
            images,
        });
    };
    let reference = Rgba8::decode_png(&bytes).with_context(|| format!("golden {name}"))?;
    std::fs::write(ctx.dir.join("reference.png"), &bytes)?;
    images.insert(0, ("reference".into(), "reference.png".into()));
    let entry = ctx.goldens.entries.get(golden_case).cloned().unwrap_or_default();
    let device = ctx.device_key();
    let exact = if entry.device == device {
        Some(reference == *actual)
    } else {
        entry.hashes.get(&device).map(|h| *h == actual.hash())
    };
    if exact == Some(true) {
        return Ok(Judgement {
            verdict: Status::Pass,
            tier: Some("bit-identical".into()),
            message: format!("bit-identical to {name}"),
            figures: Vec::new(),
            images,
        });
    }
    let exact_note = match exact {
        Some(false) => "not bit-identical on the device that made the golden",
        _ => "no exact reference for this device",
    };
    if (reference.width, reference.height) != (actual.width, actual.height) {
        return Ok(Judgement {
            verdict: Status::Fail,
            tier: Some("size".into()),
            message: format!(
                "{exact_note}; the render is {}x{}, the golden {}x{}",
                actual.width, actual.height, reference.width, reference.height
            ),
            figures: Vec::new(),
            images,
        });
    }
    let result = golden::flip(&reference, actual)?;
    write_png(&ctx.dir, "flip.png", &result.heat_map)?;
    images.push(("FLIP error".into(), "flip.png".into()));
    let (mean_limit, p99_limit) = entry.thresholds();
    let figures = vec![
        Figure::at_most("FLIP mean", result.mean, mean_limit, ""),
        Figure::at_most("FLIP 99th percentile", result.p99, p99_limit, ""),
    ];
    let pass = figures.iter().all(Figure::passes);
    Ok(Judgement {
        verdict: if pass { Status::Pass } else { Status::Fail },
        tier: Some("perceptual".into()),
        message: format!(
            "{exact_note}; perceptual tier: FLIP mean {:.5} (limit {mean_limit}), 99th percentile {:.5} (limit {p99_limit}): {}",
            result.mean,
            result.p99,
            if pass { "within the thresholds" } else { "beyond the thresholds" }
        ),
        figures,
        images,
    })
}

fn golden_case(name: &str, spec: &SceneSpec, ctx: &CaseContext<'_>, report: &mut CaseReport) -> Result<()> {
    let (scene, settings, path) = load_spec(ctx, spec, GOLDEN_SEED)?;
    let frame = render_on(ctx, &scene, &settings, &FrameOptions::default())?;
    let actual = display_image(&frame);
    let judgement = judge_image(ctx, name, &actual)?;
    report.verdict = Some(judgement.verdict);
    report.tier = judgement.tier;
    report.message = judgement.message;
    report.figures = judgement.figures;
    report.images = judgement.images;
    report.bless = vec![(file_name(name, "png"), "actual.png".into())];
    report.reproduce = render_command(ctx, spec, &path, &ctx.dir.join("actual.png"));
    if ctx.calibrate {
        report.proposed_thresholds = Some(calibrate(ctx, &scene, &settings, &actual)?);
    }
    Ok(())
}

/// Seeds `--calibrate` renders besides the golden's.
pub const CALIBRATION_SEEDS: [u64; 4] = [2, 3, 4, 5];
/// How far above the largest measured spread the proposed thresholds sit.
pub const CALIBRATION_MARGIN: f64 = 1.5;

/// ꟻLIP of renders at other seeds against this one: the case's Monte Carlo noise, which a different device's
/// rounding stays within. Proposes (mean, 99th percentile) thresholds: the largest of each, times the margin.
fn calibrate(ctx: &CaseContext<'_>, scene: &Scene, settings: &RenderSettings, seed_one: &Rgba8) -> Result<[f64; 2]> {
    let mut worst = [0.0f64; 2];
    for seed in CALIBRATION_SEEDS {
        let frame = render_on(ctx, scene, &RenderSettings { seed, ..settings.clone() }, &FrameOptions::default())?;
        let r = golden::flip(seed_one, &display_image(&frame))?;
        worst = [worst[0].max(r.mean), worst[1].max(r.p99)];
    }
    Ok(worst.map(|w| w * CALIBRATION_MARGIN))
}

/// The AOV channels a case compares, each with its tolerance on the 99th percentile of |Δ| (after the exact
/// tier), and the share of pixels whose coverage may differ (silhouettes rasterize a little differently).
const AOV_CHANNELS: [(Aov, f64); 3] = [(Aov::Normal, 2e-3), (Aov::Depth, 1e-3), (Aov::Height, 1e-4)];
const AOV_COVERAGE_SHARE: f64 = 0.01;

fn aov_case(name: &str, spec: &SceneSpec, ctx: &CaseContext<'_>, report: &mut CaseReport) -> Result<()> {
    let (mut scene, settings, _) = load_spec(ctx, spec, GOLDEN_SEED)?;
    if !scene.has_light() {
        scene.add_default_light();
    }
    let on_gpu = SceneOnGpu::upload(&ctx.gpu.device, &scene)?;
    let aovs: Vec<Aov> = AOV_CHANNELS.iter().map(|(a, _)| *a).collect();
    let frames =
        crate::render_aovs(&ctx.gpu.device, &scene, &on_gpu, (settings.width, settings.height), &aovs, 1.0 / 24.0)?;
    drop(on_gpu);
    let device = ctx.device_key();
    let mut figures = Vec::new();
    let mut missing = Vec::new();
    let mut all_exact = true;
    for ((aov, tolerance), (_, frame)) in AOV_CHANNELS.iter().zip(&frames) {
        let channel = aov.name();
        let local = format!("actual-{channel}.exr");
        let bytes = golden::encode_exr(frame, &ctx.dir.join(&local))?;
        let golden_name = file_name(&format!("{name}-{channel}"), "exr");
        report.bless.push((golden_name.clone(), local));
        let Some(reference) = ctx.goldens.read(&golden_name)? else {
            missing.push(golden_name);
            continue;
        };
        let entry = ctx.goldens.entries.get(&format!("{name}-{channel}")).cloned().unwrap_or_default();
        if entry.device == device && reference == bytes {
            continue;
        }
        all_exact = false;
        let reference = golden::decode_exr(&reference).with_context(|| format!("golden {golden_name}"))?;
        if (reference.width, reference.height) != (frame.width, frame.height) {
            bail!(
                "{golden_name} is {}x{}, the render {}x{}",
                reference.width,
                reference.height,
                frame.width,
                frame.height
            );
        }
        let mut errors = Vec::new();
        let mut coverage_differs = 0usize;
        for (a, b) in frame.pixels.iter().zip(&reference.pixels) {
            if (a[3] > 0.5) != (b[3] > 0.5) {
                coverage_differs += 1;
            } else if a[3] > 0.5 {
                errors.push((0..3).map(|c| f64::from((a[c] - b[c]).abs())).fold(0.0, f64::max));
            }
        }
        errors.sort_by(f64::total_cmp);
        let p99 = errors.get(errors.len().saturating_sub(1) * 99 / 100).copied().unwrap_or(0.0);
        let share = coverage_differs as f64 / frame.pixels.len() as f64;
        figures.push(Figure::at_most(&format!("{channel}: 99th percentile |Δ|"), p99, *tolerance, ""));
        figures.push(Figure::at_most(
            &format!("{channel}: pixels whose coverage differs"),
            share,
            AOV_COVERAGE_SHARE,
            "of the image",
        ));
    }
    if !missing.is_empty() {
        report.verdict = Some(Status::Missing);
        report.message = format!(
            "no golden {} in {} (make them: strata check --bless --cases '^{name}$')",
            missing.join(", "),
            ctx.goldens.describe()
        );
        return Ok(());
    }
    if all_exact {
        report.verdict = Some(Status::Pass);
        report.tier = Some("bit-identical".into());
        report.message = "every channel bit-identical to its golden".into();
        return Ok(());
    }
    judge_figures(report, figures);
    report.tier = Some("numeric".into());
    Ok(())
}

fn determinism_case(spec: &SceneSpec, ctx: &CaseContext<'_>, report: &mut CaseReport) -> Result<()> {
    let (scene, settings, path) = load_spec(ctx, spec, GOLDEN_SEED)?;
    let first = render_on(ctx, &scene, &settings, &FrameOptions::default())?;
    let second = render_on(ctx, &scene, &settings, &FrameOptions::default())?;
    let differing = first
        .linear
        .pixels
        .iter()
        .zip(&second.linear.pixels)
        .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
        .count();
    write_png(&ctx.dir, "first.png", &display_image(&first))?;
    write_png(&ctx.dir, "second.png", &display_image(&second))?;
    report.images = vec![("first render".into(), "first.png".into()), ("second render".into(), "second.png".into())];
    judge_figures(report, vec![Figure::at_most("pixels that differ between two renders", differing as f64, 0.0, "px")]);
    report.tier = Some("bit-identical".into());
    if differing > 0 {
        report.message = format!("nondeterministic: {differing} pixels differ between two renders in one process");
    }
    report.reproduce = render_command(ctx, spec, &path, &ctx.dir.join("again.png"));
    Ok(())
}

/// The one-pixel shift of an image: every row moves right by a pixel, the first column repeats.
fn shifted(image: &Rgba8) -> Rgba8 {
    let mut out = image.clone();
    let w = image.width as usize;
    for row in out.pixels.chunks_exact_mut(w * 4) {
        let copy = row.to_vec();
        row[4..].copy_from_slice(&copy[..(w - 1) * 4]);
    }
    out
}

/// The linear radiance written as 8-bit without the sRGB transfer curve (what writing linear values into an
/// sRGB-encoded image without encoding them does): the picture darkens.
fn without_srgb_curve(frame: &RenderedFrame, exposure: f32) -> Rgba8 {
    let scale = exposure.exp2();
    let pixels = frame
        .linear
        .pixels
        .iter()
        .flat_map(|p| {
            let c = |v: f32| ((v * scale).clamp(0.0, 1.0) * 255.0).round() as u8;
            [c(p[0]), c(p[1]), c(p[2]), 255]
        })
        .collect();
    Rgba8 { width: frame.linear.width, height: frame.linear.height, pixels }
}

fn canary_case(golden_case: &str, breakage: Breakage, ctx: &CaseContext<'_>, report: &mut CaseReport) -> Result<()> {
    let spec = golden_spec(golden_case).with_context(|| format!("a canary breaks a golden case, not {golden_case}"))?;
    let (scene, settings, _) = load_spec(ctx, &spec, GOLDEN_SEED)?;
    let sabotage = Sabotage {
        no_shadow_rays: breakage == Breakage::NoShadowRays,
        flipped_normals: breakage == Breakage::FlippedNormals,
    };
    let frame = render_on(ctx, &scene, &settings, &FrameOptions { sabotage, ..Default::default() })?;
    let broken = match breakage {
        Breakage::OnePixelShift => shifted(&display_image(&frame)),
        Breakage::WrongSrgbCurve => without_srgb_curve(&frame, settings.exposure),
        Breakage::NoShadowRays | Breakage::FlippedNormals => display_image(&frame),
    };
    let judgement = judge_image(ctx, golden_case, &broken)?;
    report.figures = judgement.figures;
    report.images = judgement.images;
    report.tier = judgement.tier;
    (report.verdict, report.message) = match judgement.verdict {
        Status::Fail => (Some(Status::Pass), format!("the broken render failed its comparison, as it must: {}", judgement.message)),
        Status::Pass => (
            Some(Status::Fail),
            format!("the broken render PASSED its comparison against {golden_case}: the suite cannot see this breakage ({})", judgement.message),
        ),
        other => (Some(other), judgement.message),
    };
    Ok(())
}

fn test_case(behaviour: TestBehaviour, ctx: &CaseContext<'_>, report: &mut CaseReport) -> Result<()> {
    match behaviour {
        TestBehaviour::Pass => judge_figures(report, vec![Figure::new("one", 1.0, 1.0, 0.0, "")]),
        TestBehaviour::Fail => judge_figures(report, vec![Figure::new("two plus two", 5.0, 4.0, 0.5, "")]),
        TestBehaviour::Crash => std::process::abort(),
        TestBehaviour::Hang => loop {
            std::thread::sleep(std::time::Duration::from_secs(3600));
        },
        TestBehaviour::Flaky => {
            let figure = Figure::new("attempt", f64::from(ctx.attempt), 2.0, 0.0, "");
            judge_figures(report, vec![figure]);
        }
        TestBehaviour::ValidationError => {
            // A buffer of size 0 (VUID-VkBufferCreateInfo-size-00912), destroyed at once.
            let info = ash::vk::BufferCreateInfo::default().size(0).usage(ash::vk::BufferUsageFlags::STORAGE_BUFFER);
            let device = &ctx.gpu.device.raw;
            // SAFETY: the handle, if any, is destroyed before the device; the call itself is the invalid usage.
            if let Ok(buffer) = unsafe { device.create_buffer(&info, None) } {
                unsafe { device.destroy_buffer(buffer, None) };
            }
            judge_figures(report, vec![Figure::new("one", 1.0, 1.0, 0.0, "")]);
        }
    }
    Ok(())
}
