//! JUnit XML as common CI systems read it (the Ant/Jenkins `junit-10.xsd` shape: `testsuites` › `testsuite`
//! with `properties` › `testcase` with `failure`, `error` or `skipped`): the device, driver, Vulkan API, layer and
//! strata versions as properties; Fail, Flake, UnexpectedPass and Missing as failures, Crash and Timeout as
//! errors, ExpectedFail and Skip as skipped.
use super::runner::RunSummary;
use super::Status;
use std::fmt::Write as _;

/// Text safe inside XML attributes and elements: the five entities escaped, characters XML 1.0 forbids dropped.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' | '\n' | '\r' => out.push(c),
            c if (c as u32) < 0x20 || c == '\u{fffe}' || c == '\u{ffff}' => {}
            c => out.push(c),
        }
    }
    out
}

pub fn xml(summary: &RunSummary) -> String {
    let failures = summary
        .results
        .iter()
        .filter(|r| matches!(r.status, Status::Fail | Status::Flake | Status::UnexpectedPass | Status::Missing))
        .count();
    let errors = summary.results.iter().filter(|r| matches!(r.status, Status::Crash | Status::Timeout)).count();
    let skipped = summary.results.iter().filter(|r| matches!(r.status, Status::ExpectedFail | Status::Skip)).count();
    let tests = summary.results.len();
    let e = &summary.environment;
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let counts = format!(
        "tests=\"{tests}\" failures=\"{failures}\" errors=\"{errors}\" skipped=\"{skipped}\" time=\"{:.3}\"",
        summary.seconds
    );
    let _ = writeln!(x, "<testsuites name=\"strata check\" {counts}>");
    let _ = writeln!(x, "  <testsuite name=\"strata check on {}\" {counts}>", escape(&e.device));
    x.push_str("    <properties>\n");
    for (name, value) in [
        ("device", &e.device),
        ("device_type", &e.device_type),
        ("driver", &e.driver),
        ("driver_info", &e.driver_info),
        ("vulkan_api", &e.vulkan_api),
        ("vulkan_loader", &e.loader),
        ("validation_layer", &e.validation_layer),
        ("strata_version", &e.strata_version),
        ("trace", &e.trace),
        ("goldens", &e.goldens),
    ] {
        let _ = writeln!(x, "      <property name=\"{name}\" value=\"{}\"/>", escape(value));
    }
    x.push_str("    </properties>\n");
    for r in &summary.results {
        let classname = format!("strata.check.{}", r.kind);
        let _ = write!(
            x,
            "    <testcase name=\"{}\" classname=\"{}\" time=\"{:.3}\"",
            escape(&r.case),
            escape(&classname),
            r.report.seconds
        );
        let message = escape(&r.report.message);
        let body = {
            let mut b = String::new();
            for f in &r.report.figures {
                let _ = writeln!(b, "{f}");
            }
            for v in &r.report.validation {
                let _ = writeln!(b, "validation: {} x{}: {}", v.id, v.count, v.first_text);
            }
            if !r.report.reproduce.is_empty() {
                let _ = writeln!(b, "reproduce: {}", r.report.reproduce);
            }
            escape(&b)
        };
        let status = r.status;
        match status {
            Status::Pass => {
                x.push_str("/>\n");
                continue;
            }
            Status::Fail | Status::Flake | Status::UnexpectedPass | Status::Missing => {
                let _ = write!(x, ">\n      <failure type=\"{status}\" message=\"{message}\">{body}</failure>\n");
            }
            Status::Crash | Status::Timeout => {
                let _ = write!(x, ">\n      <error type=\"{status}\" message=\"{message}\">{body}</error>\n");
            }
            Status::ExpectedFail | Status::Skip => {
                let why = match &r.expected {
                    Some((s, reason, _)) => format!("{status} (expected {s}: {reason})"),
                    None => format!("{status}: {}", r.report.message),
                };
                let _ = write!(x, ">\n      <skipped message=\"{}\"/>\n", escape(&why));
            }
        }
        x.push_str("    </testcase>\n");
    }
    x.push_str("  </testsuite>\n</testsuites>\n");
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaping_keeps_xml_well_formed() {
        assert_eq!(escape("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;");
        assert_eq!(escape("bell\u{7}ok\n"), "bellok\n");
    }
}
