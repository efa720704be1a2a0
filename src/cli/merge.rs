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
    strata::output::check_output_directory(&args.output)?;
    if args.partial && format != OutputFormat::Exr {
        bail!("{}: --partial writes a part, an .exr", args.output.display());
    }
    if let Some(exr) = &args.exr {
        if args.partial || OutputFormat::from_path(exr)? != OutputFormat::Exr {
            bail!("--exr {}: the linear frame goes to an .exr, and a --partial merge has none", exr.display());
        }
        strata::output::check_output_directory(exr)?;
    }
    if let Some(p) = args.parts.iter().find(|p| **p == args.output || Some(*p) == args.exr.as_ref()) {
        bail!("{}: the output would overwrite one of the parts", p.display());
    }
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
        match format {
            OutputFormat::Png => {
                strata::output::write_png_rgba8(&args.output, sums.width, sums.height, &resolved.display)?
            }
            OutputFormat::Exr => strata::output::write_frame(&args.output, &resolved.linear)?,
        }
        if let Some(exr) = &args.exr {
            strata::output::write_frame(exr, &resolved.linear)?;
        }
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
