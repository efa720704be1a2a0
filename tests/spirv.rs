//! Every embedded shader's SPIR-V passes `spirv-val` for the Vulkan 1.3 environment strata targets.
use std::process::Command;

#[test]
fn every_shader_passes_spirv_val() {
    assert!(!strata::shaders::ALL.is_empty(), "build.rs embedded no shaders");
    let dir = std::env::temp_dir().join(format!("strata-spirv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut failures = Vec::new();
    for (name, bytes) in strata::shaders::ALL {
        assert_eq!(&bytes[..4], &0x0723_0203u32.to_le_bytes(), "{name}: no SPIR-V magic number");
        let path = dir.join(format!("{name}.spv"));
        std::fs::write(&path, bytes).unwrap();
        if let Err(e) = spirv_val(&path) {
            failures.push(format!("{name}: {e}"));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "spirv-val rejected:\n{}", failures.join("\n"));
}

/// The accumulation shaders as pipelines take them (`spirv_specialize`): for every combination of the seven
/// flags that `AccumulatePass` passes, the module has no specialization constant left, is smaller, and passes
/// `spirv-val`. The raygen shader's pixel-runs flag alternates over the combinations of the other six.
#[test]
fn every_specialization_of_the_accumulation_shaders_passes_spirv_val() {
    use strata::vk::spirv_specialize::specialize;
    let dir = std::env::temp_dir().join(format!("strata-specialized-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shaders =
        [("accumulate.comp", strata::shaders::ACCUMULATE_COMP), ("accumulate.rgen", strata::shaders::ACCUMULATE_RGEN)];
    let mut jobs = Vec::new();
    for (name, bytes) in shaders {
        let words = strata::vk::pipeline::spirv_words(name, bytes).unwrap();
        for bits in 0..64u32 {
            let flag = |k: u32| (bits >> k) & 1;
            let pixel_runs = if name.ends_with(".comp") { 0 } else { bits.count_ones() & 1 };
            let constants = [flag(0), flag(1), pixel_runs, flag(2), flag(3), flag(4), flag(5)];
            let specialized =
                specialize(&words, &constants).unwrap_or_else(|| panic!("{name} {constants:?}: not specialized"));
            assert!(specialized.len() < words.len(), "{name} {constants:?}: no smaller");
            let opcodes = instruction_opcodes(&specialized);
            assert!(
                !opcodes.iter().any(|op| (48..=52).contains(op)),
                "{name} {constants:?}: a specialization constant is left"
            );
            let path = dir.join(format!("{name}-{bits}.spv"));
            std::fs::write(&path, specialized.iter().flat_map(|w| w.to_le_bytes()).collect::<Vec<u8>>()).unwrap();
            jobs.push((format!("{name} {constants:?}"), path));
        }
    }
    // Two validators at a time.
    let failures: Vec<String> = std::thread::scope(|scope| {
        let halves: Vec<_> = jobs
            .chunks(jobs.len().div_ceil(2))
            .map(|half| {
                scope.spawn(move || {
                    half.iter()
                        .filter_map(|(what, path)| spirv_val(path).err().map(|e| format!("{what}: {e}")))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        halves.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "spirv-val rejected {} of {}:\n{}", failures.len(), jobs.len(), failures.join("\n"));
}

fn instruction_opcodes(words: &[u32]) -> Vec<u32> {
    let mut opcodes = Vec::new();
    let mut i = 5;
    while i < words.len() {
        opcodes.push(words[i] & 0xffff);
        i += (words[i] >> 16).max(1) as usize;
    }
    opcodes
}

fn spirv_val(path: &std::path::Path) -> Result<(), String> {
    let output = Command::new("spirv-val")
        .args(["--target-env", "vulkan1.3", "--scalar-block-layout"])
        .arg(path)
        .output()
        .unwrap_or_else(|e| {
            panic!("cannot run spirv-val ({e}); run `sudo scripts/setup.sh` (it installs spirv-tools)")
        });
    if output.status.success() {
        Ok(())
    } else {
        Err(format!("{}{}", String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr)))
    }
}
