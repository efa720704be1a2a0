//! `strata check`: the render check suite (strata::check), its console output and exit status.
use super::args::CheckArgs;
use anyhow::{anyhow, Context as _, Result};
use strata::check::{expectations::Expectations, report, runner};

/// Runs the suite (or, with `--child`, one case of it). Ok(true) when nothing unexpected happened.
pub fn check(args: CheckArgs) -> Result<bool> {
    if let Some(case) = &args.child {
        runner::run_child(&runner::ChildOptions {
            case: case.clone(),
            out: args.out.clone(),
            attempt: args.attempt,
            trace: args.trace,
            device: args.device.clone(),
            goldens: args.goldens.clone(),
            calibrate: args.calibrate,
        })?;
        return Ok(true);
    }
    let cases = match &args.cases {
        Some(text) => Some(regex::Regex::new(text).map_err(|e| {
            anyhow!(
                "--cases {:?} is not a valid regular expression: {}",
                strata::input::excerpt(text, 80),
                strata::check::expectations::regex_error(&e)
            )
        })?),
        None => None,
    };
    let expectations = match &args.expectations {
        Some(path) => Expectations::load(path)?,
        None => Expectations::default(),
    };
    let options = runner::RunOptions {
        program: std::env::current_exe().context("finding the strata binary to run the cases with")?,
        device: args.device.clone(),
        trace: args.trace,
        out: args.out.clone(),
        cases,
        expectations,
        jobs: args.jobs as usize,
        fraction: args.fraction.unwrap_or((1, 1)),
        quick: args.quick,
        bless: args.bless,
        calibrate: args.calibrate,
        timeout: std::time::Duration::from_secs(args.timeout),
        include_test_cases: args.test_cases,
        goldens: args.goldens.clone(),
    };
    if args.list {
        let mut text = String::new();
        for c in runner::select_cases(&options) {
            text.push_str(&format!("{:<34} {}{}\n", c.name, c.about, if c.quick { " (quick)" } else { "" }));
        }
        super::print_stdout(&text);
        return Ok(true);
    }
    // Every report's place checked before the first case runs: an unwritable --junit found after a 30 s suite
    // loses the run.
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let mut plan = strata::write_plan::WritePlan::new();
    for name in report::REPORT_FILES {
        plan.writes("a report", &args.out.join(name))?;
    }
    if let Some(junit) = &args.junit {
        plan.writes("--junit", junit)?;
    }
    if let Some(expectations) = &args.expectations {
        plan.reads("--expectations", expectations);
    }
    plan.check(&|_, _| false)?;
    eprintln!(
        "strata check: {} case(s), each in its own process under the validation layer; reports in {}",
        runner::select_cases(&options).len(),
        args.out.display()
    );
    let summary =
        runner::run(&options, &mut |done, total, result| eprintln!("{}", report::console_line(done, total, result)))?;
    let written = report::write_all(&summary, &args.out, args.junit.as_deref())?;
    let e = &summary.environment;
    eprintln!(
        "strata check on {} ({} {}): {} in {:.0} s",
        e.device,
        e.driver,
        e.driver_info,
        summary.counts(),
        summary.seconds
    );
    for note in &summary.unused_allows {
        eprintln!("note: {note}");
    }
    for g in &summary.goldens_written {
        eprintln!("wrote golden {g}");
    }
    let html = written.iter().find(|p| p.extension().is_some_and(|x| x == "html"));
    if let Some(html) = html {
        eprintln!("report: {}", html.display());
    }
    let unexpected: Vec<&str> = summary.unexpected().map(|r| r.case.as_str()).collect();
    if !unexpected.is_empty() {
        eprintln!("unexpected: {}", unexpected.join(", "));
    }
    Ok(unexpected.is_empty())
}
