//! Expectations: what a device is known to do, so that a run fails only on what is new. A TOML file of
//! `[[expect]]` entries (a case, the status it is expected to end in, a required reason, and optionally the
//! devices it applies to) and `[[allow]]` entries (a validation message id the cases may provoke, with its
//! reason); or a `failures.csv` an earlier run wrote, which is a baseline as it stands (deqp-runner's way).
//!
//! ```toml
//! [[expect]]
//! case = "golden/showcase"           # a case name, or a regular expression matching whole names
//! status = "Fail"                    # Fail, Crash, Timeout, Flake, Missing or Skip (not run)
//! reason = "why it fails on this device"
//! device = "NVIDIA"                  # optional, each a case-insensitive part of what strata info shows:
//! driver = "NVIDIA"                  #   the device's name, its driver's name, its driver's version text
//! driver_info = "580."
//!
//! [[allow]]
//! id = "VUID-vkCmdTraceRaysKHR-None-08608"
//! reason = "why this message is not a bug of the driver under test"
//! ```
//! ```
use super::Status;
use anyhow::{anyhow, bail, Context as _, Result};
use regex::Regex;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// What an entry's device keys are matched against.
#[derive(Debug, Clone, Default)]
pub struct DeviceFacts {
    pub name: String,
    pub driver: String,
    pub driver_info: String,
}

/// Which devices an entry applies to: every key given must be part of the device's (case-insensitive).
#[derive(Debug, Clone, Default, Deserialize)]
pub struct DeviceFilter {
    #[serde(default)]
    pub device: Option<String>,
    #[serde(default)]
    pub driver: Option<String>,
    #[serde(default)]
    pub driver_info: Option<String>,
}

impl DeviceFilter {
    pub fn matches(&self, facts: &DeviceFacts) -> bool {
        let part = |key: &Option<String>, value: &str| {
            key.as_ref().is_none_or(|k| value.to_lowercase().contains(&k.to_lowercase()))
        };
        part(&self.device, &facts.name)
            && part(&self.driver, &facts.driver)
            && part(&self.driver_info, &facts.driver_info)
    }
}

/// One `[[expect]]` entry (or baseline line).
#[derive(Debug, Clone)]
pub struct Expect {
    pub case: String,
    pattern: CasePattern,
    pub status: Status,
    pub reason: String,
    pub devices: DeviceFilter,
    /// Where it was written: `file:line`.
    pub at: String,
}

/// One `[[allow]]` entry.
#[derive(Debug, Clone)]
pub struct Allow {
    pub id: String,
    pub reason: String,
    pub devices: DeviceFilter,
    pub at: String,
}

#[derive(Debug, Clone, Default)]
pub struct Expectations {
    pub path: Option<PathBuf>,
    pub expects: Vec<Expect>,
    pub allows: Vec<Allow>,
}

/// The statuses an entry may expect.
const EXPECTABLE: [Status; 6] =
    [Status::Fail, Status::Crash, Status::Timeout, Status::Flake, Status::Missing, Status::Skip];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileToml {
    #[serde(default)]
    expect: Vec<toml::Spanned<ExpectToml>>,
    #[serde(default)]
    allow: Vec<toml::Spanned<AllowToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExpectToml {
    case: String,
    status: String,
    reason: String,
    #[serde(flatten)]
    devices: DeviceFilter,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AllowToml {
    id: String,
    reason: String,
    #[serde(flatten)]
    devices: DeviceFilter,
}

/// The 1-based lines of byte offsets in a text: the line starts found once, then a binary search per offset
/// (counting from the start for each of 100,000 entries was quadratic).
struct Lines(Vec<usize>);

impl Lines {
    fn of(text: &str) -> Self {
        Self(text.bytes().enumerate().filter(|(_, b)| *b == b'\n').map(|(i, _)| i).collect())
    }

    fn line(&self, offset: usize) -> usize {
        self.0.partition_point(|&newline| newline < offset) + 1
    }
}

/// The 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    Lines::of(text).line(offset)
}

/// How an entry names its cases: a plain name matches itself (compared as text: a baseline of 100,000 names
/// compiles no regular expression), anything else is a whole-name regular expression.
#[derive(Debug, Clone)]
enum CasePattern {
    Exact(String),
    Regex(Regex),
}

impl CasePattern {
    fn is_match(&self, case: &str) -> bool {
        match self {
            CasePattern::Exact(name) => name == case,
            CasePattern::Regex(r) => r.is_match(case),
        }
    }
}

/// The most of a pattern or value a message quotes.
const QUOTED: usize = 80;

/// A regular expression's error in one line, without the pattern it repeats (which may be megabytes).
pub fn regex_error(e: &regex::Error) -> String {
    match e {
        regex::Error::Syntax(text) => {
            text.lines().rev().find(|l| l.starts_with("error:")).unwrap_or("a syntax error").to_string()
        }
        other => crate::input::excerpt(&other.to_string(), QUOTED),
    }
}

/// A case pattern: a whole-name regular expression (a plain name matches itself).
fn case_pattern(case: &str) -> Result<CasePattern> {
    if regex::escape(case) == case {
        return Ok(CasePattern::Exact(case.to_string()));
    }
    Regex::new(&format!("^(?:{case})$")).map(CasePattern::Regex).map_err(|e| {
        anyhow!("case {:?} is not a valid regular expression: {}", crate::input::excerpt(case, QUOTED), regex_error(&e))
    })
}

/// The largest expectations file read (a baseline of every case many times over).
pub const MAX_EXPECTATIONS_BYTES: u64 = 16 << 20;

fn expectable(word: &str) -> Result<Status> {
    match Status::parse(word) {
        Some(s) if EXPECTABLE.contains(&s) => Ok(s),
        _ => bail!("status {word:?} cannot be expected (use one of {})", EXPECTABLE.map(Status::name).join(", ")),
    }
}

impl Expectations {
    /// Reads a TOML expectations file, or a `.csv` baseline (`case,status,reason`).
    pub fn load(path: &Path) -> Result<Self> {
        // A regular file of bounded size: /dev/zero would be read for ever, a FIFO would block.
        let text = crate::input::read_text_bounded(path, MAX_EXPECTATIONS_BYTES, "an expectations file")?;
        let is_csv = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        let mut parsed = if is_csv { Self::parse_csv(&text, path)? } else { Self::parse_toml(&text, path)? };
        parsed.path = Some(path.to_path_buf());
        Ok(parsed)
    }

    pub fn parse_toml(text: &str, path: &Path) -> Result<Self> {
        let file = path.display();
        let raw: FileToml = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of(text, s.start)).unwrap_or(0);
            anyhow!("{file}:{line}: {}", e.message())
        })?;
        let mut out = Self::default();
        let lines = Lines::of(text);
        for entry in raw.expect {
            let at = format!("{file}:{}", lines.line(entry.span().start));
            let e = entry.into_inner();
            let status = expectable(&e.status).with_context(|| at.clone())?;
            if e.reason.trim().is_empty() {
                bail!("{at}: the expectation for {} needs a reason", e.case);
            }
            let pattern = case_pattern(&e.case).with_context(|| at.clone())?;
            out.expects.push(Expect { case: e.case, pattern, status, reason: e.reason, devices: e.devices, at });
        }
        for entry in raw.allow {
            let at = format!("{file}:{}", lines.line(entry.span().start));
            let a = entry.into_inner();
            if a.reason.trim().is_empty() {
                bail!("{at}: allowing {} needs a reason", a.id);
            }
            out.allows.push(Allow { id: a.id, reason: a.reason, devices: a.devices, at });
        }
        Ok(out)
    }

    /// A baseline: the `failures.csv` a run writes (`case,status,reason`, a header line, quoted fields).
    pub fn parse_csv(text: &str, path: &Path) -> Result<Self> {
        let mut out = Self::default();
        for (i, line) in text.lines().enumerate() {
            let at = format!("{}:{}", path.display(), i + 1);
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') || (i == 0 && line.starts_with("case,")) {
                continue;
            }
            let fields = split_csv_line(line).with_context(|| at.clone())?;
            let [case, status, reason] = fields.as_slice() else {
                bail!("{at}: expected case,status,reason, found {} field(s)", fields.len());
            };
            let status = expectable(status).with_context(|| at.clone())?;
            if reason.trim().is_empty() {
                bail!("{at}: the expectation for {case} needs a reason");
            }
            let pattern = CasePattern::Exact(case.clone());
            out.expects.push(Expect {
                case: case.clone(),
                pattern,
                status,
                reason: reason.clone(),
                devices: DeviceFilter::default(),
                at,
            });
        }
        Ok(out)
    }

    /// The first entry that expects something of `case` on this device.
    pub fn expected(&self, case: &str, device: &DeviceFacts) -> Option<&Expect> {
        self.expects.iter().find(|e| e.pattern.is_match(case) && e.devices.matches(device))
    }

    /// The entry that allows validation message `id` on this device.
    pub fn allowed(&self, id: &str, device: &DeviceFacts) -> Option<&Allow> {
        self.allows.iter().find(|a| a.id == id && a.devices.matches(device))
    }
}

/// The final status of a case that ended in `raw` (after its re-run), given what is expected of it.
pub fn apply(raw: Status, expected: Option<&Expect>) -> Status {
    let Some(e) = expected else { return raw };
    match raw {
        Status::Pass if e.status == Status::Flake => Status::Pass,
        Status::Pass => Status::UnexpectedPass,
        Status::Skip => Status::Skip,
        r if r == e.status || e.status == Status::Flake => Status::ExpectedFail,
        r => r,
    }
}

/// Splits one CSV line into fields ("quoted" fields may hold commas and doubled quotes).
pub fn split_csv_line(line: &str) -> Result<Vec<String>> {
    let mut fields = Vec::new();
    let mut chars = line.chars().peekable();
    loop {
        let mut field = String::new();
        if chars.peek() == Some(&'"') {
            chars.next();
            loop {
                match chars.next() {
                    Some('"') if chars.peek() == Some(&'"') => {
                        chars.next();
                        field.push('"');
                    }
                    Some('"') => break,
                    Some(c) => field.push(c),
                    None => bail!("a quoted field is not closed"),
                }
            }
            match chars.next() {
                None => {
                    fields.push(field);
                    return Ok(fields);
                }
                Some(',') => {}
                Some(c) => bail!("unexpected {c:?} after a quoted field"),
            }
        } else {
            loop {
                match chars.next() {
                    None => {
                        fields.push(field);
                        return Ok(fields);
                    }
                    Some(',') => break,
                    Some(c) => field.push(c),
                }
            }
        }
        fields.push(field);
    }
}

/// A CSV field, quoted when it must be.
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\"").replace('\n', " "))
    } else {
        text.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn facts(name: &str) -> DeviceFacts {
        DeviceFacts { name: name.into(), driver: "llvmpipe".into(), driver_info: "Mesa 25.0.7".into() }
    }

    #[test]
    fn entries_match_by_name_pattern_and_device() {
        let text = "[[expect]]\ncase = \"golden/.*\"\nstatus = \"Fail\"\nreason = \"r\"\ndevice = \"nvidia\"\n\n\
                    [[expect]]\ncase = \"optics/penumbra\"\nstatus = \"Crash\"\nreason = \"r2\"\n";
        let e = Expectations::parse_toml(text, Path::new("e.toml")).unwrap();
        assert!(e.expected("golden/cornell", &facts("NVIDIA H200")).is_some());
        assert!(e.expected("golden/cornell", &facts("llvmpipe")).is_none());
        assert!(e.expected("xgolden/cornell", &facts("NVIDIA H200")).is_none(), "patterns match whole names");
        assert_eq!(e.expected("optics/penumbra", &facts("llvmpipe")).unwrap().at, "e.toml:7");
    }

    #[test]
    fn a_malformed_file_names_its_line() {
        let missing_reason = "[[expect]]\ncase = \"a\"\nstatus = \"Fail\"\n";
        let err = Expectations::parse_toml(missing_reason, Path::new("x.toml")).unwrap_err().to_string();
        assert!(err.starts_with("x.toml:1:") && err.contains("reason"), "{err}");
        let bad_status = "\n\n[[expect]]\ncase = \"a\"\nstatus = \"Sometimes\"\nreason = \"r\"\n";
        let err = format!("{:#}", Expectations::parse_toml(bad_status, Path::new("x.toml")).unwrap_err());
        assert!(err.contains("x.toml:3") && err.contains("Sometimes"), "{err}");
        let unknown_key = "[[expect]]\ncase = \"a\"\nstatus = \"Fail\"\nreason = \"r\"\ncolour = \"blue\"\n";
        let err = Expectations::parse_toml(unknown_key, Path::new("x.toml")).unwrap_err().to_string();
        assert!(err.starts_with("x.toml:") && err.contains("colour"), "{err}");
        let syntax = "[[expect]]\ncase = \"a\nstatus = 1\n";
        let err = Expectations::parse_toml(syntax, Path::new("x.toml")).unwrap_err().to_string();
        assert!(err.starts_with("x.toml:2:"), "{err}");
    }

    #[test]
    fn statuses_follow_the_expectation() {
        let e = |status| Expect {
            case: "c".into(),
            pattern: case_pattern("c").unwrap(),
            status,
            reason: "r".into(),
            devices: DeviceFilter::default(),
            at: String::new(),
        };
        assert_eq!(apply(Status::Fail, Some(&e(Status::Fail))), Status::ExpectedFail);
        assert_eq!(apply(Status::Pass, Some(&e(Status::Fail))), Status::UnexpectedPass);
        assert_eq!(apply(Status::Crash, Some(&e(Status::Fail))), Status::Crash);
        assert_eq!(apply(Status::Fail, Some(&e(Status::Flake))), Status::ExpectedFail);
        assert_eq!(apply(Status::Pass, Some(&e(Status::Flake))), Status::Pass);
        assert_eq!(apply(Status::Fail, None), Status::Fail);
    }

    #[test]
    fn csv_baselines_round_trip_quoted_fields() {
        let line = format!("{},{},{}", csv_field("golden/a"), csv_field("Fail"), csv_field("FLIP mean 0.2, \"high\""));
        assert_eq!(split_csv_line(&line).unwrap(), ["golden/a", "Fail", "FLIP mean 0.2, \"high\""]);
        let text = format!("case,status,reason\n{line}\n");
        let e = Expectations::parse_csv(&text, Path::new("failures.csv")).unwrap();
        assert_eq!(e.expects[0].status, Status::Fail);
        assert!(e.expected("golden/a", &DeviceFacts::default()).is_some());
        let err = Expectations::parse_csv("case,status,reason\na,Fail\n", Path::new("f.csv")).unwrap_err();
        assert!(err.to_string().starts_with("f.csv:2:"), "{err}");
    }
}
