//! `strata info`: the Vulkan devices, what they support, and whether strata can use them.
use super::args::InfoArgs;
use super::print_stdout;
use anyhow::{bail, Context as _, Result};

pub fn info(args: InfoArgs) -> Result<()> {
    if let Some(path) = &args.scene {
        return scene_info(path);
    }
    let mut text = String::new();
    macro_rules! out {
        ($($arg:tt)*) => {{
            use std::fmt::Write as _;
            let _ = writeln!(text, $($arg)*);
        }};
    }
    let loader = strata::vk::instance::loader_info()?;
    out!("Vulkan loader: {}", strata::vk::instance::version_string(loader.loader_version));
    match &loader.validation_layer {
        Some(layer) => out!("Validation layer: {layer}"),
        None => out!("Validation layer: not installed (run scripts/setup.sh for vulkan-validationlayers)"),
    }
    print_stdout(&text);
    text.clear();
    let instance = strata::vk::instance::Instance::new(&strata::vk::instance::InstanceOptions {
        validation: args.validate && loader.validation_layer.is_some(),
        echo_messages: args.validate,
    })
    .context("creating a Vulkan instance")?;
    let reports = strata::vk::device::enumerate_devices(&instance)?;
    if reports.is_empty() {
        print_stdout(&text);
        bail!("no Vulkan devices found; run scripts/setup.sh to install Mesa's lavapipe");
    }
    let chosen = strata::vk::device::select_device(&reports, None, strata::vk::DeviceNeeds::RayTracing).ok();
    let yes_no =
        |has: bool, lacks: &[String]| if has { "yes".to_string() } else { format!("no (lacks {})", lacks.join(", ")) };
    out!("Devices:");
    for r in &reports {
        let marker = if Some(r.index) == chosen { " (default)" } else { "" };
        out!("  [{}] {}{marker}", r.index, r.name);
        out!("      type:      {}", r.type_name());
        out!("      driver:    {} {}", r.driver_name, r.driver_info);
        out!("      Vulkan:    {}", r.api_version_string());
        out!("      ray query: {} (--trace query)", yes_no(r.ray_query, &r.missing_for_query));
        out!("      pipeline:  {} (--trace pipeline)", yes_no(r.ray_tracing_pipeline, &r.missing_for_pipeline));
        if r.qualifies() {
            let auto = if r.ray_query { "query" } else { "pipeline" };
            out!("      strata:    usable; --trace auto takes {auto}");
        } else {
            out!("      strata:    not usable, {}", r.status());
        }
    }
    print_stdout(&text);
    if chosen.is_none() {
        bail!(
            "no device can run strata (it needs ray queries or ray-tracing pipelines); run scripts/setup.sh to \
             install Mesa's lavapipe, which has both"
        );
    }
    Ok(())
}

/// `strata info SCENE`: what the file holds, every animation clip included (the file as loaded before one clip is
/// chosen to play).
fn scene_info(path: &std::path::Path) -> Result<()> {
    use std::fmt::Write as _;
    let is_toml = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    let scene = if is_toml {
        strata::scene::scene_file::load_scene_file(path, None)?.scene
    } else {
        strata::scene::gltf_import::load_gltf(path, &Default::default())?
    };
    let mut text = String::new();
    let _ = writeln!(text, "{}:", path.display());
    let _ = writeln!(
        text,
        "  {} meshes, {} instances, {} triangles; {} materials, {} textures",
        scene.meshes.len(),
        scene.instances.len(),
        scene.triangle_count(),
        scene.materials.len(),
        scene.textures.len()
    );
    let names = |names: Vec<&str>| if names.is_empty() { "none".to_string() } else { names.join(", ") };
    let _ = writeln!(text, "  cameras: {}", names(scene.cameras.iter().map(|c| c.name.as_str()).collect()));
    let _ = writeln!(text, "  lights: {}", names(scene.lights.iter().map(|l| l.name.as_str()).collect()));
    if !scene.skins.is_empty() {
        let skins: Vec<String> = scene
            .skins
            .iter()
            .enumerate()
            .map(|(k, skin)| {
                let nodes: Vec<&str> =
                    scene.nodes.iter().filter(|n| n.skin == Some(k)).map(|n| n.name.as_str()).collect();
                format!("\"{}\" ({} joints; skins {})", skin.name, skin.joints.len(), names(nodes))
            })
            .collect();
        let _ = writeln!(text, "  skins (applied at every sample's time): {}", skins.join(", "));
    }
    if scene.animations.is_empty() {
        let _ = writeln!(text, "  animation clips: none");
    } else {
        let _ = writeln!(text, "  animation clips (--animation NAME|INDEX; the first plays unless one is named):");
        for (i, clip) in scene.animations.iter().enumerate() {
            let (duration, channels) = (clip.duration(), clip.channels.len());
            let weights = clip.channels.iter().filter(|c| c.property == strata::scene::Property::Weights).count();
            let morph = if weights > 0 { format!(" ({weights} of them morph weights)") } else { String::new() };
            let plural = if channels == 1 { "" } else { "s" };
            let _ = writeln!(text, "    [{i}] \"{}\": {duration:.3} s, {channels} channel{plural}{morph}", clip.name);
        }
    }
    if !scene.variants.is_empty() {
        let _ = writeln!(text, "  material variants (--variant NAME): {}", scene.variants.join(", "));
    }
    for warning in &scene.warnings {
        let _ = writeln!(text, "  warning: {warning}");
    }
    print_stdout(&text);
    Ok(())
}
