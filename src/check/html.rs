//! `report.html`: one self-contained page (pictures inlined as data URIs) a driver developer can open from a CI
//! artifact: the device, every case's status, and for each case that did not pass its reference, actual and
//! ꟻLIP pictures, its figures, its validation messages and the one command that reproduces it.
use super::junit::escape;
use super::runner::{case_dir, CaseResult, RunSummary};
use super::Status;
use base64::Engine as _;
use std::fmt::Write as _;
use std::path::Path;

const STYLE: &str = "body{font:14px/1.45 system-ui,sans-serif;margin:2em;color:#222;max-width:1200px}\
h1{font-size:1.4em}h2{font-size:1.15em;margin-top:2em}table{border-collapse:collapse;margin:.5em 0}\
td,th{border:1px solid #ccc;padding:.25em .6em;text-align:left;vertical-align:top}\
.Pass{color:#17692b}.Fail,.Crash,.Timeout,.Flake,.UnexpectedPass,.Missing{color:#b3121b;font-weight:600}\
.ExpectedFail,.Skip{color:#8a6d00}code,pre{background:#f4f4f4;padding:.1em .3em;white-space:pre-wrap}\
figure{display:inline-block;margin:.5em 1em .5em 0}img{image-rendering:pixelated;width:256px;border:1px solid #999}\
figcaption{font-size:.9em;color:#555}";

fn status_cell(status: Status) -> String {
    format!("<span class=\"{status}\">{status}</span>")
}

/// A picture of the case's directory as an `<img>` with a data URI (nothing when it cannot be read).
fn picture(dir: &Path, label: &str, file: &str) -> String {
    match std::fs::read(dir.join(file)) {
        Ok(bytes) => format!(
            "<figure><img alt=\"{label}\" src=\"data:image/png;base64,{}\"><figcaption>{label}</figcaption></figure>",
            base64::engine::general_purpose::STANDARD.encode(bytes),
            label = escape(label)
        ),
        Err(_) => String::new(),
    }
}

fn case_section(out: &Path, r: &CaseResult) -> String {
    let mut s = format!(
        "<h2 id=\"{id}\">{name} — {status}</h2>\n<p>{about}</p>\n<p>{message}</p>\n",
        id = escape(&r.case),
        name = escape(&r.case),
        status = status_cell(r.status),
        about = escape(&r.about),
        message = escape(&r.report.message)
    );
    if let Some((expected, reason, at)) = &r.expected {
        let _ = writeln!(s, "<p>Expected {expected} ({}: {})</p>", escape(at), escape(reason));
    }
    let dir = case_dir(out, &r.case);
    let pictures: String = r.report.images.iter().map(|(label, file)| picture(&dir, label, file)).collect();
    if !pictures.is_empty() {
        let _ = writeln!(s, "<div>{pictures}</div>");
    }
    if !r.report.figures.is_empty() {
        s.push_str("<table><tr><th>figure</th><th>measured</th><th>expected</th><th></th></tr>\n");
        for f in &r.report.figures {
            let unit = escape(&f.unit);
            // An error measure (expected 0) reads as a limit; anything else as a value and its tolerance.
            let expected = if f.expected == 0.0 {
                format!("at most {:.6} {unit}", f.tolerance)
            } else {
                format!("{:.6} ± {:.6} {unit}", f.expected, f.tolerance)
            };
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td>{:.6} {unit}</td><td>{expected}</td><td>{}</td></tr>",
                escape(&f.name),
                f.measured,
                if f.passes() { status_cell(Status::Pass) } else { status_cell(Status::Fail) },
            );
        }
        s.push_str("</table>\n");
    }
    if !r.report.validation.is_empty() {
        s.push_str("<table><tr><th>validation message</th><th>count</th><th>first text</th></tr>\n");
        for v in &r.report.validation {
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
                escape(&v.id),
                v.count,
                escape(&v.first_text)
            );
        }
        s.push_str("</table>\n");
    }
    if !r.report.reproduce.is_empty() {
        let _ = writeln!(s, "<p>Reproduce:</p><pre>{}</pre>", escape(&r.report.reproduce));
    }
    let _ = writeln!(s, "<p>Files: <code>{}</code></p>", escape(&dir.display().to_string()));
    s
}

pub fn page(summary: &RunSummary, out: &Path) -> String {
    let e = &summary.environment;
    let unexpected = summary.unexpected().count();
    let verdict = if unexpected == 0 { "passed" } else { "failed" };
    let mut s = format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>strata check {verdict}: {device}</title>\
         <style>{STYLE}</style></head><body>\n<h1>strata check {verdict}: {n} cases on {device}</h1>\n",
        device = escape(&e.device),
        n = summary.results.len()
    );
    let _ = writeln!(
        s,
        "<table><tr><th>device</th><td>{} ({})</td></tr><tr><th>driver</th><td>{} {}</td></tr>\
         <tr><th>Vulkan</th><td>API {}, loader {}</td></tr><tr><th>validation layer</th><td>{}</td></tr>\
         <tr><th>strata</th><td>{} (--trace {})</td></tr><tr><th>goldens</th><td>{}</td></tr>\
         <tr><th>result</th><td>{} in {:.0} s</td></tr></table>",
        escape(&e.device),
        escape(&e.device_type),
        escape(&e.driver),
        escape(&e.driver_info),
        escape(&e.vulkan_api),
        escape(&e.loader),
        escape(&e.validation_layer),
        escape(&e.strata_version),
        escape(&e.trace),
        escape(&e.goldens),
        escape(&summary.counts()),
        summary.seconds
    );
    for note in &summary.unused_allows {
        let _ = writeln!(s, "<p class=\"Flake\">{}</p>", escape(note));
    }
    s.push_str("<table><tr><th>case</th><th>status</th><th>decided by</th><th>seconds</th><th>why</th></tr>\n");
    for r in &summary.results {
        let name = if r.status == Status::Pass {
            escape(&r.case)
        } else {
            format!("<a href=\"#{id}\">{id}</a>", id = escape(&r.case))
        };
        let _ = writeln!(
            s,
            "<tr><td>{name}</td><td>{}</td><td>{}</td><td>{:.1}</td><td>{}</td></tr>",
            status_cell(r.status),
            escape(r.report.tier.as_deref().unwrap_or("")),
            r.report.seconds,
            escape(&r.report.message)
        );
    }
    s.push_str("</table>\n");
    for r in summary.results.iter().filter(|r| r.status != Status::Pass) {
        s.push_str(&case_section(out, r));
    }
    s.push_str("</body></html>\n");
    s
}
