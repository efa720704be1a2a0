//! The G-buffer pass read back: Blinn bump normals against the closed form on a plane (UV scales 0.5, 1, 4 and
//! mirrored UVs) and against the CPU twin on an fBm sphere; central differences against the analytic gradient;
//! the thin lens on the position channel; and no NaN or Inf from degenerate geometry.
use crate::common;

use common::raycast::{cast, point_ray};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec3Swizzles};
use strata::math::bump::{height_gradient, perturb_normal};
use strata::math::lens::camera_sample;
use strata::render::gbuffer::{GBuffer, GBufferFrame, GBufferPass};
use strata::render::gbuffer_layout::{GEOMETRIC_NORMAL, POSITION, SHADING_NORMAL};
use strata::render::textures::GpuTextures;
use strata::render::GpuScene;
use strata::scene::camera::{look_at, Lens};
use strata::scene::shapes::{plane, uv_sphere};
use strata::scene::surface::compute_surface_derivatives;
use strata::scene::{
    BumpDerivative, BumpMap, Camera, Instance, Material, Mesh, NoiseKind, Primitive, Projection, Scene,
};

fn scene_of(primitive: Primitive, world_from_object: Mat4, bump: Option<BumpMap>, camera: Camera) -> Scene {
    let mut primitive = primitive;
    compute_surface_derivatives(&mut primitive);
    primitive.material = Some(0);
    Scene {
        meshes: vec![Mesh { name: "subject".into(), primitives: vec![primitive] }],
        materials: vec![Material { name: "bumpy".into(), bump, ..Default::default() }],
        instances: vec![Instance {
            name: "subject".into(),
            mesh: 0,
            node: None,
            world_from_object,
            node_from_object: glam::Mat4::IDENTITY,
        }],
        camera: Some(camera),
        ..Default::default()
    }
}

fn camera(eye: Vec3, target: Vec3, up: Vec3, lens: Lens) -> Camera {
    Camera {
        name: "test".into(),
        world_from_camera: look_at(eye, target, up),
        projection: Projection::Perspective { yfov: 0.8, znear: 0.05, zfar: Some(100.0) },
        lens,
    }
}

/// The pass, built once per test: lavapipe compiles the noise-heavy fragment shader in seconds. Most test scenes
/// have at most one texture, so one pipeline (sized for one texture slot) serves them.
fn pass(gpu: &common::GpuTest) -> GBufferPass {
    GBufferPass::new(gpu.device()).unwrap()
}

/// Renders the G-buffer for one camera sample.
fn render(gpu: &common::GpuTest, pass: &GBufferPass, scene: &Scene, size: (u32, u32), lens_uv: Vec2) -> GBufferFrame {
    let device = gpu.device();
    let gpu_scene = GpuScene::upload(device, scene).unwrap();
    let textures = GpuTextures::upload(device, scene).unwrap();
    assert_eq!(textures.images.len(), scene.textures.len().max(1), "one image per texture, or the white stand-in");
    let gbuffer = GBuffer::new(device, size.0, size.1).unwrap();
    let materials = pass.materials(scene, &textures).unwrap();
    // The test scenes' instances have no nodes: every time places them at their `world_from_object`.
    let inputs = pass.inputs(scene, &gpu_scene, &textures, &materials, 0.0).unwrap();
    let sample = camera_sample(scene.camera.as_ref().unwrap(), size.0, size.1, lens_uv, Vec2::ZERO);
    pass.render_to_host(&gbuffer, &inputs, &sample).unwrap()
}

/// Calls `check` at every covered pixel of a 16×16 frame, and asserts that more than 100 are covered.
fn each_covered_pixel(frame: &GBufferFrame, mut check: impl FnMut(u32, u32)) {
    let mut covered = 0;
    for y in 0..16 {
        for x in 0..16 {
            if frame.covered(x, y) {
                covered += 1;
                check(x, y);
            }
        }
    }
    assert!(covered > 100, "{covered} pixels covered");
}

/// An emissive factor times an sRGB-encoded texel, decoded exactly.
fn emission_of(factor: Vec3, srgb_texel: [u8; 4]) -> Vec3 {
    factor * Vec3::from_array([0, 1, 2].map(|i| srgb_channel(srgb_texel[i])))
}

fn srgb_channel(code: u8) -> f32 {
    strata::output::srgb_to_linear(f32::from(code) / 255.0)
}

/// Asserts that a colour read back (`what`: an emission, a specular colour) is the factor times the sRGB texel:
/// each channel within a quarter of the gap to the next 8-bit code. GPUs decode sRGB in hardware to about that (an NVIDIA H100 gave 0.50391 for code
/// 188, exactly 0.50289), which still tells every code apart and sRGB from linear (0.737 for 188).
fn assert_srgb_texel_times(what: &str, got: Vec3, factor: Vec3, srgb_texel: [u8; 4], pixel: (u32, u32)) {
    let want = emission_of(factor, srgb_texel);
    for i in 0..3 {
        let code = srgb_texel[i];
        let gap = srgb_channel(code.saturating_add(1)) - srgb_channel(code.saturating_sub(1));
        let tolerance = factor[i] * gap / 8.0 + 1e-5;
        assert!(
            (got[i] - want[i]).abs() <= tolerance,
            "{pixel:?}: {what} {got}, expected {want} (± {tolerance} in channel {i})"
        );
    }
}

#[test]
fn sine_bumps_on_a_plane_match_the_closed_form_at_every_pixel() {
    let gpu = common::GpuTest::raster_only();
    let pass = pass(&gpu);
    let (amplitude, frequency) = (0.05f32, 1.5f32);
    let bump = BumpMap {
        kind: NoiseKind::Sine,
        amplitude,
        frequency,
        derivative: BumpDerivative::Analytic,
        ..Default::default()
    };
    // Looking straight down at a 2 m plane; UV scale s metres per UV unit, u = (x + 1)/s.
    let cam = camera(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, Lens::PINHOLE);
    for (s, mirrored) in [(0.5f32, false), (1.0, false), (4.0, false), (1.0, true), (0.5, true)] {
        let uv_scale = 2.0 / s;
        let mut p = plane(Vec2::splat(2.0), Vec2::splat(uv_scale), None);
        if mirrored {
            for uv in &mut p.uvs {
                uv.x = uv_scale - uv.x;
            }
        }
        let scene = scene_of(p, Mat4::IDENTITY, Some(bump), cam.clone());
        let frame = render(&gpu, &pass, &scene, (48, 48), Vec2::splat(0.5));
        let (mut worst, mut covered) = (0.0f32, 0);
        for y in 0..frame.height {
            for x in 0..frame.width {
                if !frame.covered(x, y) {
                    continue;
                }
                covered += 1;
                let world = Vec3::from_slice(&frame.at(POSITION, x, y)[..3]);
                let mut u = (world.x + 1.0) / s;
                if mirrored {
                    u = uv_scale - u;
                }
                let b_u = amplitude * std::f32::consts::TAU * frequency * (std::f32::consts::TAU * frequency * u).cos();
                // Height h(x) = B(u(x)); du/dx = ±1/s; the normal of y = h(x) is (−h', 1, 0).
                let dh_dx = if mirrored { -b_u / s } else { b_u / s };
                let want = Vec3::new(-dh_dx, 1.0, 0.0).normalize();
                let got = Vec3::from_slice(&frame.at(SHADING_NORMAL, x, y)[..3]);
                worst = worst.max((got - want).abs().max_element());
            }
        }
        assert!(covered > 1000, "s = {s}: only {covered} pixels covered");
        assert!(worst < 1e-3, "s = {s}, mirrored = {mirrored}: worst normal component error {worst}");
    }
    drop(pass);
    gpu.finish().unwrap();
}

/// The CPU twin's bumped normal at the surface point seen through a point of the image (pixel centres at +0.5).
fn twin_normal(scene: &Scene, frame: &GBufferFrame, point: Vec2, bump: &BumpMap) -> Option<Vec3> {
    let cam = scene.camera.as_ref().unwrap();
    let sample = camera_sample(cam, frame.width, frame.height, Vec2::splat(0.5), Vec2::ZERO);
    let transforms: Vec<Mat4> = scene.instances.iter().map(|i| i.world_from_object).collect();
    let (origin, direction) = point_ray(sample.clip_from_world(), point, frame.width, frame.height);
    let hit = cast(scene, &transforms, origin, direction)?;
    let p = hit.primitive;
    let m = hit.world_from_object;
    let normal = Mat3::from_mat4(m).inverse().transpose() * hit.lerp(&p.normals);
    let (dpdu, dpdv) = (m.transform_vector3(hit.lerp(&p.dpdu)), m.transform_vector3(hit.lerp(&p.dpdv)));
    Some(perturb_normal(normal, dpdu, dpdv, height_gradient(bump, hit.lerp(&p.uvs))))
}

fn fbm_sphere(derivative: BumpDerivative) -> (Scene, BumpMap) {
    let bump =
        BumpMap { kind: NoiseKind::Fbm, amplitude: 0.01, frequency: 4.0, octaves: 4, derivative, ..Default::default() };
    let cam = camera(Vec3::new(0.0, 0.5, 3.0), Vec3::ZERO, Vec3::Y, Lens::PINHOLE);
    (scene_of(uv_sphere(1.0, 96, 48, None), Mat4::IDENTITY, Some(bump), cam), bump)
}

#[test]
fn fbm_bumps_on_a_sphere_match_the_cpu_twin() {
    let gpu = common::GpuTest::raster_only();
    let pass = pass(&gpu);
    let (scene, bump) = fbm_sphere(BumpDerivative::CentralDifferences);
    let frame = render(&gpu, &pass, &scene, (64, 64), Vec2::splat(0.5));
    // Rasterization snaps vertices to the device's sub-pixel grid, which moves where a pixel centre lands on the
    // surface by up to about one grid step: each pixel may differ from the twin by as much as the twin's own normal
    // changes over that step, plus the attachment's half-float rounding (2^-12 at 1) and fp32 arithmetic.
    // lavapipe agrees to ~1e-4 everywhere; an NVIDIA H100 to 3e-5 typically and 1e-3 where the bumps are seen
    // obliquely.
    let grid_step = 0.5f32.powi(gpu.device().limits.sub_pixel_precision_bits as i32);
    let (mut worst_ratio, mut worst, mut checked) = (0.0f32, String::new(), 0);
    for y in (0..frame.height).step_by(2) {
        for x in (0..frame.width).step_by(2) {
            if !frame.covered(x, y) {
                continue;
            }
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let Some(want) = twin_normal(&scene, &frame, centre, &bump) else { continue };
            let shifts = [Vec2::X, Vec2::NEG_X, Vec2::Y, Vec2::NEG_Y].map(|d| centre + d * grid_step);
            let Some(spread) = shifts.iter().try_fold(0.0f32, |spread, &point| {
                twin_normal(&scene, &frame, point, &bump).map(|n| spread.max((n - want).abs().max_element()))
            }) else {
                continue;
            };
            let tolerance = 5e-4 + spread;
            let got = Vec3::from_slice(&frame.at(SHADING_NORMAL, x, y)[..3]);
            let error = (got - want).abs().max_element();
            if error / tolerance > worst_ratio {
                worst_ratio = error / tolerance;
                worst = format!("({x}, {y}): {got} vs twin {want}, error {error:.2e}, tolerance {tolerance:.2e}");
            }
            checked += 1;
        }
    }
    eprintln!("fBm sphere: {checked} pixels; worst error/tolerance {worst_ratio:.2} at {worst}");
    assert!(checked > 300, "only {checked} pixels checked");
    assert!(worst_ratio <= 1.0, "the normal strays from the twin at {worst}");
    drop(pass);
    gpu.finish().unwrap();
}

#[test]
fn central_differences_stay_within_their_derived_bound_of_the_analytic_gradient() {
    let gpu = common::GpuTest::raster_only();
    let pass = pass(&gpu);
    let (central_scene, bump) = fbm_sphere(BumpDerivative::CentralDifferences);
    let (analytic_scene, _) = fbm_sphere(BumpDerivative::Analytic);
    let central = render(&gpu, &pass, &central_scene, (64, 64), Vec2::splat(0.5));
    let analytic = render(&gpu, &pass, &analytic_scene, (64, 64), Vec2::splat(0.5));
    let (mut sum, mut count, mut worst) = (0.0f64, 0, 0.0f32);
    for y in 0..central.height {
        for x in 0..central.width {
            if !central.covered(x, y) {
                continue;
            }
            let a = Vec3::from_slice(&central.at(SHADING_NORMAL, x, y)[..3]);
            let b = Vec3::from_slice(&analytic.at(SHADING_NORMAL, x, y)[..3]);
            let angle = a.dot(b).clamp(-1.0, 1.0).acos();
            sum += f64::from(angle);
            worst = worst.max(angle);
            count += 1;
        }
    }
    let mean = (sum / count as f64) as f32;
    // Bound: central differences err by ε²/6 · B''' (Taylor). Octave i has frequency fλⁱ per UV unit, gain gⁱ,
    // so |B'''| ≤ A Σ gⁱ (fλⁱ)³ K with K = max |∂³noise| of unit noise (≤ 2·30·4 from the quintic fade and
    // unit-size gradients; 240 is generous). The normal tilts by at most that over |Q| ≥ the sphere's smallest
    // UV-scale away from the poles (πr for v, 2πr·sin θ for u; the poles are few pixels). Mean angle is far below.
    let e = bump.epsilon;
    let third: f32 = (0..bump.octaves)
        .map(|i| bump.gain.powi(i as i32) * (bump.frequency * bump.lacunarity.powi(i as i32)).powi(3))
        .sum::<f32>()
        * bump.amplitude
        * 240.0;
    let bound = e * e / 6.0 * third / std::f32::consts::PI;
    eprintln!(
        "central differences (ε = 1/64) vs analytic: mean angle {:.3e} rad, worst {:.3e} rad, bound {:.3e} rad",
        mean, worst, bound
    );
    assert!(mean > 0.0, "the two derivative methods gave identical normals: one of them is not in effect");
    assert!(mean < bound, "mean angle {mean} exceeds the derived bound {bound}");
    drop(pass);
    gpu.finish().unwrap();
}

#[test]
fn thin_lens_keeps_the_focus_plane_and_shifts_other_depths_by_the_prediction() {
    let gpu = common::GpuTest::raster_only();
    let pass = pass(&gpu);
    let (aperture, focus) = (0.2f32, 4.0f32);
    // The camera looks down −Z from the origin; a large plane faces it at depth d.
    for depth in [focus, 2.5, 7.0] {
        let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, Lens { aperture_radius: aperture, focus_distance: focus });
        let wall =
            Mat4::from_translation(Vec3::new(0.0, 0.0, -depth)) * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let scene = scene_of(plane(Vec2::splat(40.0), Vec2::ONE, None), wall, None, cam);
        let pinhole = render(&gpu, &pass, &scene, (40, 30), Vec2::splat(0.5));
        // Lens point (1, ½) is (A, 0) on the aperture: the eye moves +x by A.
        let shifted = render(&gpu, &pass, &scene, (40, 30), Vec2::new(1.0, 0.5));
        // The world point seen through a pixel moves by A(1 − d/f) in x (similar triangles through the focus
        // plane), nothing in y; on the focus plane, not at all.
        let predicted = aperture * (1.0 - depth / focus);
        let pixel_at_depth = 2.0 * depth * (0.4f32).tan() / 30.0;
        let mut worst = 0.0f32;
        for y in 0..30 {
            for x in 0..40 {
                let a = Vec3::from_slice(&pinhole.at(POSITION, x, y)[..3]);
                let b = Vec3::from_slice(&shifted.at(POSITION, x, y)[..3]);
                worst = worst.max(((b - a).xy() - Vec2::new(predicted, 0.0)).length() / pixel_at_depth);
            }
        }
        // Rasterizers snap vertices to a subpixel grid (1/256 px on lavapipe), so the GPU can only be held to a
        // fraction of a pixel here; the exact 1e-3 px check of the projection is in math::lens's tests.
        assert!(worst < 1.0 / 64.0, "depth {depth}: moved {worst} px off the prediction {predicted} m");
    }
    drop(pass);
    gpu.finish().unwrap();
}

#[test]
fn degenerate_uvs_and_zero_area_triangles_give_no_nan_or_inf() {
    let gpu = common::GpuTest::raster_only();
    let pass = pass(&gpu);
    let bump = BumpMap { kind: NoiseKind::Fbm, amplitude: 0.1, ..Default::default() };
    let mut p = plane(Vec2::splat(2.0), Vec2::ONE, None);
    p.uvs = vec![Vec2::splat(0.3); 4]; // zero UV area everywhere
                                       // Add a zero-area triangle (three equal vertices) and one collapsed onto a line.
    let base = p.positions.len() as u32;
    p.positions.extend([Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::X * 3.0]);
    p.normals.extend([Vec3::Y; 6]);
    p.uvs.extend([Vec2::ZERO; 6]);
    p.indices.extend(base..base + 6);
    let cam = camera(Vec3::new(0.0, 2.0, 0.5), Vec3::ZERO, Vec3::Y, Lens::PINHOLE);
    let scene = scene_of(p, Mat4::IDENTITY, Some(bump), cam);
    let frame = render(&gpu, &pass, &scene, (32, 32), Vec2::splat(0.5));
    let covered = (0..32 * 32).filter(|&i| frame.ids[i][0] != 0).count();
    assert!(covered > 200, "{covered} pixels covered");
    for (c, channel) in frame.channels.iter().enumerate() {
        assert!(channel.iter().flatten().all(|v| v.is_finite()), "channel {c} holds NaN or Inf");
    }
    // No bump was possible: shading normals equal the geometric (up) normal.
    for i in 0..32 * 32 {
        if frame.ids[i][0] != 0 {
            let n = Vec3::from_slice(&frame.channels[SHADING_NORMAL][i][..3]);
            let g = Vec3::from_slice(&frame.channels[GEOMETRIC_NORMAL][i][..3]);
            assert!((n - Vec3::Y).length() < 1e-5 && (g - Vec3::Y).length() < 1e-2, "pixel {i}: {n} {g}");
        }
    }
    drop(pass);
    gpu.finish().unwrap();
}

#[test]
fn normal_textures_tilt_the_normal_and_the_bump_composes_on_top() {
    use strata::scene::{Sampler, Texture, TextureImage, TextureRef};
    let gpu = common::GpuTest::raster_only();
    let pass = pass(&gpu);
    // One texel: tangent-space (2·200/255 − 1, 2·128/255 − 1, 2·220/255 − 1), stored linear (it is data).
    let texel = [200u8, 128, 220, 255];
    let tangent_space = Vec3::new(texel[0] as f32, texel[1] as f32, texel[2] as f32) / 255.0 * 2.0 - Vec3::ONE;
    let cam = camera(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, Lens::PINHOLE);
    for bump in [
        None,
        Some(BumpMap {
            kind: NoiseKind::Sine,
            amplitude: 0.03,
            frequency: 1.0,
            derivative: BumpDerivative::Analytic,
            ..Default::default()
        }),
    ] {
        let mut scene = scene_of(plane(Vec2::splat(2.0), Vec2::splat(2.0), None), Mat4::IDENTITY, bump, cam.clone());
        scene.images = vec![TextureImage { name: "normal texel".into(), width: 1, height: 1, rgba8: texel.to_vec() }];
        scene.textures =
            vec![Texture { name: "normal map".into(), image: 0, sampler: Sampler::default(), srgb: false }];
        scene.materials[0].normal_texture = Some(TextureRef { texture: 0, tex_coord: 0, transform: None });
        let frame = render(&gpu, &pass, &scene, (24, 24), Vec2::splat(0.5));
        // plane(): Q_u along +X, Q_v along −Z, normal +Y, so T = +X and B = −Z.
        let mapped = (Vec3::X * tangent_space.x - Vec3::Z * tangent_space.y + Vec3::Y * tangent_space.z).normalize();
        let mut worst = 0.0f32;
        for y in 0..24 {
            for x in 0..24 {
                if !frame.covered(x, y) {
                    continue;
                }
                let want = match &bump {
                    None => mapped,
                    Some(b) => {
                        let world = Vec3::from_slice(&frame.at(POSITION, x, y)[..3]);
                        let uv = Vec2::new(world.x + 1.0, 1.0 - world.z);
                        perturb_normal(mapped, Vec3::X, Vec3::NEG_Z, height_gradient(b, uv))
                    }
                };
                let got = Vec3::from_slice(&frame.at(SHADING_NORMAL, x, y)[..3]);
                worst = worst.max((got - want).abs().max_element());
            }
        }
        assert!(worst < 1e-3, "bump {}: worst normal component error {worst}", bump.is_some());
    }
    drop(pass);
    gpu.finish().unwrap();
}

#[test]
fn metallic_roughness_and_emissive_textures_scale_their_factors() {
    use strata::render::gbuffer_layout::{EMISSION, MATERIAL};
    use strata::scene::{Sampler, Texture, TextureImage, TextureRef};
    let gpu = common::GpuTest::raster_only();
    let pass = GBufferPass::new(gpu.device()).unwrap();
    // Roughness in G, metalness in B, stored linear (glTF 2.0 §3.9.2); the emissive texel is sRGB colour.
    let metal_rough = [0u8, 153, 51, 255];
    let emissive = [188u8, 128, 64, 255];
    let cam = camera(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, Lens::PINHOLE);
    let mut scene = scene_of(plane(Vec2::splat(2.0), Vec2::splat(2.0), None), Mat4::IDENTITY, None, cam);
    scene.images = vec![
        TextureImage { name: "metal-rough texel".into(), width: 1, height: 1, rgba8: metal_rough.to_vec() },
        TextureImage { name: "emissive texel".into(), width: 1, height: 1, rgba8: emissive.to_vec() },
    ];
    scene.textures = vec![
        Texture { name: "metal-rough".into(), image: 0, sampler: Sampler::default(), srgb: false },
        Texture { name: "emissive".into(), image: 1, sampler: Sampler::default(), srgb: true },
    ];
    let m = &mut scene.materials[0];
    (m.metallic, m.roughness, m.emissive) = (0.5, 0.8, Vec3::new(2.0, 1.0, 0.5));
    m.metallic_roughness_texture = Some(TextureRef { texture: 0, tex_coord: 0, transform: None });
    m.emissive_texture = Some(TextureRef { texture: 1, tex_coord: 0, transform: None });
    let frame = render(&gpu, &pass, &scene, (16, 16), Vec2::splat(0.5));
    let (metallic, roughness) = (0.5 * 51.0 / 255.0, 0.8 * 153.0 / 255.0);
    each_covered_pixel(&frame, |x, y| {
        // The material attachment holds 8-bit unorm: within half a step.
        let mat = frame.at(MATERIAL, x, y);
        let step = 0.5 / 255.0 + 1e-4;
        assert!((mat[0] - metallic).abs() < step && (mat[1] - roughness).abs() < step, "({x}, {y}): {mat:?}");
        let emission = Vec3::from_slice(&frame.at(EMISSION, x, y)[..3]);
        assert_srgb_texel_times("emission", emission, Vec3::new(2.0, 1.0, 0.5), emissive, (x, y));
    });
    drop(pass);
    gpu.finish().unwrap();
}

/// KHR_texture_transform applies to every texture the pass reads, the transmission texture's R channel scales
/// its factor and the specular texture's alpha its factor (into the geometric normal's spare channel); the
/// specular colour texel (sRGB) fills its own attachment. Each texture holds two texels, left and right; the
/// transforms (offset 0.55, scale 0.4 in u) send the whole plane to the right one, so an untransformed lookup
/// shows as the left texel on half of it. A normal texture turned a quarter turn tilts the normal along the
/// surface's ∂p/∂v instead of ∂p/∂u: its tangent frame turns with it.
#[test]
fn texture_transforms_apply_to_every_texture_and_transmission_and_specular_textures_scale_their_factors() {
    use strata::render::gbuffer_layout::{EMISSION, GEOMETRIC_NORMAL, MATERIAL, SPECULAR_COLOR};
    use strata::scene::{Texture, TextureImage, TextureRef, UvTransform, Wrap};
    let gpu = common::GpuTest::raster_only();
    let pass = GBufferPass::new(gpu.device()).unwrap();
    let white = [255u8; 4];
    // Right texels: roughness in G, metalness in B, transmission in R, specular in A (linear); the emissive one
    // is sRGB.
    let data = [128u8, 153, 51, 64];
    let emissive = [188u8, 128, 64, 255];
    let tilt_u = [255u8, 128, 128, 255];
    let cam = camera(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, Lens::PINHOLE);
    let mut scene = scene_of(plane(Vec2::splat(2.0), Vec2::ONE, None), Mat4::IDENTITY, None, cam);
    let halves = |name: &str, right: [u8; 4]| TextureImage {
        name: name.into(),
        width: 2,
        height: 1,
        rgba8: [white, right].concat(),
    };
    let tilted = TextureImage { name: "normal".into(), width: 2, height: 1, rgba8: [tilt_u, tilt_u].concat() };
    scene.images = vec![halves("data", data), halves("emissive", emissive), tilted];
    let nearest = common::scenes::nearest_sampler(Wrap::Repeat);
    let texture = |name: &str, image: usize, srgb: bool| Texture { name: name.into(), image, sampler: nearest, srgb };
    scene.textures = vec![texture("data", 0, false), texture("emissive", 1, true), texture("normal", 2, false)];
    let right = Some(UvTransform { offset: Vec2::new(0.55, 0.0), rotation: 0.0, scale: Vec2::new(0.4, 1.0) });
    let quarter_turn =
        Some(UvTransform { offset: Vec2::ZERO, rotation: std::f32::consts::FRAC_PI_2, scale: Vec2::ONE });
    let uses = |texture: usize, transform: Option<UvTransform>| Some(TextureRef { texture, tex_coord: 0, transform });
    let m = &mut scene.materials[0];
    (m.metallic, m.roughness, m.transmission, m.emissive) = (0.5, 0.8, 0.6, Vec3::new(2.0, 1.0, 0.5));
    m.specular = 0.7;
    m.metallic_roughness_texture = uses(0, right);
    m.transmission_texture = uses(0, right);
    m.specular_texture = uses(0, right);
    m.emissive_texture = uses(1, right);
    // The attachment holds the specular colour texel alone; its factor is applied where the G-buffer is read.
    m.specular_color = Vec3::new(4.0, 0.5, 0.25);
    m.specular_color_texture = uses(1, right);
    m.normal_texture = uses(2, quarter_turn);
    let primitive = &scene.meshes[0].primitives[0];
    let (dpdu, dpdv) = (primitive.dpdu[0], primitive.dpdv[0]);
    assert!(dpdu.cross(dpdv).length() > 0.1, "the plane needs a tangent frame: {dpdu} {dpdv}");
    let frame = render(&gpu, &pass, &scene, (16, 16), Vec2::splat(0.5));
    let (metallic, roughness, transmission) = (0.5 * 51.0 / 255.0, 0.8 * 153.0 / 255.0, 0.6 * 128.0 / 255.0);
    let specular = 0.7 * 64.0 / 255.0;
    // A quarter turn (KHR_texture_transform's rotation) makes ∂p/∂u' = ∂p/∂v: the texel's +x tilt follows ∂p/∂v.
    let n = Vec3::Y;
    let expected_normal = (dpdv - n * n.dot(dpdv)).normalize();
    each_covered_pixel(&frame, |x, y| {
        let mat = frame.at(MATERIAL, x, y);
        let step = 0.5 / 255.0 + 1e-4;
        assert!(
            (mat[0] - metallic).abs() < step
                && (mat[1] - roughness).abs() < step
                && (mat[2] - transmission).abs() < step,
            "({x}, {y}): material {mat:?}"
        );
        let emission = Vec3::from_slice(&frame.at(EMISSION, x, y)[..3]);
        assert_srgb_texel_times("emission", emission, Vec3::new(2.0, 1.0, 0.5), emissive, (x, y));
        let specular_color = Vec3::from_slice(&frame.at(SPECULAR_COLOR, x, y)[..3]);
        assert_srgb_texel_times("specular colour", specular_color, Vec3::ONE, emissive, (x, y));
        // The G-buffer keeps the specular factor in 8 bits, as fine as the texture's channel it comes from.
        let got = frame.at(GEOMETRIC_NORMAL, x, y)[3];
        assert!((got - specular).abs() < step, "({x}, {y}): specular {got}, expected {specular}");
        let normal = Vec3::from_slice(&frame.at(SHADING_NORMAL, x, y)[..3]);
        assert!((normal - expected_normal).length() < 0.02, "({x}, {y}): normal {normal}, expected {expected_normal}");
    });
    drop(pass);
    gpu.finish().unwrap();
}

/// Minification reads the mip chain where the sampler asks for mipmaps: a black and white checkerboard of
/// single texels, 256 across a plane that covers about 16 pixels, shows its mean radiance 0.5 at every pixel
/// (sRGB decoded before the 2×2 averages: averaging the encoded values would give 0.216). Without mipmaps the
/// same nearest-filtered lookups land on single texels, black or white.
#[test]
fn minified_textures_read_their_mip_chain_averaged_in_linear_space() {
    use strata::render::gbuffer_layout::ALBEDO;
    use strata::scene::{MipFilter, Sampler, Texture, TextureImage, TextureRef, Wrap};
    let gpu = common::GpuTest::raster_only();
    let pass = pass(&gpu);
    let side = 256u32;
    let rgba8: Vec<u8> = (0..side * side)
        .flat_map(|i| {
            let v = if (i % side + i / side) % 2 == 0 { 255 } else { 0 };
            [v, v, v, 255]
        })
        .collect();
    let cam = camera(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, Lens::PINHOLE);
    let mut scene = scene_of(plane(Vec2::splat(2.0), Vec2::ONE, None), Mat4::IDENTITY, None, cam);
    scene.images = vec![TextureImage { name: "checker".into(), width: side, height: side, rgba8 }];
    scene.materials[0].base_color_texture = Some(TextureRef { texture: 0, tex_coord: 0, transform: None });
    for mipmaps in [MipFilter::Linear, MipFilter::None] {
        let sampler = Sampler { mipmaps, ..common::scenes::nearest_sampler(Wrap::Repeat) };
        scene.textures = vec![Texture { name: "checker".into(), image: 0, sampler, srgb: true }];
        let frame = render(&gpu, &pass, &scene, (16, 16), Vec2::splat(0.5));
        let mut albedos = Vec::new();
        each_covered_pixel(&frame, |x, y| albedos.push(frame.at(ALBEDO, x, y)[0]));
        let (low, high) = albedos.iter().fold((f32::MAX, f32::MIN), |(l, h), &a| (l.min(a), h.max(a)));
        if mipmaps == MipFilter::None {
            assert!(low < 0.01 && high > 0.99, "level 0 alone: single texels, black and white: {low}..{high}");
        } else {
            // The G-buffer stores albedo as 8-bit sRGB: 0.5 comes back within one step (0.0039 here).
            assert!((low - 0.5).abs() < 0.005 && (high - 0.5).abs() < 0.005, "mipmapped: {low}..{high}, not 0.5");
        }
    }
    drop(pass);
    gpu.finish().unwrap();
}
