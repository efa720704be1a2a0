//! `strata render`'s scale-out options: which share of the work this run makes (`--samples`, `--shard`), and
//! how a long render survives being stopped (`--checkpoint`, `--resume`). docs/scale-out.md has the picture.
use super::args::RenderArgs;
use super::sequence::FramePlan;
use anyhow::{anyhow, bail, Context as _, Result};
use std::path::{Path, PathBuf};
use strata::partial::file::{read_part, write_part, Part, PartLook};
use strata::partial::shard::Shard;
use strata::render::frame::{Checkpoint, Continuation, FrameOptions, RenderedFrame};

/// Exit status after SIGTERM with a checkpoint written (EX_TEMPFAIL: run the same command again).
pub const EXIT_TERMINATED: u8 = 75;

/// The shard `--shard` names, read from the scheduler for `auto`; None without `--shard`.
fn shard(args: &RenderArgs) -> Result<Option<(Shard, &'static str)>> {
    let Some(spec) = args.shard else { return Ok(None) };
    spec.resolve(&|name| std::env::var(name).ok()).map(Some)
}

/// Checks the scale-out options against the rest of the command line, before any work.
pub fn check_options(args: &RenderArgs, several_scenes: bool) -> Result<()> {
    let used = args.samples.is_some() || args.shard.is_some() || args.checkpoint.is_some() || args.resume.is_some();
    if !used {
        return Ok(());
    }
    if several_scenes {
        bail!("--samples, --shard, --checkpoint and --resume work on one scene at a time");
    }
    if args.preview {
        bail!("--preview makes one quick sample: it has nothing to split or checkpoint");
    }
    if args.samples.is_some() && args.shard.is_some() {
        bail!("--samples and --shard each choose this run's samples: give one of them");
    }
    for (flag, path) in [("--checkpoint", &args.checkpoint), ("--resume", &args.resume)] {
        if let Some(path) = path {
            if strata::output::OutputFormat::from_path(path)? != strata::output::OutputFormat::Exr {
                bail!("{flag} {}: checkpoints are parts, written as .exr", path.display());
            }
        }
    }
    // Whether the checkpoint is a file of its own is the write plan's to say (cli::render), as files, not strings.
    Ok(())
}

/// With `--shard` over a sequence (--frames, --turntable): this shard's frames. One frame stays as it is (its
/// samples are split instead: [`FramePart`]).
pub fn frames_of_shard(args: &RenderArgs, plans: Vec<FramePlan>) -> Result<Vec<FramePlan>> {
    if plans.len() == 1 {
        return Ok(plans);
    }
    if args.samples.is_some() {
        bail!("--samples splits one frame's samples; to split the frames of a sequence over runs use --shard K/N");
    }
    if args.checkpoint.is_some() || args.resume.is_some() {
        bail!(
            "--checkpoint and --resume keep one frame's samples; a sequence keeps every finished frame already \
             (after an interruption render the frames left with --frames A..B)"
        );
    }
    let Some((shard, by)) = shard(args)? else { return Ok(plans) };
    let (first, end) = shard.range(plans.len() as u32);
    if !args.quiet && first < end {
        eprintln!(
            "strata: shard {}/{} ({by}): frames {} to {} of {}",
            shard.index,
            shard.count,
            first + 1,
            end,
            plans.len()
        );
    }
    Ok(plans.into_iter().skip(first as usize).take((end - first) as usize).collect())
}

/// How this run makes its one frame: which samples, from which checkpoint, saved where.
pub struct FramePart {
    /// The samples this run's result holds when it is done.
    target: (u32, u32),
    /// Write a part for `strata merge` (--samples, --shard) instead of the frame.
    pub writes_part: bool,
    checkpoint: Option<PathBuf>,
    every: std::time::Duration,
    /// The part this run goes on from, read before any work.
    resume: Option<(PathBuf, Part)>,
    quiet: bool,
    /// Whether the last checkpoint write failed (then an interrupted run has not saved its samples).
    last_save_failed: std::cell::Cell<bool>,
}

impl FramePart {
    /// None when the run is a plain render of every sample.
    pub fn of(args: &RenderArgs, spp: u32, output: &Path) -> Result<Option<FramePart>> {
        let shard = shard(args)?;
        let target = match (args.samples, shard) {
            (Some((a, b)), _) => {
                if b > spp {
                    bail!("--samples {a}..{b}: the frame has {spp} samples (--spp), numbered 0 to {}", spp - 1);
                }
                (a, b)
            }
            (None, Some((shard, by))) => {
                let range = shard.range(spp);
                if range.0 == range.1 {
                    // More shards than samples: this one has none, as docs/scale-out.md says; not an error.
                    eprintln!(
                        "strata: shard {}/{} ({by}) has no samples: {} shards share the frame's {spp}; nothing to do",
                        shard.index, shard.count, shard.count
                    );
                } else if !args.quiet {
                    eprintln!(
                        "strata: shard {}/{} ({by}): samples {}..{} of {spp}",
                        shard.index, shard.count, range.0, range.1
                    );
                }
                range
            }
            (None, None) if args.checkpoint.is_none() && args.resume.is_none() => return Ok(None),
            (None, None) => (0, spp),
        };
        let writes_part = args.samples.is_some() || shard.is_some();
        if writes_part {
            if strata::output::OutputFormat::from_path(output)? != strata::output::OutputFormat::Exr {
                bail!(
                    "{}: a part of a frame (--samples, --shard) is written as an .exr for `strata merge`, which \
                     writes the .png",
                    output.display()
                );
            }
            if args.exr.is_some() || args.aov.is_some() {
                bail!(
                    "a part holds sums only: --exr and --aov go on the `strata merge` of the parts, or a full render"
                );
            }
        }
        // A checkpoint left by an earlier run of this command is where this one goes on from.
        // Read (and its header checked) before the device is made: a bad part costs nothing.
        let resume = match args.resume.clone().or_else(|| args.checkpoint.clone().filter(|c| c.is_file())) {
            Some(path) => {
                let part = read_part(&path).context(if args.resume.is_some() { "--resume" } else { "--checkpoint" })?;
                Some((path, part))
            }
            None => None,
        };
        Ok(Some(FramePart {
            target,
            writes_part,
            checkpoint: args.checkpoint.clone(),
            // Bounded by the option's parser (at most a day), so the conversion cannot overflow.
            every: std::time::Duration::from_secs_f32(args.checkpoint_every),
            resume,
            quiet: args.quiet,
            last_save_failed: std::cell::Cell::new(false),
        }))
    }

    /// Renders what is left of the target on top of the checkpoint, saving checkpoints as it goes. Returns the
    /// frame and, for a part, what to write.
    pub fn render(
        &self,
        gpu: &strata::vk::Gpu,
        scene: &strata::scene::Scene,
        on_gpu: &strata::render::SceneOnGpu,
        settings: &strata::scene::settings::RenderSettings,
        progress: &mut dyn FnMut(u32, u32) -> bool,
    ) -> Result<(RenderedFrame, Option<Part>)> {
        let provenance = strata::part_provenance(gpu, scene, settings)?;
        let backdrop = settings.backdrop_for(scene.environment.is_some());
        let look = PartLook {
            exposure: settings.exposure,
            tone_map: settings.tone_map,
            transparent: backdrop == strata::scene::settings::Backdrop::Transparent,
            auto_exposure: settings.auto_exposure,
        };
        let resumed = match &self.resume {
            Some((path, part)) => {
                if let Some((field, ours, theirs)) = provenance.difference(&part.provenance) {
                    bail!(
                        "{}: a checkpoint of another render (its {field} is {theirs}, this render's {ours}); remove \
                         it or choose another --checkpoint",
                        path.display()
                    );
                }
                if part.look != look {
                    bail!("{}: a checkpoint of a render with other display settings", path.display());
                }
                part.sums
                    .check_fits(settings.width, settings.height, settings.spp)
                    .with_context(|| path.display().to_string())?;
                Some(part)
            }
            None => None,
        };
        let remaining = match &resumed {
            Some(part) => {
                let left = part.sums.samples.remaining_of(self.target).with_context(|| {
                    format!(
                        "{}: cannot go on to samples {}..{}",
                        self.resume.as_ref().expect("resumed").0.display(),
                        self.target.0,
                        self.target.1
                    )
                })?;
                if !self.quiet {
                    eprintln!(
                        "strata: going on from {} ({} of {} samples done)",
                        self.resume.as_ref().expect("resumed").0.display(),
                        part.sums.samples.len(),
                        self.target.1 - self.target.0
                    );
                }
                left.unwrap_or((self.target.1, self.target.1))
            }
            None => self.target,
        };
        let options = FrameOptions { samples: Some(remaining), keep_sums: self.writes_part, ..Default::default() };
        // A checkpoint that cannot be written (a full disk) costs the protection, not the render: warn and go on.
        let mut save = |sums: &strata::partial::PartialSums| -> Result<()> {
            let path = self.checkpoint.as_ref().expect("only with --checkpoint");
            match write_part(path, &Part { provenance: provenance.clone(), look, sums: sums.clone() }) {
                Ok(()) => self.last_save_failed.set(false),
                Err(e) => {
                    eprintln!("warning: the checkpoint was not saved: {e:#}; the render goes on without it");
                    self.last_save_failed.set(true);
                }
            }
            Ok(())
        };
        let continuation = Continuation {
            resume: resumed.as_ref().map(|p| &p.sums),
            checkpoint: self.checkpoint.as_ref().map(|_| Checkpoint { every: self.every, save: &mut save }),
        };
        let rendered = strata::render::frame::render_samples(
            &gpu.device,
            scene,
            on_gpu,
            settings,
            &options,
            continuation,
            progress,
        )?;
        let part = match (&rendered.sums, self.writes_part) {
            (Some(sums), true) => Some(Part { provenance, look, sums: sums.clone() }),
            _ => None,
        };
        Ok((rendered, part))
    }

    /// The samples this run's result holds when it is done.
    pub fn target(&self) -> (u32, u32) {
        self.target
    }

    /// The checkpoint this run saves to, if any.
    pub fn checkpoint(&self) -> Option<&Path> {
        self.checkpoint.as_deref()
    }

    /// Whether the last checkpoint write failed.
    pub fn last_save_failed(&self) -> bool {
        self.last_save_failed.get()
    }

    /// A shard with no samples (more shards than samples): nothing to render or write.
    pub fn is_empty(&self) -> bool {
        self.target.0 == self.target.1
    }

    /// Once the output is written the checkpoint has served: removed, so that a later run starts afresh.
    pub fn finish(&self) -> Result<()> {
        if let Some(path) = &self.checkpoint {
            if path.is_file() {
                std::fs::remove_file(path).map_err(|e| anyhow!("{}: removing the checkpoint: {e}", path.display()))?;
            }
        }
        Ok(())
    }
}
