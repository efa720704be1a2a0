//! `strata check` as a CI system runs it: the binary, its exit status and the reports it leaves. The suite's
//! hidden test cases (`--test-cases`: pass, fail, crash, hang, flaky, a validation error) stand in for a broken
//! driver; the canaries show the comparisons can fail; goldens are blessed into temporary directories, never into
//! the repository's.
use crate::common;
use common::cli::{stderr, strata, temp_dir};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo_goldens() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("check/goldens")
}

/// A copy of the repository's goldens to change.
fn goldens_copy(tag: &str) -> PathBuf {
    let dir = temp_dir(tag);
    for entry in std::fs::read_dir(repo_goldens()).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, dir.join(path.file_name().unwrap())).unwrap();
    }
    dir
}

/// Runs `strata check` with `args` into a fresh report directory; returns the run, that directory and each
/// case's (status, tier, message) from results.json.
fn check(tag: &str, args: &[&str]) -> (Output, PathBuf, HashMap<String, (String, String, String)>) {
    let out = temp_dir(tag);
    let mut all = vec!["check", "--out", out.to_str().unwrap()];
    all.extend_from_slice(args);
    let run = strata(&all);
    let results = match std::fs::read(out.join("results.json")) {
        Ok(bytes) => {
            let json: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
            json["results"]
                .as_array()
                .unwrap()
                .iter()
                .map(|r| {
                    let text = |v: &serde_json::Value| v.as_str().unwrap_or_default().to_string();
                    (text(&r["case"]), (text(&r["status"]), text(&r["report"]["tier"]), text(&r["report"]["message"])))
                })
                .collect()
        }
        Err(_) => HashMap::new(),
    };
    (run, out, results)
}

fn status<'a>(results: &'a HashMap<String, (String, String, String)>, case: &str) -> &'a str {
    results.get(case).map(|r| r.0.as_str()).unwrap_or_else(|| panic!("no result for {case}: {results:?}"))
}

#[test]
fn every_canary_breaks_its_render_and_fails_its_comparison() {
    let (run, _, results) = check("canaries", &["--cases", "^canary/"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(results.len(), 4, "{results:?}");
    for (case, (status, tier, message)) in &results {
        assert_eq!(status, "Pass", "{case}: {message}");
        assert_eq!(tier, "perceptual", "{case}: decided by {tier}");
        assert!(
            message.contains("failed its comparison") && message.contains("beyond the thresholds"),
            "{case}: {message}"
        );
    }
    // With thresholds no picture can exceed, the suite cannot see the breakage: every canary then fails the run.
    let blind = goldens_copy("blind-goldens");
    let meta: String = std::fs::read_to_string(blind.join("goldens.toml"))
        .unwrap()
        .lines()
        .map(|l| match l.split(" = ").next() {
            Some(key @ ("flip_mean" | "flip_p99")) => format!("{key} = 1.0\n"),
            _ => format!("{l}\n"),
        })
        .collect();
    std::fs::write(blind.join("goldens.toml"), meta).unwrap();
    let (run, _, results) = check("canaries-blind", &["--cases", "^canary/", "--goldens", blind.to_str().unwrap()]);
    assert!(!run.status.success(), "blind thresholds must fail the run");
    for (case, (status, _, message)) in &results {
        assert_eq!(status, "Fail", "{case}: {message}");
        assert!(message.contains("cannot see this breakage"), "{case}: {message}");
    }
}

#[test]
fn a_crash_a_hang_and_a_flake_are_their_own_statuses_and_the_other_cases_still_run() {
    let (run, out, results) =
        check("crash", &["--test-cases", "--cases", "^(test/crash|test/flaky|test/pass|golden/cornell)$"]);
    assert!(!run.status.success(), "a crash fails the run");
    assert_eq!(run.status.code(), Some(1));
    assert_eq!(status(&results, "test/crash"), "Crash");
    assert!(results["test/crash"].2.contains("SIGABRT"), "{:?}", results["test/crash"]);
    assert_eq!(status(&results, "test/flaky"), "Flake");
    assert!(results["test/flaky"].2.contains("passed on the re-run"), "{:?}", results["test/flaky"]);
    assert_eq!(status(&results, "test/pass"), "Pass");
    assert_eq!(status(&results, "golden/cornell"), "Pass");
    // The crash's output is kept, its abort named by strata's own handler with its call stack (as a driver's crash
    // is), and the flake's first attempt.
    let crash_log = std::fs::read_to_string(out.join("cases/test-crash/log-1.txt")).unwrap();
    assert!(crash_log.contains("strata: crashed with SIGABRT"), "{crash_log}");
    assert!(crash_log.contains("the call stack, innermost first"), "{crash_log}");
    assert!(out.join("cases/test-flaky/attempt-1.json").is_file());
    let failures = std::fs::read_to_string(out.join("failures.csv")).unwrap();
    for case in ["test/crash,Crash", "test/flaky,Flake"] {
        assert!(failures.contains(case), "{failures}");
    }
    // A short timeout of its own (a real case's first run may compile shaders for longer).
    let (run, _, results) = check("hang", &["--test-cases", "--cases", "^test/hang$", "--timeout", "2"]);
    assert!(!run.status.success());
    assert_eq!(status(&results, "test/hang"), "Timeout");
    assert!(results["test/hang"].2.contains("killed after 2 s"), "{:?}", results["test/hang"]);
}

#[test]
fn expectations_turn_known_failures_into_expected_ones_and_catch_unexpected_passes() {
    let dir = temp_dir("expectations");
    let file = dir.join("llvmpipe.toml");
    std::fs::write(
        &file,
        "# known on lavapipe\n[[expect]]\ncase = \"test/fail\"\nstatus = \"Fail\"\nreason = \"the suite's own failing case\"\n\
         device = \"llvmpipe\"\n\n[[expect]]\ncase = \"test/(hang|other)\"\nstatus = \"Skip\"\nreason = \"not run\"\n\n\
         [[allow]]\nid = \"VUID-VkBufferCreateInfo-size-00912\"\nreason = \"the suite's own invalid buffer\"\n\n\
         [[allow]]\nid = \"VUID-never-reported\"\nreason = \"stale\"\n",
    )
    .unwrap();
    let cases = ["--cases", "^test/(fail|pass|validation-error|hang)$", "--test-cases"];
    let (run, out, results) = check("expected", &[&cases[..], &["--expectations", file.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(status(&results, "test/fail"), "ExpectedFail");
    assert_eq!(status(&results, "test/hang"), "Skip", "a Skip entry is not run");
    assert_eq!(status(&results, "test/pass"), "Pass");
    assert_eq!(status(&results, "test/validation-error"), "Pass", "an allowed message fails nothing");
    assert!(stderr(&run).contains("VUID-never-reported"), "an allowed message that never came is reported");
    assert!(std::fs::read_to_string(out.join("summary.md")).unwrap().contains("VUID-never-reported"));

    // Without the allow entry the message fails its case, with its id, count and text.
    let (run, _, results) = check("validation", &["--cases", "^test/validation-error$", "--test-cases"]);
    assert!(!run.status.success());
    let (s, _, message) = &results["test/validation-error"];
    assert_eq!(s, "Fail");
    assert!(message.contains("VUID-VkBufferCreateInfo-size-00912 ×1"), "{message}");

    // A listed case that passes is an unexpected pass, and fails the run.
    std::fs::write(&file, "[[expect]]\ncase = \"test/pass\"\nstatus = \"Fail\"\nreason = \"was broken\"\n").unwrap();
    let pass_only = ["--cases", "^test/pass$", "--test-cases", "--expectations", file.to_str().unwrap()];
    let (run, _, results) = check("unexpected-pass", &pass_only);
    assert!(!run.status.success());
    assert_eq!(status(&results, "test/pass"), "UnexpectedPass");

    // A malformed file is a clear error naming file and line, before anything runs.
    std::fs::write(&file, "[[expect]]\ncase = \"test/pass\"\nstatus = \"Sometimes\"\nreason = \"r\"\n").unwrap();
    let (run, out, _) = check("malformed", &pass_only);
    assert_eq!(run.status.code(), Some(1));
    let text = stderr(&run);
    assert!(text.contains(&format!("{}:1", file.display())) && text.contains("Sometimes"), "{text}");
    assert!(!out.join("results.csv").exists(), "nothing ran");
}

#[test]
fn a_runs_failures_csv_is_a_baseline_for_the_next_run() {
    let cases = ["--test-cases", "--cases", "^test/(fail|crash|pass)$"];
    let (run, out, _) = check("baseline-1", &cases);
    assert!(!run.status.success());
    let baseline = out.join("failures.csv");
    let (run, _, results) =
        check("baseline-2", &[&cases[..], &["--expectations", baseline.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(status(&results, "test/fail"), "ExpectedFail");
    assert_eq!(status(&results, "test/crash"), "ExpectedFail");
    assert_eq!(status(&results, "test/pass"), "Pass");
}

#[test]
fn the_junit_report_parses_back_with_the_device_and_every_status() {
    let dir = temp_dir("junit-expect");
    let file = dir.join("e.toml");
    std::fs::write(&file, "[[expect]]\ncase = \"test/fail\"\nstatus = \"Fail\"\nreason = \"known\"\n").unwrap();
    let junit = dir.join("report.xml");
    let (run, _, _) = check(
        "junit",
        &[
            "--test-cases",
            "--cases",
            "^test/(fail|crash|pass|validation-error)$",
            "--expectations",
            file.to_str().unwrap(),
            "--junit",
            junit.to_str().unwrap(),
        ],
    );
    assert!(!run.status.success());
    let text = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("not XML: {e}\n{text}"));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "testsuites");
    let suites: Vec<_> = root.children().filter(|n| n.is_element()).collect();
    assert_eq!(suites.len(), 1);
    let suite = suites[0];
    assert_eq!(suite.tag_name().name(), "testsuite");
    let attr = |n: roxmltree::Node, a: &str| n.attribute(a).unwrap_or_else(|| panic!("{a} missing")).to_string();
    assert_eq!(attr(suite, "tests"), "4");
    assert_eq!(
        (attr(suite, "failures"), attr(suite, "errors"), attr(suite, "skipped")),
        ("1".into(), "1".into(), "1".into())
    );
    assert!(attr(suite, "time").parse::<f64>().unwrap() > 0.0);
    let properties: HashMap<String, String> = suite
        .descendants()
        .filter(|n| n.has_tag_name("property"))
        .map(|n| (attr(n, "name"), attr(n, "value")))
        .collect();
    for key in ["device", "driver", "driver_info", "vulkan_api", "validation_layer", "strata_version"] {
        assert!(properties.get(key).is_some_and(|v| !v.is_empty()), "property {key}: {properties:?}");
    }
    assert!(properties["device"].contains("llvmpipe"));
    let cases: HashMap<String, roxmltree::Node> =
        suite.children().filter(|n| n.has_tag_name("testcase")).map(|n| (attr(n, "name"), n)).collect();
    assert_eq!(cases.len(), 4);
    let child = |case: &str| cases[case].children().find(|n| n.is_element()).map(|n| n.tag_name().name().to_string());
    assert_eq!(child("test/pass"), None);
    assert_eq!(child("test/fail").as_deref(), Some("skipped"), "an expected failure is skipped");
    assert_eq!(child("test/crash").as_deref(), Some("error"));
    assert_eq!(child("test/validation-error").as_deref(), Some("failure"));
    let failure = cases["test/validation-error"].children().find(|n| n.has_tag_name("failure")).unwrap();
    assert!(attr(failure, "message").contains("VUID-VkBufferCreateInfo-size-00912"));
    for (_, n) in cases {
        assert!(n.attribute("classname").is_some_and(|c| c.starts_with("strata.check.")));
        assert!(attr(n, "time").parse::<f64>().is_ok());
    }
}

#[test]
fn bless_then_a_plain_run_passes_bit_identical_and_a_missing_golden_is_never_made_silently() {
    let goldens = temp_dir("bless-goldens");
    let g = goldens.to_str().unwrap();
    let cases = ["--cases", "^(golden/cornell|aov/cornell|canary/normals-flipped)$", "--goldens", g];
    let (run, _, results) = check("bless-missing", &cases);
    assert!(!run.status.success());
    for case in ["golden/cornell", "aov/cornell", "canary/normals-flipped"] {
        assert_eq!(status(&results, case), "Missing", "{case}");
    }
    assert_eq!(std::fs::read_dir(&goldens).unwrap().count(), 0, "nothing is created without --bless");

    let (run, _, _) = check("bless", &[&cases[..], &["--bless"]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(goldens.join("golden-cornell.png").is_file() && goldens.join("aov-cornell-normal.exr").is_file());
    let (run, _, results) = check("bless-plain", &cases);
    assert!(run.status.success(), "{}", stderr(&run));
    for case in ["golden/cornell", "aov/cornell"] {
        assert_eq!(results[case].0, "Pass", "{case}");
        assert_eq!(results[case].1, "bit-identical", "{case}");
    }
    // Blessing again keeps the old file.
    let (run, _, _) = check("bless-again", &[&cases[..], &["--bless"]].concat());
    assert!(run.status.success());
    assert!(goldens.join("golden-cornell.png.old").is_file());
}

#[test]
fn a_golden_changed_by_one_pixel_fails_the_exact_tier_and_passes_the_perceptual_one() {
    // Blessed here, so that this device made it whatever CPU lavapipe runs on.
    let goldens = temp_dir("one-pixel-goldens");
    let g = goldens.to_str().unwrap();
    let (run, _, _) = check("one-pixel-bless", &["--cases", "^golden/cornell$", "--goldens", g, "--bless"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let path = goldens.join("golden-cornell.png");
    let mut image = image::open(&path).unwrap().to_rgba8();
    let p = image.get_pixel_mut(32, 32);
    p[0] = p[0].wrapping_add(40);
    image.save(&path).unwrap();
    let (run, _, results) = check("one-pixel", &["--cases", "^golden/cornell$", "--goldens", g]);
    assert!(run.status.success(), "{}", stderr(&run));
    let (s, tier, message) = &results["golden/cornell"];
    assert_eq!((s.as_str(), tier.as_str()), ("Pass", "perceptual"), "{message}");
    assert!(message.contains("not bit-identical") && message.contains("within the thresholds"), "{message}");
}

#[test]
fn the_summary_goes_to_github_step_summary_when_it_is_set() {
    let out = temp_dir("step-summary");
    let summary = out.join("step-summary.md");
    std::fs::write(&summary, "earlier steps\n").unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_strata"))
        .args(["check", "--test-cases", "--cases", "^test/(pass|fail)$", "--out"])
        .arg(out.join("report"))
        .env("GITHUB_STEP_SUMMARY", &summary)
        .output()
        .unwrap();
    assert!(!run.status.success());
    let text = std::fs::read_to_string(&summary).unwrap();
    assert!(text.starts_with("earlier steps\n"), "appended, not replaced: {text}");
    assert!(text.contains("## strata check FAILED") && text.contains("`test/fail` | Fail"), "{text}");
    assert!(text.contains("strata check --cases '^test/fail$'"), "the reproduce command: {text}");
}
