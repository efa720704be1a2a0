//! A white sphere in a white furnace (uniform environment of radiance 1, diffuse interreflection, 16 bounces), where no
//! surface may reflect more than 1: the mean radiance and its standard error over rings of the sphere's image, from the
//! centre (facing the camera) out to the grazing silhouette, for a white dielectric (glTF metallic-roughness, F0 0.04)
//! at two roughnesses, smooth and Perlin-bumped, and a white metal. What it measures is in docs/gltf-support.md
//! ("Energy at grazing angles").
//!
//! `cargo run --release --example furnace_rings [SPP]` (default 256).
use glam::{Vec3, Vec4};
use strata::render::frame::{render_frame, FrameOptions};
use strata::render::SceneOnGpu;
use strata::scene::environment::Environment;
use strata::scene::settings::{RenderSettings, SamplerKind};
use strata::scene::{BumpMap, Material, NoiseKind, Scene};
use strata::vk::{Gpu, GpuOptions};

const SIZE: u32 = 96;
const DISTANCE: f32 = 5.0;
const YFOV_DEGREES: f32 = 30.0;

fn sphere(metallic: f32, roughness: f32, bump: f32) -> Scene {
    let mut scene = Scene::default();
    scene.materials.push(Material {
        name: "white".into(),
        base_color: Vec4::ONE,
        metallic,
        roughness,
        bump: (bump > 0.0).then(|| BumpMap {
            kind: NoiseKind::Fbm,
            amplitude: bump,
            frequency: 16.0,
            ..Default::default()
        }),
        ..Default::default()
    });
    strata::scene::library::add_sphere_in_view(&mut scene, 0, DISTANCE, YFOV_DEGREES);
    scene.environment = Some(Environment::uniform(Vec3::ONE));
    scene
}

fn main() -> anyhow::Result<()> {
    let spp: u32 = match std::env::args().nth(1) {
        Some(text) => text.parse().map_err(|_| anyhow::anyhow!("SPP must be a whole number, not {text:?}"))?,
        None => 256,
    };
    let gpu = Gpu::new(&GpuOptions::default())?;
    // The sphere's radius in pixels: tan(asin(1 / distance)) over tan(half the field of view), in half images.
    let radius = (1.0 / DISTANCE).asin().tan() / (YFOV_DEGREES.to_radians() / 2.0).tan() * SIZE as f32 / 2.0;
    let rings = [(0.0, 0.7), (0.7, 0.9), (0.9, 0.97)];
    println!(
        "White furnace, {SIZE}x{SIZE}, {spp} spp: mean ± standard error of the brightest channel per ring (r / R)"
    );
    for (metallic, roughness, bump) in
        [(0.0, 0.5, 0.0), (0.0, 0.5, 0.05), (0.0, 0.2, 0.0), (0.0, 0.2, 0.08), (1.0, 0.2, 0.08)]
    {
        let scene = sphere(metallic, roughness, bump);
        let on_gpu = SceneOnGpu::upload(&gpu.device, &scene)?;
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            spp,
            sampler: SamplerKind::MultiJittered,
            indirect: true,
            bounces: 16,
            ..Default::default()
        };
        let frame = render_frame(&gpu.device, &scene, &on_gpu, &settings, &FrameOptions::default(), &mut |_, _| true)?;
        let mut line = format!("metallic {metallic}, roughness {roughness}, bump amplitude {bump}:");
        for (lo, hi) in rings {
            let values: Vec<f64> = (0..SIZE * SIZE)
                .filter_map(|i| {
                    let (x, y) =
                        ((i % SIZE) as f32 + 0.5 - SIZE as f32 / 2.0, (i / SIZE) as f32 + 0.5 - SIZE as f32 / 2.0);
                    let r = (x * x + y * y).sqrt() / radius;
                    let p = frame.linear.pixels[i as usize];
                    (p[3] >= 1.0 && r >= lo && r < hi).then(|| f64::from(p[0].max(p[1]).max(p[2])))
                })
                .collect();
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            line += &format!("  {lo}–{hi}: {mean:.4} ± {:.4}", sd / n.sqrt());
        }
        println!("{line}");
    }
    Ok(())
}
