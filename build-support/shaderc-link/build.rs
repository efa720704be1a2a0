// Emits static link lines for glslang + SPIRV-Tools. Order matters for static archives: users before providers.
fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    for dir in ["/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib"] {
        if std::path::Path::new(dir).join("libglslang.a").exists() {
            println!("cargo:rustc-link-search=native={dir}");
        }
    }
    for lib in [
        "glslang",
        "MachineIndependent",
        "OSDependent",
        "GenericCodeGen",
        "OGLCompiler",
        "SPIRV",
        "SPIRV-Tools-opt",
        "SPIRV-Tools",
    ] {
        println!("cargo:rustc-link-lib=static={lib}");
    }
    println!("cargo:rustc-link-lib=dylib=stdc++");
}
