//! The reports a run leaves in `--out`: `results.csv` (every case), `failures.csv` (every case that did not pass,
//! itself a valid expectations baseline), `results.json` (everything), `summary.md` (also appended to
//! `$GITHUB_STEP_SUMMARY` when set), `report.html` ([`super::html`]) and, when asked, JUnit XML
//! ([`super::junit`]).
use super::expectations::csv_field;
use super::runner::{CaseResult, RunSummary};
use super::Status;
use anyhow::{Context as _, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The reports written in `--out`, in the order [`write_all`] writes them.
pub const REPORT_FILES: [&str; 5] = ["results.csv", "failures.csv", "results.json", "summary.md", "report.html"];

/// Writes every report; returns the paths written.
pub fn write_all(summary: &RunSummary, out: &Path, junit: Option<&Path>) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    let mut write = |name: &Path, text: &str| -> Result<()> {
        crate::output::write_atomic(name, |f| {
            use std::io::Write as _;
            f.write_all(text.as_bytes()).map_err(Into::into)
        })?;
        written.push(name.to_path_buf());
        Ok(())
    };
    let [results, failures, json, summary_md, html] = REPORT_FILES;
    write(&out.join(results), &results_csv(summary))?;
    write(&out.join(failures), &failures_csv(summary))?;
    write(&out.join(json), &serde_json::to_string_pretty(summary).context("results.json")?)?;
    let markdown = markdown(summary);
    write(&out.join(summary_md), &markdown)?;
    write(&out.join(html), &super::html::page(summary, out))?;
    if let Some(path) = junit {
        write(path, &super::junit::xml(summary))?;
    }
    if let Some(step_summary) = std::env::var_os("GITHUB_STEP_SUMMARY").filter(|s| !s.is_empty()) {
        use std::io::Write as _;
        let mut f =
            std::fs::OpenOptions::new().create(true).append(true).open(&step_summary).with_context(|| {
                format!("opening $GITHUB_STEP_SUMMARY ({})", PathBuf::from(&step_summary).display())
            })?;
        f.write_all(markdown.as_bytes())?;
    }
    Ok(written)
}

pub fn results_csv(summary: &RunSummary) -> String {
    let mut text = String::from("case,status,seconds,tier,message\n");
    for r in &summary.results {
        let _ = writeln!(
            text,
            "{},{},{:.2},{},{}",
            csv_field(&r.case),
            r.status,
            r.report.seconds,
            csv_field(r.report.tier.as_deref().unwrap_or("")),
            csv_field(&r.report.message)
        );
    }
    text
}

/// Every case that did not pass, as `case,status,reason`: what an expectations baseline for this device holds.
/// A case that failed as expected keeps its expected status and reason; an unexpected pass is left out.
pub fn failures_csv(summary: &RunSummary) -> String {
    let mut text = String::from("case,status,reason\n");
    for r in &summary.results {
        let (status, reason) = match r.status {
            Status::Pass | Status::UnexpectedPass | Status::Skip => continue,
            Status::ExpectedFail => match &r.expected {
                Some((s, reason, _)) => (*s, reason.clone()),
                None => (r.raw, r.report.message.clone()),
            },
            other => (other, r.report.message.clone()),
        };
        let reason = if reason.trim().is_empty() { format!("{status} in an earlier run") } else { reason };
        let _ = writeln!(text, "{},{},{}", csv_field(&r.case), status, csv_field(&reason));
    }
    text
}

/// One line per status with a count, in `Status::ALL` order.
pub fn markdown(summary: &RunSummary) -> String {
    let e = &summary.environment;
    let verdict = if summary.unexpected().next().is_none() { "passed" } else { "FAILED" };
    let mut text = format!(
        "## strata check {verdict}\n\n{} on **{}** ({} {}, Vulkan {}), validation layer {}, strata {}, --trace {}: {} \
         in {:.0} s.\n\n",
        summary.results.len(),
        e.device,
        e.driver,
        e.driver_info,
        e.vulkan_api,
        e.validation_layer,
        e.strata_version,
        e.trace,
        summary.counts(),
        summary.seconds
    );
    let problems: Vec<&CaseResult> = summary.unexpected().collect();
    if !problems.is_empty() {
        text.push_str("| case | status | why | reproduce |\n| --- | --- | --- | --- |\n");
        for r in problems {
            let _ = writeln!(
                text,
                "| `{}` | {} | {} | `{}` |",
                r.case,
                r.status,
                r.report.message.replace('|', "\\|"),
                r.report.reproduce.replace('|', "\\|")
            );
        }
        text.push('\n');
    }
    for note in &summary.unused_allows {
        let _ = writeln!(text, "- {note}");
    }
    text
}

/// The console's line for one result.
pub fn console_line(done: usize, total: usize, r: &CaseResult) -> String {
    let width = total.to_string().len();
    let tier = r.report.tier.as_deref().map(|t| format!(" ({t})")).unwrap_or_default();
    let mut line = format!("[{done:>width$}/{total}] {:<34} {}{tier} {:.1} s", r.case, r.status, r.report.seconds);
    if r.status != Status::Pass {
        let _ = write!(line, "\n        {}", r.report.message);
        if r.status.is_unexpected() && !r.report.reproduce.is_empty() {
            let _ = write!(line, "\n        reproduce: {}", r.report.reproduce);
        }
    }
    line
}
