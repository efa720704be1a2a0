//! Writes the project's own scenes into `scenes/` (or the directory given): `cargo run --example make_scenes`.
fn main() -> anyhow::Result<()> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/scenes").to_string());
    for (name, scene) in strata::scene::library::all() {
        let path = std::path::Path::new(&dir).join(format!("{name}.gltf"));
        strata::scene::gltf_export::write_gltf(&scene, &path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
