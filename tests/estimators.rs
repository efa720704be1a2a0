//! The direct-light estimators check each other, the standard unbiasedness test of a physically based renderer:
//! light sampling alone, BSDF sampling alone and their combination by multiple importance sampling (Veach and
//! Guibas 1995) estimate one integral, so on every scene in `scenes/` and on a table of materials and lights
//! their pictures must agree within noise — and so must the bounce strategies of `--indirect` (light sampling at
//! every vertex against BSDF sampling only). Any place where light sampling and the rays disagree on where light
//! comes from (the back of a one-sided emitter, a light sample weighted against a ray that is never cast) shows
//! up as a difference.
//!
//! Tolerances come from the measured noise: each render also accumulates every sample's squared luminance
//! (`FrameOptions::luminance_moments`), which gives each pixel's variance; the traced primary mode with a still
//! frame and the random sampler keeps every pixel's samples independent of the other pixels', so a region mean's
//! variance is the sum of its pixels' variances over P². Region means must agree within `Z_MAX` standard errors
//! of their difference.
use crate::common;

use common::scenes::*;
use common::GpuTest;
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::path::PathBuf;
use std::sync::Arc;
use strata::render::frame::{render_frame, DirectLight, FrameOptions};
use strata::render::SceneOnGpu;
use strata::scene::camera::{look_at, Lens};
use strata::scene::settings::{Primary, RenderSettings, SamplerKind};
use strata::scene::{AlphaMode, Camera, Light, LightShape, Material, Projection, Scene};
use strata::vk::Device;

/// How many standard errors two estimates of one region may differ by. Each test makes a few hundred
/// comparisons; for normal errors a 5σ difference has probability 6e-7, so a failure is a bias, not bad luck.
const Z_MAX: f64 = 5.0;

/// Regions per side of the grid whose means are compared.
const GRID: u32 = 4;

const ESTIMATORS: [DirectLight; 3] = [DirectLight::Mis, DirectLight::LightSampling, DirectLight::BsdfSampling];

/// A region's mean luminance and the variance of that mean.
#[derive(Debug, Clone, Copy)]
struct RegionMean {
    mean: f64,
    variance: f64,
}

fn luminance(p: &[f32; 4]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// Renders with one estimator and returns the GRID×GRID region means with their variances.
fn region_means(
    device: &Arc<Device>,
    scene: &Scene,
    on_gpu: &SceneOnGpu,
    settings: &RenderSettings,
    direct_light: DirectLight,
) -> Vec<RegionMean> {
    let options = FrameOptions { direct_light, luminance_moments: true, ..Default::default() };
    let frame = render_frame(device, scene, on_gpu, settings, &options, &mut |_, _| true).expect("render");
    let f = &frame.linear;
    let n = f64::from(settings.spp);
    let (rw, rh) = (f.width / GRID, f.height / GRID);
    let mut regions = Vec::new();
    for gy in 0..GRID {
        for gx in 0..GRID {
            let (mut sum, mut variance) = (0.0, 0.0);
            for y in gy * rh..(gy + 1) * rh {
                for x in gx * rw..(gx + 1) * rw {
                    let p = f.pixel(x, y);
                    assert!(p.iter().all(|v| v.is_finite()), "pixel ({x}, {y}) is not finite: {p:?}");
                    let mean = luminance(&p);
                    // The alpha channel holds the mean of the squared luminance; the pixel mean's variance is the
                    // sample variance over N.
                    let second = f64::from(p[3]);
                    sum += mean;
                    variance += ((second - mean * mean) * n / (n - 1.0)).max(0.0) / n;
                }
            }
            let count = f64::from(rw * rh);
            regions.push(RegionMean { mean: sum / count, variance: variance / (count * count) });
        }
    }
    regions
}

/// What a case measured: the worst difference between two estimators, in standard errors, and where.
struct Agreement {
    worst_z: f64,
    report: String,
}

/// BSDF sampling alone finds small lights only by chance: it gets this many times the samples of the others.
const BSDF_SAMPLES: u32 = 4;

/// Renders `scene` with every estimator and compares each pair region by region.
fn agreement(device: &Arc<Device>, scene: &Scene, settings: &RenderSettings) -> Agreement {
    let on_gpu = SceneOnGpu::upload(device, scene).expect("upload");
    let mut estimates: Vec<Vec<RegionMean>> = ESTIMATORS
        .iter()
        .map(|&e| {
            let spp = settings.spp * if e == DirectLight::BsdfSampling { BSDF_SAMPLES } else { 1 };
            region_means(device, scene, &on_gpu, &RenderSettings { spp, ..settings.clone() }, e)
        })
        .collect();
    drop(on_gpu);
    // A light that one strategy reaches only rarely (BSDF sampling and a small or distant light, light sampling
    // and a sharp highlight) makes that strategy's estimate heavy-tailed: a region that saw none of the rare,
    // bright samples reports a mean below the truth and a variance far below the truth. So each strategy's
    // variance is kept at least at its typical ratio to MIS's (the median over the regions) times MIS's: the
    // tolerance still comes from the measured noise, taken where the noise could be measured.
    let reference = estimates[0].clone();
    for estimate in estimates.iter_mut().skip(1) {
        let mut ratios: Vec<f64> = estimate
            .iter()
            .zip(&reference)
            .filter(|(_, m)| m.variance > 0.0)
            .map(|(e, m)| e.variance / m.variance)
            .collect();
        ratios.sort_by(f64::total_cmp);
        let typical = ratios.get(ratios.len() / 2).copied().unwrap_or(0.0);
        for (e, m) in estimate.iter_mut().zip(&reference) {
            e.variance = e.variance.max(typical * m.variance);
        }
    }
    let signal = estimates[0].iter().map(|r| r.mean).fold(0.0, f64::max);
    assert!(signal > 1e-3, "the case renders black: nothing to compare");
    let (mut worst_z, mut report) = (0.0f64, String::new());
    for a in 0..ESTIMATORS.len() {
        for b in a + 1..ESTIMATORS.len() {
            for (region, (ra, rb)) in estimates[a].iter().zip(&estimates[b]).enumerate() {
                let difference = (ra.mean - rb.mean).abs();
                let error = (ra.variance + rb.variance).sqrt();
                // Equal to the last bit, or a difference far below what the picture can show.
                let z = if difference <= 1e-6 * signal { 0.0 } else { difference / error.max(1e-12) };
                if z > worst_z {
                    worst_z = z;
                    report = format!(
                        "{:?} {:.5} ± {:.5} vs {:?} {:.5} ± {:.5} in region ({}, {})",
                        ESTIMATORS[a],
                        ra.mean,
                        ra.variance.sqrt(),
                        ESTIMATORS[b],
                        rb.mean,
                        rb.variance.sqrt(),
                        region as u32 % GRID,
                        region as u32 / GRID
                    );
                }
            }
        }
    }
    Agreement { worst_z, report }
}

/// The comparison frames: traced primary rays and the random sampler (independent pixels), a still frame.
fn comparison_settings(spp: u32, indirect: bool, bounces: u32) -> RenderSettings {
    RenderSettings {
        primary: Primary::Rays,
        indirect,
        bounces,
        // Escaping rays see it: the rays that only gather direct light must not.
        background: Vec3::splat(0.2),
        ..settings(32, 32, spp, SamplerKind::Random)
    }
}

/// Runs every case and fails with the list of those whose estimators disagree.
fn check_cases(gpu: &GpuTest, cases: Vec<(String, Scene, RenderSettings)>) {
    let mut failures = Vec::new();
    for (name, mut scene, settings) in cases {
        // A still frame: one shutter time per sample is shared by every pixel, which would correlate them.
        scene.shutter = (scene.shutter.0, scene.shutter.0);
        let result = agreement(gpu.device(), &scene, &settings);
        eprintln!("{name}: worst difference {:.2} standard errors ({})", result.worst_z, result.report);
        if result.worst_z > Z_MAX {
            failures.push(format!("{name}: {:.1} standard errors: {}", result.worst_z, result.report));
        }
    }
    assert!(failures.is_empty(), "estimators disagree:\n{}", failures.join("\n"));
}

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn project_scenes() -> Vec<(String, Scene)> {
    let mut scenes = Vec::new();
    for entry in std::fs::read_dir(repo("scenes")).expect("scenes/") {
        let path = entry.expect("scenes/ entry").path();
        if path.extension().and_then(|e| e.to_str()) == Some("toml") {
            let mut scene = strata::load(&path, &Default::default()).expect("scene loads").scene;
            if !scene.has_light() {
                scene.add_default_light();
            }
            let name = path.file_stem().unwrap().to_string_lossy().into_owned();
            scenes.push((name, scene));
        }
    }
    scenes.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(scenes.len() >= 5, "scenes/ should hold the project's scenes");
    scenes
}

#[test]
fn estimators_agree_on_every_scene_with_cooks_effects() {
    let gpu = GpuTest::new();
    let cases = project_scenes()
        .into_iter()
        .flat_map(|(name, scene)| {
            // Bounces 0: the light sample at the visible surface is all there is, so it must take every lobe.
            [(0, 64), (3, 64)].map(|(bounces, spp)| {
                (format!("{name}, bounces {bounces}"), scene.clone(), comparison_settings(spp, false, bounces))
            })
        })
        .collect();
    check_cases(&gpu, cases);
    gpu.finish().unwrap();
}

#[test]
fn estimators_agree_on_every_scene_with_diffuse_interreflection() {
    let gpu = GpuTest::new();
    let mut cases: Vec<_> = project_scenes()
        .into_iter()
        .map(|(name, scene)| (format!("{name}, --indirect"), scene, comparison_settings(64, true, 3)))
        .collect();
    // One bounce in the Cornell box: the light that arrives by one bounce near the ceiling light, where the light
    // fills a large solid angle.
    let cornell = cases.iter().find(|c| c.0.starts_with("cornell")).expect("the Cornell box").1.clone();
    cases.push(("cornell, --indirect --bounces 1".into(), cornell, comparison_settings(64, true, 1)));
    check_cases(&gpu, cases);
    gpu.finish().unwrap();
}

/// A stage for one case: a 6 m floor of `floor` at y = 0 seen from (0, 1.5, 3) towards (0, 0, -0.3), so the
/// mirror image of a light near (0, 1.2, −1) lies in view.
fn stage(floor: Material) -> Scene {
    let mut scene = Scene::default();
    scene.materials.push(floor);
    let (p, m) = plane_at(Vec2::new(6.0, 6.0), Vec3::ZERO, false, 0);
    place(&mut scene, "floor", p, m);
    scene.camera = Some(Camera {
        name: "stage".into(),
        world_from_camera: look_at(Vec3::new(0.0, 1.5, 3.0), Vec3::new(0.0, 0.0, -0.3), Vec3::Y),
        projection: Projection::Perspective { yfov: 50f32.to_radians(), znear: 0.01, zfar: None },
        lens: Lens::PINHOLE,
    });
    scene
}

/// An orthographic camera placed by `world_from_camera`, 2·half_height metres across.
fn ortho_camera(world_from_camera: Mat4, half_height: f32) -> Camera {
    Camera {
        name: "close-up".into(),
        world_from_camera,
        projection: Projection::Orthographic { xmag: half_height, ymag: half_height, znear: 0.01, zfar: 100.0 },
        lens: Lens::PINHOLE,
    }
}

/// A frame at `position` emitting along `direction` (the light's −Z).
fn facing(position: Vec3, direction: Vec3) -> Mat4 {
    let up = if direction.cross(Vec3::Y).length() > 1e-3 { Vec3::Y } else { Vec3::Z };
    look_at(position, position + direction, up)
}

fn analytic_light(scene: &mut Scene, shape: LightShape, radiance: f32, world_from_light: Mat4) {
    scene.lights.push(Light {
        name: "light".into(),
        shape,
        emission: Vec3::splat(radiance),
        world_from_light,
        node: None,
        range: 0.0,
    });
}

/// A dielectric of grey base colour 0.5 with GGX roughness `roughness` (F0 0.04).
fn glossy(roughness: f32) -> Material {
    Material {
        name: format!("ggx {roughness}"),
        base_color: Vec4::new(0.5, 0.5, 0.5, 1.0),
        metallic: 0.0,
        roughness,
        ..Default::default()
    }
}

/// How an emissive quad (geometry, so its triangles are lights) is made and placed.
#[derive(Clone, Copy)]
enum Panel {
    /// One-sided, over the floor facing down.
    OneSidedDown,
    /// One-sided, 0.3 m over the floor facing down: most of the floor sees it at a grazing angle, where a shadow
    /// ray that starts off the floor meets the light's plane sooner than one from the floor itself.
    LowOverTheFloor,
    /// Standing upright at z = −1, facing the camera (+Z) or away from it; one- or two-sided.
    Upright { towards_camera: bool, two_sided: bool },
    /// One-sided, facing up: it lights nothing in the scene, and the camera sees its front.
    FacingAway,
    /// An emissive checker texture (4×4 texels, magnified).
    Textured,
    /// Alpha-masked by a checker in its base colour's alpha: only the covered squares emit.
    Masked,
}

fn checker(scene: &mut Scene, name: &str, texel: impl Fn(bool) -> [u8; 4]) -> usize {
    use strata::scene::{Texture, TextureImage, Wrap};
    let rgba8 = (0..16).flat_map(|i| texel((i % 4 + i / 4) % 2 == 0)).collect();
    scene.images.push(TextureImage { name: name.into(), width: 4, height: 4, rgba8 });
    scene.textures.push(Texture {
        name: name.into(),
        image: scene.images.len() - 1,
        sampler: nearest_sampler(Wrap::ClampToEdge),
        srgb: false,
    });
    scene.textures.len() - 1
}

fn add_panel(scene: &mut Scene, panel: Panel) {
    use strata::scene::TextureRef;
    let mut material = Material {
        name: "panel".into(),
        base_color: Vec4::new(0.3, 0.3, 0.3, 1.0),
        metallic: 0.0,
        roughness: 0.5,
        emissive: Vec3::splat(4.0),
        ..Default::default()
    };
    let (size, transform) = match panel {
        Panel::OneSidedDown | Panel::Textured | Panel::Masked => (
            Vec2::splat(0.8),
            Mat4::from_translation(Vec3::new(0.0, 1.0, -1.0)) * Mat4::from_rotation_x(std::f32::consts::PI),
        ),
        Panel::Upright { towards_camera, two_sided } => {
            material.double_sided = two_sided;
            // The plane faces +Y; turned about x by +90° it faces +Z, by −90° −Z.
            let angle = if towards_camera { 1.0 } else { -1.0 } * std::f32::consts::FRAC_PI_2;
            (Vec2::new(1.2, 0.6), Mat4::from_translation(Vec3::new(0.0, 0.45, -1.0)) * Mat4::from_rotation_x(angle))
        }
        Panel::FacingAway => (Vec2::splat(0.8), Mat4::from_translation(Vec3::new(0.0, 0.6, -1.0))),
        Panel::LowOverTheFloor => (
            Vec2::splat(0.8),
            Mat4::from_translation(Vec3::new(0.0, 0.3, -1.0)) * Mat4::from_rotation_x(std::f32::consts::PI),
        ),
    };
    if let Panel::Textured = panel {
        let texture =
            checker(scene, "emissive checker", |on| if on { [255, 200, 100, 255] } else { [40, 40, 40, 255] });
        material.emissive_texture = Some(TextureRef { texture, tex_coord: 0, transform: None });
    }
    if let Panel::Masked = panel {
        let texture = checker(scene, "alpha checker", |on| [255, 255, 255, if on { 255 } else { 0 }]);
        material.base_color_texture = Some(TextureRef { texture, tex_coord: 0, transform: None });
        material.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    }
    scene.materials.push(material);
    let (p, _) = plane_at(size, Vec3::ZERO, false, scene.materials.len() - 1);
    place(scene, "panel", p, transform);
}

#[test]
fn estimators_agree_on_every_material_and_light() {
    let gpu = GpuTest::new();
    let quad_over = |scene: &mut Scene| {
        let light = facing(Vec3::new(0.0, 1.2, -1.0), Vec3::NEG_Y);
        analytic_light(scene, LightShape::Quad { size: Vec2::splat(0.8) }, 4.0, light);
    };
    let mut cases: Vec<(String, Scene)> = Vec::new();
    let mut lambert = glossy(1.0);
    lambert.specular = 0.0;
    lambert.name = "diffuse".into();
    let metal = Material { name: "metal".into(), metallic: 1.0, roughness: 0.3, ..glossy(0.3) };
    for floor in [lambert, glossy(0.05), glossy(0.3), glossy(1.0), metal] {
        let mut scene = stage(floor.clone());
        quad_over(&mut scene);
        cases.push((format!("{} floor under a quad light", floor.name), scene));
    }
    // Glass: a sphere on a diffuse floor, lit through it.
    let mut scene = stage(glossy(1.0));
    scene.materials.push(Material {
        name: "glass".into(),
        base_color: Vec4::ONE,
        metallic: 0.0,
        roughness: 0.05,
        transmission: 1.0,
        ..Default::default()
    });
    let sphere = strata::scene::shapes::uv_sphere(0.35, 32, 16, Some(1));
    place(&mut scene, "glass sphere", sphere, Mat4::from_translation(Vec3::new(0.0, 0.35, -0.6)));
    quad_over(&mut scene);
    cases.push(("glass sphere under a quad light".into(), scene));

    // The lights, over a glossy floor where BSDF sampling reaches them.
    let over = facing(Vec3::new(0.0, 1.2, -1.0), Vec3::NEG_Y);
    for (name, shape, radiance, transform) in [
        ("disk light", LightShape::Disk { radius: 0.4 }, 4.0, over),
        ("sphere light", LightShape::Sphere { radius: 0.3 }, 4.0, Mat4::from_translation(Vec3::new(0.0, 0.8, -1.0))),
        (
            "point light of radius 0.2",
            LightShape::Point { radius: 0.2 },
            2.0,
            Mat4::from_translation(Vec3::new(0.0, 0.8, -1.0)),
        ),
        ("point light", LightShape::Point { radius: 0.0 }, 2.0, Mat4::from_translation(Vec3::new(0.0, 0.8, -1.0))),
    ] {
        let mut scene = stage(glossy(0.3));
        analytic_light(&mut scene, shape, radiance, transform);
        cases.push((name.into(), scene));
    }
    for (name, panel) in [
        ("one-sided emitter over the floor", Panel::OneSidedDown),
        ("one-sided emitter low over the floor", Panel::LowOverTheFloor),
        ("one-sided emitter facing the camera", Panel::Upright { towards_camera: true, two_sided: false }),
        ("one-sided emitter seen from behind", Panel::Upright { towards_camera: false, two_sided: false }),
        ("two-sided emitter", Panel::Upright { towards_camera: true, two_sided: true }),
        ("two-sided emitter turned round", Panel::Upright { towards_camera: false, two_sided: true }),
        ("one-sided emitter facing away from everything", Panel::FacingAway),
        ("textured emitter", Panel::Textured),
        ("alpha-masked emitter", Panel::Masked),
    ] {
        let mut scene = stage(glossy(0.3));
        add_panel(&mut scene, panel);
        if let Panel::FacingAway = panel {
            // Something to light the floor: a point light, which only light sampling can find.
            analytic_light(
                &mut scene,
                LightShape::Point { radius: 0.0 },
                1.0,
                Mat4::from_translation(Vec3::new(1.0, 1.0, 0.0)),
            );
        }
        cases.push((name.into(), scene));
    }
    // The environment: a light sampled by its luminance distribution and found by escaping rays, alone over a
    // glossy floor and beside a quad light (selection between them by power).
    for (name, with_quad) in [("studio environment", false), ("studio environment and a quad light", true)] {
        let mut scene = stage(glossy(0.3));
        scene.environment = Some(strata::scene::environment::Environment::studio(128, 64));
        if with_quad {
            quad_over(&mut scene);
        }
        cases.push((name.into(), scene));
    }
    // Bounces 0 and 1: the light sample at a path's last vertex is all there is of its direct light.
    let cases = cases
        .into_iter()
        .flat_map(|(name, scene)| {
            [(false, 0), (false, 3), (true, 1)].map(|(indirect, bounces)| {
                let label = format!("{name}, {}--bounces {bounces}", if indirect { "--indirect " } else { "" });
                (label, scene.clone(), comparison_settings(64, indirect, bounces))
            })
        })
        .collect();
    check_cases(&gpu, cases);
    gpu.finish().unwrap();
}

/// The layers (KHR_materials_clearcoat, _sheen; layers.glsl): the coat joins the specular lobe's estimators with one
/// mixture density, the sheen the diffuse lobe's, so light sampling, BSDF sampling and MIS must still agree on
/// floors that carry them under a quad light; and a floor that transmits diffusely
/// (KHR_materials_diffuse_transmission), lit from above and through itself from below.
#[test]
fn estimators_agree_on_layered_materials() {
    use strata::scene::{Anisotropy, Clearcoat, DiffuseTransmission, Sheen};
    let gpu = GpuTest::new();
    let coat = |roughness| Some(Clearcoat { factor: 1.0, roughness, ..Default::default() });
    let sheen = |roughness| Some(Sheen { color: Vec3::new(0.9, 0.7, 0.5), roughness, ..Default::default() });
    let floors = [
        ("smooth coat over rough grey", Material { clearcoat: coat(0.05), ..glossy(0.8) }),
        ("rough coat over glossy grey", Material { clearcoat: coat(0.4), ..glossy(0.2) }),
        ("sheen over diffuse grey", Material { sheen: sheen(0.5), specular: 0.0, ..glossy(1.0) }),
        (
            "coat over sheen over metal",
            Material { clearcoat: coat(0.1), sheen: sheen(0.3), metallic: 1.0, ..glossy(0.3) },
        ),
    ];
    let transmits = Some(DiffuseTransmission { factor: 0.6, color: Vec3::new(1.0, 0.6, 0.3), ..Default::default() });
    let mut cases = Vec::new();
    let stretched = Some(Anisotropy { strength: 0.8, rotation: 0.4, ..Default::default() });
    for (name, floor) in floors.into_iter().chain([
        (
            "floor transmitting diffusely, lit from both sides",
            Material { diffuse_transmission: transmits, ..glossy(0.6) },
        ),
        ("anisotropic glossy floor", Material { anisotropy: stretched, ..glossy(0.3) }),
    ]) {
        let from_below = floor.diffuse_transmission.is_some();
        let mut scene = stage(floor);
        let light = facing(Vec3::new(0.0, 1.2, -1.0), Vec3::NEG_Y);
        analytic_light(&mut scene, LightShape::Quad { size: Vec2::splat(0.8) }, 4.0, light);
        if from_below {
            let below = facing(Vec3::new(0.5, -0.6, -0.5), Vec3::Y);
            analytic_light(&mut scene, LightShape::Quad { size: Vec2::splat(0.8) }, 4.0, below);
        }
        for (indirect, bounces) in [(false, 0), (true, 2)] {
            let label = format!("{name}, {}--bounces {bounces}", if indirect { "--indirect " } else { "" });
            cases.push((label, scene.clone(), comparison_settings(64, indirect, bounces)));
        }
    }
    check_cases(&gpu, cases);
    gpu.finish().unwrap();
}

/// The G-buffer has no room for the layers' parameters, so where a layered material is seen the accumulation pass
/// meets the G-buffer's surface again with a short ray and evaluates it at that hit (docs/architecture.md,
/// "Layered materials"): region by region, a coated and sheened sphere filling the view, seen from above under a quad light, must
/// shade as the reference mode's primary rays shade it.
#[test]
fn a_layered_surface_shades_alike_from_the_gbuffer_and_from_primary_rays() {
    use strata::scene::{Clearcoat, Sheen};
    let gpu = GpuTest::new();
    let mut scene = stage(glossy(0.6));
    scene.materials.push(Material {
        name: "coated velvet".into(),
        base_color: Vec4::new(0.6, 0.2, 0.1, 1.0),
        clearcoat: Some(Clearcoat { factor: 0.8, roughness: 0.15, ..Default::default() }),
        sheen: Some(Sheen { color: Vec3::new(0.3, 0.5, 0.9), roughness: 0.4, ..Default::default() }),
        ..glossy(0.5)
    });
    let center = Vec3::new(0.0, 0.35, -0.6);
    place(
        &mut scene,
        "sphere",
        strata::scene::shapes::uv_sphere(0.35, 64, 32, Some(1)),
        Mat4::from_translation(center),
    );
    scene.camera = Some(ortho_camera(look_at(center + Vec3::new(0.2, 1.4, 0.8), center, Vec3::Y), 0.22));
    let light = facing(Vec3::new(0.0, 1.2, -1.0), Vec3::NEG_Y);
    analytic_light(&mut scene, LightShape::Quad { size: Vec2::splat(0.8) }, 4.0, light);
    let on_gpu = SceneOnGpu::upload(gpu.device(), &scene).expect("upload");
    // Direct light alone (no chain code: a fifth of the compile), which is all the visible surface's own shading is.
    let rays = comparison_settings(64, false, 0);
    let raster = RenderSettings { primary: Primary::Raster, ..rays.clone() };
    let [from_rays, from_gbuffer] =
        [rays, raster].map(|s| region_means(gpu.device(), &scene, &on_gpu, &s, DirectLight::Mis));
    drop(on_gpu);
    for (region, (a, b)) in from_rays.iter().zip(&from_gbuffer).enumerate() {
        let z = (a.mean - b.mean).abs() / (a.variance + b.variance).sqrt().max(1e-12);
        eprintln!("region {region}: primary rays {:.5}, G-buffer {:.5}: {z:.2} standard errors", a.mean, b.mean);
        assert!(a.mean > 1e-3, "region {region} renders black");
        assert!(
            z <= Z_MAX,
            "region {region}: primary rays {:.5} ± {:.5}, G-buffer {:.5} ± {:.5}",
            a.mean,
            a.variance.sqrt(),
            b.mean,
            b.variance.sqrt()
        );
    }
    gpu.finish().unwrap();
}

/// A named window of an image: its columns and rows.
type Window = (&'static str, std::ops::Range<u32>, std::ops::Range<u32>);

/// Mean luminance of the pixels in `columns` × `rows` and the variance of that mean (from the moments alpha).
fn window_mean(
    frame: &strata::output::Frame,
    spp: u32,
    columns: std::ops::Range<u32>,
    rows: std::ops::Range<u32>,
) -> RegionMean {
    let n = f64::from(spp);
    let (mut sum, mut variance, mut count) = (0.0, 0.0, 0.0);
    for y in rows {
        for x in columns.clone() {
            let p = frame.pixel(x, y);
            let mean = luminance(&p);
            sum += mean;
            variance += ((f64::from(p[3]) - mean * mean) * n / (n - 1.0)).max(0.0) / n;
            count += 1.0;
        }
    }
    RegionMean { mean: sum / count, variance: variance / (count * count) }
}

/// The scene of the bug report: `scenes/cornell.toml`'s ceiling light is a one-sided emissive square 1 mm below
/// the ceiling. With `--indirect`, a diffuse bounce from the ceiling just beside it often hits the square's back,
/// which must not emit: the ceiling there is lit only indirectly; and the ceiling above the square must not pass
/// the back's light on to the room. The reference is the same box with the square black and not emissive and an
/// analytic quad light of the same size and radiance just under it (a light that is not geometry, which rays and
/// light sampling both see only from the front): the ceiling beside the light, along its edge and in front of
/// it, and the walls and floor must read the same in both, within the measured noise.
#[test]
fn the_ceiling_beside_a_one_sided_emitter_is_lit_only_indirectly() {
    let gpu = GpuTest::new();
    let mut emissive = strata::load(&repo("scenes/cornell.toml"), &Default::default()).expect("cornell").scene;
    let lamp = emissive.materials.iter().position(|m| m.name == "ceiling light").expect("the ceiling light");
    // The square only emits: a ray that reaches the analytic light ends there, so in both scenes nothing may be
    // reflected by what lies behind it.
    emissive.materials[lamp].base_color = Vec4::new(0.0, 0.0, 0.0, 1.0);
    emissive.materials[lamp].specular = 0.0;
    let mut analytic = emissive.clone();
    let radiance = analytic.materials[lamp].emissive;
    analytic.materials[lamp].emissive = Vec3::ZERO;
    analytic.lights.push(Light {
        name: "analytic ceiling light".into(),
        shape: LightShape::Quad { size: Vec2::splat(0.5) },
        emission: radiance,
        world_from_light: facing(Vec3::new(0.0, 1.9985, 0.0), Vec3::NEG_Y),
        node: None,
        range: 0.0,
    });
    let spp = 64;
    let settings = RenderSettings { width: 128, height: 128, ..comparison_settings(spp, true, 3) };
    let options = FrameOptions { luminance_moments: true, ..Default::default() };
    // The scene's camera at (0, 1, 3.9) with a 39° field of view sees the light (|x|, |z| ≤ 0.25 at y = 2) over
    // rows 14.5–20.5 and columns 51.6–76.4 of 128, the ceiling above row 27. A second camera looks straight up at
    // the light's front edge (z = 0.25) from below, 4 cm across: image x is world x, rows 0–31 the ceiling from
    // 2 cm to 0 in front of the edge (what a diffuse bounce from there sees of the square's back shrinks with the
    // square of that distance), rows 32–63 the light.
    let close_up = ortho_camera(look_at(Vec3::new(0.0, 1.5, 0.25), Vec3::new(0.0, 2.0, 0.25), Vec3::Z), 0.02);
    let views: [(Option<Camera>, u32, Vec<Window>); 2] = [
        (
            None,
            128,
            vec![
                ("ceiling beside the light, left", 28..50, 15..21),
                ("ceiling beside the light, right", 78..100, 15..21),
                ("ceiling along the light's front edge", 52..77, 11..14),
                ("ceiling in front of the light", 40..88, 4..11),
                ("walls and floor", 0..128, 30..128),
            ],
        ),
        (
            Some(close_up),
            64,
            vec![
                ("ceiling 0.6–2 cm in front of the light's edge", 0..64, 0..20),
                ("ceiling 0–0.6 cm in front of the light's edge", 0..64, 20..31),
            ],
        ),
    ];
    let mut failures = Vec::new();
    for (camera, size, windows) in views {
        let settings = RenderSettings { width: size, height: size, ..settings.clone() };
        let frames: Vec<strata::output::Frame> = [&emissive, &analytic]
            .iter()
            .map(|&scene| {
                let mut scene = scene.clone();
                if let Some(camera) = &camera {
                    scene.camera = Some(camera.clone());
                }
                let on_gpu = SceneOnGpu::upload(gpu.device(), &scene).expect("upload");
                let frame = render_frame(gpu.device(), &scene, &on_gpu, &settings, &options, &mut |_, _| true);
                frame.expect("render").linear
            })
            .collect();
        for (name, columns, rows) in windows {
            let [e, a] = [0, 1].map(|i| window_mean(&frames[i], spp, columns.clone(), rows.clone()));
            let z = (e.mean - a.mean).abs() / (e.variance + a.variance).sqrt();
            eprintln!(
                "{name}: emissive square {:.4} ± {:.4}, analytic light {:.4} ± {:.4} ({z:.2} standard errors)",
                e.mean,
                e.variance.sqrt(),
                a.mean,
                a.variance.sqrt()
            );
            if z > Z_MAX {
                failures.push(format!("{name}: {:.4} vs {:.4}, {z:.1} standard errors", e.mean, a.mean));
            }
        }
    }
    assert!(failures.is_empty(), "the ceiling is not lit as by the analytic light:\n{}", failures.join("\n"));
    gpu.finish().unwrap();
}

/// One rule of emission for every way a surface is seen: the back of a one-sided emitter is dark to the raster
/// pass's visible surface and to a traced primary ray alike (and, in the table above, to every other ray).
#[test]
fn a_one_sided_emitter_is_dark_from_behind_in_both_primary_modes() {
    let gpu = GpuTest::new();
    // A 1 m square emitting radiance 5 from its front, seen from above: its back when it faces down.
    let lamp_scene = |facing_down: bool| {
        let mut scene = Scene::default();
        let lamp = emitter(&mut scene, 5.0);
        let (p, m) = plane_at(Vec2::new(1.0, 1.0), Vec3::ZERO, facing_down, lamp);
        place(&mut scene, "lamp", p, m);
        scene.camera = Some(ortho_down(Vec3::ZERO, 1.0, 0.25));
        scene
    };
    for primary in [Primary::Raster, Primary::Rays] {
        for face_up in [false, true] {
            let scene = lamp_scene(!face_up);
            let frame =
                render(gpu.device(), &scene, &RenderSettings { primary, ..settings(16, 16, 4, SamplerKind::Jittered) });
            let coverage = frame.linear.pixels.iter().map(|p| p[3]).sum::<f32>() / frame.linear.pixels.len() as f32;
            assert!((coverage - 1.0).abs() < 1e-6, "{primary:?}: the emitter fills the view");
            let red = mean_red(&frame);
            if face_up {
                assert!((red - 5.0).abs() < 1e-4, "{primary:?}: the emitter's front shows its radiance 5: {red}");
            } else {
                assert_eq!(red, 0.0, "{primary:?}: the back of a one-sided emitter must be dark");
            }
        }
    }
    gpu.finish().unwrap();
}

/// Several paths per camera sample (`--shading-samples`) estimate the picture one path per sample does, with
/// less noise. Traced primaries and the random sampler keep pixels independent. In the Cornell box (soft shadows,
/// a light seen directly, paths that go on), 4 samples of 4 paths agree with 16 samples of 1 path region by region
/// within Z_MAX standard errors. A camera sample's variance is its pixel footprint's (its primary ray, which its
/// paths share) plus the lighting's over its paths: on a plain diffuse floor under a quad light, where the
/// footprint adds almost nothing, 4 paths take each region's variance to about a quarter (0.21 to 0.36 measured).
/// The bound, half in every region of the floor, leaves room for the estimated variances' own noise (each region's
/// from 4 samples of 64 pixels) and the footprint's share.
#[test]
fn more_paths_per_camera_sample_estimate_the_same_picture_with_less_noise() {
    let gpu = GpuTest::new();
    let frames = |scene: &Scene, runs: &[(u32, u32)]| -> Vec<Vec<RegionMean>> {
        let on_gpu = SceneOnGpu::upload(gpu.device(), scene).expect("upload");
        let frames = runs
            .iter()
            .map(|&(spp, shading_samples)| {
                let settings = RenderSettings { shading_samples, ..comparison_settings(spp, false, 3) };
                region_means(gpu.device(), scene, &on_gpu, &settings, DirectLight::Mis)
            })
            .collect();
        drop(on_gpu);
        frames
    };
    let (_, mut cornell) = project_scenes().into_iter().find(|(name, _)| name == "cornell").expect("the Cornell box");
    cornell.shutter = (cornell.shutter.0, cornell.shutter.0);
    let [one_path, four_paths] = <[_; 2]>::try_from(frames(&cornell, &[(16, 1), (4, 4)])).ok().unwrap();
    let mut worst_z = 0.0f64;
    for (a, b) in one_path.iter().zip(&four_paths) {
        worst_z = worst_z.max((a.mean - b.mean).abs() / (a.variance + b.variance).sqrt().max(1e-12));
    }
    eprintln!("Cornell box, 4 samples of 4 paths against 16 of 1: worst difference {worst_z:.2} standard errors");
    assert!(worst_z < Z_MAX, "4 samples of 4 paths differ from 16 of 1 by {worst_z:.1} standard errors");

    let mut diffuse = glossy(1.0);
    diffuse.specular = 0.0;
    let mut floor = stage(diffuse);
    analytic_light(
        &mut floor,
        LightShape::Quad { size: Vec2::splat(0.8) },
        4.0,
        facing(Vec3::new(0.0, 1.2, -1.0), Vec3::NEG_Y),
    );
    let [four_paths, one_path] = <[_; 2]>::try_from(frames(&floor, &[(4, 4), (4, 1)])).ok().unwrap();
    // The lower half of the picture sees the floor alone (the upper half its far edge and the background).
    let floor_regions = (GRID * GRID / 2) as usize..;
    let ratios: Vec<f64> = four_paths[floor_regions.clone()]
        .iter()
        .zip(&one_path[floor_regions])
        .map(|(b, c)| b.variance / c.variance)
        .collect();
    eprintln!("variance of 4 samples' mean on the floor, 4 paths each / 1 path each, by region: {ratios:.3?}");
    let worst = ratios.iter().copied().fold(0.0, f64::max);
    assert!(worst < 0.5, "4 paths per camera sample left {worst:.2} of one path's variance in a region of the floor");
    gpu.finish().unwrap();
}
