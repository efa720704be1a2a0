//! Checks whether the installed Khronos validation layer survives two validated instances used on two threads:
//! one thread creates and destroys instances and devices while another records labelled command buffers.
//! Layer 1.3.239 (Debian 12) does not: its state shared between instances is unlocked (Vulkan-ValidationLayers
//! #4391), and this died with SIGSEGV inside libVkLayer_khronos_validation.so in half of eight runs of 20–40 s
//! on a 2-core machine. That is why GPU tests take turns (`tests/common/mod.rs`); if this survives a newer layer, the turns can go.
//!
//! `cargo run --release --example validation_layer_race [SECONDS]` (default 40): exits 0 if the layer survived.
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use strata::vk::commands::{labelled, submit_and_wait};
use strata::vk::{DeviceNeeds, Gpu, GpuOptions};

fn validated_gpu() -> anyhow::Result<Gpu> {
    Gpu::new(&GpuOptions { validation: true, echo_messages: false, device: None, needs: DeviceNeeds::RasterOnly })
}

fn main() -> anyhow::Result<()> {
    let seconds: u64 = match std::env::args().nth(1) {
        Some(text) => text.parse().map_err(|_| anyhow::anyhow!("SECONDS must be a whole number, not {text:?}"))?,
        None => 40,
    };
    strata::fatal_signals::report_fatal_signals_with(
        "Two validated instances on two threads crashed the layer: GPU tests must keep taking turns.",
    );
    let stop = AtomicBool::new(false);
    let (instances, submissions) = std::thread::scope(|scope| -> anyhow::Result<(u64, u64)> {
        let churn = scope.spawn(|| -> anyhow::Result<u64> {
            let mut instances = 0;
            while !stop.load(Ordering::Relaxed) {
                drop(validated_gpu()?);
                instances += 1;
            }
            Ok(instances)
        });
        let recorded = (|| -> anyhow::Result<u64> {
            let gpu = validated_gpu()?;
            let start = Instant::now();
            let mut submissions = 0;
            while start.elapsed() < Duration::from_secs(seconds) {
                submit_and_wait(&gpu.device, "label churn", |cmd| {
                    for i in 0..20 {
                        labelled(&gpu.device, cmd, &format!("region {i}"), || ());
                    }
                    Ok(())
                })?;
                submissions += 1;
            }
            Ok(submissions)
        })();
        stop.store(true, Ordering::Relaxed);
        let instances = churn.join().expect("the churning thread panicked")?;
        Ok((instances, recorded?))
    })?;
    println!("survived {seconds} s: {instances} instances created and destroyed beside {submissions} submissions");
    Ok(())
}
