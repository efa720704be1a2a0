//! `strata merge`: parts of one frame (from `--samples`, `--shard` or `--checkpoint`) into the frame, or into a
//! bigger part.
use super::args::MergeArgs;
use anyhow::{anyhow, bail, Result};
use strata::output::OutputFormat;
use strata::partial::file::write_part;
use strata::partial::merge::merge_parts;
use strata::render::resolve::{resolve_sums, DisplayLook};
use strata::vk::{Gpu, GpuOptions};

pub fn merge(args: MergeArgs) -> Result<()> {
    let started = std::time::Instant::now();
    let format = OutputFormat::from_path(&args.output)?;
    if args.partial && format != OutputFormat::Exr {
        bail!("{}: --partial writes a part, an .exr", args.output.display());
    }
    if let Some(exr) = &args.exr {
        if args.partial || OutputFormat::from_path(exr)? != OutputFormat::Exr {
            bail!("--exr {}: the linear frame goes to an .exr, and a --partial merge has none", exr.display());
        }
    }
    // Parts, output and --exr compared as files (./a.exr, an absolute path, a link): nothing read is
    // overwritten, nothing written is removed.
    let mut plan = strata::write_plan::WritePlan::new();
    for part in &args.parts {
        if args.remove_parts {
            plan.reads_then_removes("the part", part);
        } else {
            plan.reads("the part", part);
        }
    }
    plan.writes("-o", &args.output)?;
    if let Some(exr) = &args.exr {
        plan.writes("--exr", exr)?;
    }
    plan.check(&|_, _| false)?;
    let merged = merge_parts(&args.parts, !args.partial)?;
    let sums = &merged.sums;
    if args.partial {
        write_part(&args.output, &merged)?;
    } else {
        // The resolve runs on the GPU, as at the end of a render, so the bytes are the ones a render makes.
        let gpu = Gpu::new(&GpuOptions {
            validation: args.gpu.validate,
            echo_messages: args.gpu.validate,
            device: args.gpu.device.clone(),
            needs: strata::vk::DeviceNeeds::RayTracing,
        })?;
        let log = gpu.validation_log();
        // The resolve's division may round differently on another device: the bytes are the render's only on its own.
        let here = &gpu.device.report.name;
        if !merged.provenance.device.starts_with(here.as_str()) {
            eprintln!(
                "warning: the parts were rendered on {}; resolving them on {here} may differ from that device's \
                 render in the last bits (--device chooses)",
                merged.provenance.device
            );
        }
        let look = DisplayLook {
            exposure: merged.look.exposure,
            tone_map: merged.look.tone_map,
            transparent: merged.look.transparent,
        };
        let resolved = resolve_sums(&gpu.device, sums, look, merged.look.auto_exposure)?;
        drop(gpu);
        if args.gpu.validate {
            log.check().map_err(|report| anyhow!("{report}"))?;
        }
        // Both files written in full before either is put in place: a failed --exr leaves no PNG behind.
        let mut staged = vec![match format {
            OutputFormat::Png => {
                strata::output::stage_png_rgba8(&args.output, sums.width, sums.height, &resolved.display)?
            }
            OutputFormat::Exr => strata::output::stage_frame_with_layers(&args.output, &resolved.linear, &[])?,
        }];
        if let Some(exr) = &args.exr {
            staged.push(strata::output::stage_frame_with_layers(exr, &resolved.linear, &[])?);
        }
        strata::output::commit_all(staged)?;
    }
    if args.remove_parts {
        for part in &args.parts {
            std::fs::remove_file(part).map_err(|e| anyhow!("{}: removing the part: {e}", part.display()))?;
        }
    }
    if !args.quiet {
        eprintln!(
            "strata: merged {} parts ({} of {} samples, {}x{}) into {} in {:.2} s",
            args.parts.len(),
            sums.samples.len(),
            sums.spp,
            sums.width,
            sums.height,
            args.output.display(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
