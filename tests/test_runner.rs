//! `scripts/test-runner.sh`, Cargo's runner, on a stand-in test binary (a shell script that answers libtest's
//! `--list` and `--exact`): a test that crashes inside native code once runs once more and passes, one that
//! crashes twice fails, an assertion that fails is not run again, and every crash is printed at the end.
use crate::common::cli::temp_dir;
use std::path::Path;
use std::process::Command;

/// What the stand-in prints for a crash: the first lines of strata's signal handler's message.
const CRASH: &str = "printf '\\nstrata: crashed with SIGSEGV (inside the Vulkan driver or a layer)\\n\
    strata: in the thread \"main\", at the address 0x10; the call stack, innermost first:\\n\
    /usr/lib/libvulkan_lvp.so(+0x1234)[0x7f0000001234]\\n'; echo 'test result: FAILED. 0 passed; 1 failed'; exit 101";

#[test]
fn a_native_crash_runs_the_test_once_more_and_an_assertion_does_not() {
    let dir = temp_dir("runner");
    // The runner takes over only for binaries under a `deps` folder, as Cargo's test binaries are.
    let deps = dir.join("deps");
    std::fs::create_dir_all(&deps).unwrap();
    let state = dir.join("state");
    std::fs::create_dir_all(&state).unwrap();
    let fake = deps.join("suite-stand-in");
    let script = format!(
        r#"#!/usr/bin/env bash
if [[ $1 == --list ]]; then printf 'x::crashes_once: test\nx::crashes_twice: test\nx::fails: test\nx::passes: test\n'; exit 0; fi
name=$2
state={state}
echo "$name" >> "$state/runs"
pass() {{ echo "test $name ... ok"; echo 'test result: ok. 1 passed; 0 failed; 0 ignored; 0 measured; 3 filtered out'; exit 0; }}
case $name in
  x::crashes_once) if [[ -e $state/crashed ]]; then pass; else touch "$state/crashed"; {CRASH}; fi ;;
  x::crashes_twice) {CRASH} ;;
  x::fails) echo 'assertion failed: 1 == 2'; echo 'test result: FAILED. 0 passed; 1 failed'; exit 101 ;;
  x::passes) pass ;;
esac
"#,
        state = state.display()
    );
    std::fs::write(&fake, script).unwrap();
    std::fs::set_permissions(&fake, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let runner = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/test-runner.sh");
    let out = Command::new("bash")
        .arg(&runner)
        .arg(&fake)
        .env("STRATA_TEST_JOBS", "2")
        .output()
        .expect("run scripts/test-runner.sh");
    let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(101), "two tests fail, so the run does:\n{text}");
    let runs = std::fs::read_to_string(state.join("runs")).unwrap();
    let count = |name: &str| runs.lines().filter(|l| *l == name).count();
    assert_eq!(
        [count("x::crashes_once"), count("x::crashes_twice"), count("x::fails"), count("x::passes")],
        [2, 2, 1, 1],
        "how often each test ran:\n{runs}"
    );
    assert!(text.contains("test x::crashes_once ... ok on its second run"), "{text}");
    assert!(text.contains("test x::crashes_twice ... FAILED"), "{text}");
    assert!(text.contains("test x::fails ... FAILED"), "{text}");
    assert!(text.contains("test result: FAILED. 2 passed; 2 failed;"), "{text}");
    // The crashes come last, where a CI log's tail shows them: the first runs of both, the second of the one
    // that failed, each with its call stack.
    let tail = &text[text.rfind("failures:").expect("a failures list")..];
    for header in ["x::crashes_once, first run", "x::crashes_twice, first run", "x::crashes_twice, the run that failed"]
    {
        let at = tail.find(header).unwrap_or_else(|| panic!("no {header:?} after the failures:\n{text}"));
        assert!(tail[at..].contains("libvulkan_lvp.so(+0x1234)"), "{header}: no call stack:\n{text}");
    }
    assert!(!tail.contains("x::fails,"), "an assertion is no crash:\n{text}");
}
