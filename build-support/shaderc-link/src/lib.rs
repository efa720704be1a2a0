//! Nothing to call: this crate exists for its build script, which tells the linker to pull in the static
//! glslang and SPIRV-Tools archives that Debian's `libshaderc_combined.a` does not contain (see
//! `shared/notes/lavapipe.md`). A build dependency nobody references is not linked, so the parent build script
//! calls [`linked`].

/// Returns true; calling it makes the parent build script reference this crate so its link lines apply.
pub fn linked() -> bool {
    true
}
