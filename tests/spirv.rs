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
        let output = Command::new("spirv-val")
            .args(["--target-env", "vulkan1.3", "--scalar-block-layout"])
            .arg(&path)
            .output()
            .unwrap_or_else(|e| {
                panic!("cannot run spirv-val ({e}); run `sudo scripts/setup.sh` (it installs spirv-tools)")
            });
        if !output.status.success() {
            failures.push(format!(
                "{name}: {}{}",
                String::from_utf8_lossy(&output.stdout),
                String::from_utf8_lossy(&output.stderr)
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "spirv-val rejected:\n{}", failures.join("\n"));
}
