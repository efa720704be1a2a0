//! Every integration test, in one binary: each file under `tests/` is a module of it (`render_frames.rs` is
//! `render_frames::…`, `bad_input/` is `bad_input::…`), so a test's path reads as its file and name, and
//! `cargo test render_frames::` runs one file's tests. One binary, not one per file, because Cargo runs test
//! binaries one after another: each binary's slowest test ran alone at its end while the other cores idled, and
//! every binary linked the whole library again (docs/performance.md, "One binary for the tests").
//! `scripts/test-runner.sh` runs its tests one process each, as many at a time as there are CPUs.

mod common;

mod animation;
mod bad_input;
mod check;
mod cli;
mod contracts;
mod data_capture;
mod denoise;
mod dispersion;
mod distributed;
mod environment;
mod estimators;
mod fuzz_regressions;
mod gbuffer;
mod gltf_features;
mod gltf_samples;
mod layered_materials;
mod layering;
mod library_api;
mod noise_gpu;
mod output;
mod raster_readback;
mod ray_query;
mod render_colors;
mod render_frames;
mod sampling_gpu;
mod scale_out;
mod scene_file;
mod scenes;
mod spirv;
mod test_runner;
mod validation_harness;
