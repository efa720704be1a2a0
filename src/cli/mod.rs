//! The commands of the `strata` binary, one file each, and what they share.
pub mod args;
pub mod bench;
pub mod check;
pub mod info;
pub mod merge;
pub mod progress;
pub mod render;
pub mod scale_out;
pub mod sequence;
pub mod summary;

/// Prints to stdout; a closed pipe (`strata info | head`) is not an error.
pub fn print_stdout(text: &str) {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    let _ = stdout.write_all(text.as_bytes()).and_then(|_| stdout.flush());
}
