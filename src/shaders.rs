//! The SPIR-V of every shader in `shaders/`, compiled by `build.rs` and embedded in the binary.
include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// The numbers GLSL and Rust share, read from `shaders/include/shared_constants.glsl` (binding numbers, the
/// accumulation pass's tile size, its counters).
pub mod constants {
    include!(concat!(env!("OUT_DIR"), "/shared_constants.rs"));
}
