//! Running the `strata` binary from a test: a command with the scheduler variables cleared (so a test machine
//! inside a Slurm or Kubernetes job does not steer `--shard auto`), its outcome in words, and scratch directories.
use std::path::PathBuf;
use std::process::{Command, Output};

/// Cleared from every run.
pub const SCHEDULER_VARIABLES: [&str; 6] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_STEP",
    "SLURM_ARRAY_TASK_COUNT",
    "JOB_COMPLETION_INDEX",
    "AWS_BATCH_JOB_ARRAY_INDEX",
];

/// `strata ARGS...`, not yet started.
pub fn command<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_strata"));
    command.args(args);
    for name in SCHEDULER_VARIABLES {
        command.env_remove(name);
    }
    command
}

/// `strata ARGS...`, run to its end.
pub fn strata<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    command(args).output().expect("run strata")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// How a run ended and what it said: the exit status names a signal where stderr may hold nothing.
pub fn outcome(o: &Output) -> String {
    format!("{}; stderr:\n{}", o.status, stderr(o))
}

/// An empty directory of this test's own, under the system's temporary directory.
pub fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("strata-test-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The repository's file at `relative` (scenes, test data).
pub fn repo_file(relative: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(relative)
}
