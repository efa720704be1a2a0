//! The `strata` command line: its arguments and dispatch; each command lives in `cli/`.
mod cli;

use clap::{Parser, Subcommand};
use cli::args::{BenchArgs, CheckArgs, InfoArgs, MergeArgs, RenderArgs};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "strata",
    version,
    about = "A headless Vulkan renderer: distributed ray tracing on any ray-tracing Vulkan device, validated on lavapipe",
    long_about = "strata renders glTF 2.0 scenes without a window through raw Vulkan and writes PNG or OpenEXR.\n\
                  It needs a Vulkan 1.3 device with acceleration structures and VK_KHR_ray_query or\n\
                  VK_KHR_ray_tracing_pipeline (either way traces; --trace chooses): on a machine without a GPU,\n\
                  run scripts/setup.sh to install Mesa's lavapipe. `strata info` shows what it finds.",
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
                            sub-pixel jitter, then the accumulation pass casts shadow, gloss and translucency rays \
                            (with ray queries, or through a ray-tracing pipeline: --trace). The output format follows the extension of -o (.png or .exr); files are \
                            written atomically, so a failed or interrupted render (Ctrl-C) leaves nothing behind (--checkpoint keeps the samples so far, and the same command goes on from them).\n\n\
                            Examples:\n  strata render scenes/showcase.toml -o showcase.png\n  \
                            strata render scenes/dof.toml -o dof.png --spp 64 --aperture 0.05 --focus 3\n  \
                            strata render scenes/motion.toml -o motion.exr --shutter 0:0.5 --sampler multi-jittered\n  \
                            strata render scenes/cornell.toml -o cornell.png --spp 256 --sampler sobol --indirect\n  \
                            strata render Box.gltf -o box.png --size 512x512 --json --quiet --validate\n  \
                            strata render scenes/showcase.toml -o part.exr --spp 1024 --shard auto --checkpoint ck.exr \
                            # a Slurm array task (docs/scale-out.md)")]
    Render(Box<RenderArgs>),
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
    /// Run the render check suite for driver, layer and renderer CI: closed-form optics, golden images (exact,
    /// then perceptual), G-buffer channels, determinism and canaries, each case in its own process under the
    /// validation layer; exits non-zero on any unexpected result.
    #[command(after_help = "Reports go to --out: results.csv, failures.csv (a baseline for --expectations), \
                            results.json, summary.md and report.html (every failing case with its pictures, \
                            figures and the command that reproduces it). docs/check.md explains the cases, the \
                            expectations file and how to add a case and regenerate goldens.\n\n\
                            Exit status: 0 when every result was expected, 1 otherwise.\n\n\
                            Examples:\n  strata check --junit report.xml\n  strata check --quick\n  \
                            strata check --device nvidia --trace pipeline --expectations nvidia.toml\n  \
                            strata check --fraction 2/4 --out shard-2\n  \
                            strata check --bless --cases '^golden/'   # after an intended change of the pictures")]
    Check(CheckArgs),
    /// Merge parts of one frame, rendered anywhere (`strata render --samples A..B`, `--shard K/N`, or a
    /// checkpoint), into the frame: byte for byte what one render of every sample writes.
    #[command(after_help = "The parts must come from one render (the same scene, settings, seed, strata version and \
                      device: each part's header says) and hold every sample of the frame exactly once; otherwise \
                      the error names the gap, the overlap or the part that differs, and nothing is written. \
                      docs/scale-out.md shows Slurm and Kubernetes set-ups.\n\n\
                      Examples:\n  strata render scenes/showcase.toml -o a.exr --samples 0..32\n  \
                      strata render scenes/showcase.toml -o b.exr --samples 32..64\n  \
                      strata merge a.exr b.exr -o showcase.png\n  \
                      strata merge parts/*.exr -o frame.exr --remove-parts")]
    Merge(MergeArgs),
}

fn main() -> ExitCode {
    strata::fatal_signals::report_fatal_signals();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => cli::render::render(*args),
        Command::Info(args) => cli::info::info(args),
        Command::Bench(args) => cli::bench::bench(args),
        Command::Merge(args) => cli::merge::merge(args),
        Command::Check(args) => match cli::check::check(args) {
            Ok(true) => Ok(()),
            Ok(false) => return ExitCode::FAILURE,
            Err(e) => Err(e),
        },
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<strata::render::frame::Interrupted>().is_some() => {
            if cli::render::terminated() {
                // 128 + SIGTERM, what a shell reports for a process SIGTERM ended.
                eprintln!("strata: stopped by SIGTERM; nothing was written (--checkpoint keeps the samples so far)");
                return ExitCode::from(143);
            }
            eprintln!("strata: interrupted; nothing was written");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
