// Emits static link lines for glslang + SPIRV-Tools, for the archives this distribution ships. Order matters
// for static archives: users before providers. glslang 14+ folded OGLCompiler and OSDependent into glslang,
// so only the archives that exist are linked.
use std::path::Path;

const ARCHIVES: [&str; 8] = [
    "glslang",
    "MachineIndependent",
    "OSDependent",
    "GenericCodeGen",
    "OGLCompiler",
    "SPIRV",
    "SPIRV-Tools-opt",
    "SPIRV-Tools",
];

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let dirs = ["/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib", "/usr/local/lib"];
    let Some(dir) = dirs.iter().find(|d| Path::new(d).join("libglslang.a").exists()) else {
        println!(
            "cargo:warning=no libglslang.a found in {dirs:?}: run scripts/setup.sh, or build with \
             --no-default-features --features shaderc-from-source"
        );
        return;
    };
    println!("cargo:rustc-link-search=native={dir}");
    for lib in ARCHIVES {
        if Path::new(dir).join(format!("lib{lib}.a")).exists() {
            println!("cargo:rustc-link-lib=static={lib}");
        }
    }
    println!("cargo:rustc-link-lib=dylib=stdc++");
}
