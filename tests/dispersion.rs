//! KHR_materials_dispersion through the renderer: a tilted glass slab shifts what lies behind it sideways by an
//! amount that depends on the index of refraction, so each colour channel of an edge seen through a dispersive
//! slab lands where Snell's law with that channel's index puts it, and through a slab without dispersion all three
//! land together; in a white furnace a dispersive sphere still returns exactly the light that reaches it.
use crate::common;
use common::scenes::{emitter, ortho_down, place, plane_at, render, settings};
use common::GpuTest;
use glam::{Mat4, Vec2, Vec3, Vec4};
use strata::math::dispersion::dispersed_ior;
use strata::scene::environment::Environment;
use strata::scene::settings::{RenderSettings, SamplerKind, Trace};
use strata::scene::{Material, Scene};

const TILT: f32 = std::f32::consts::FRAC_PI_4;
// Metres: large beside the rays' origin offset off a surface (about 1e-4 m, path_vertex.glsl's offset_origin), which
// at a tenth of this scale moved the edges by 0.4 px.
const THICKNESS: f32 = 5.0;
const IOR: f32 = 1.5;
const DISPERSION: f32 = 2.0;
const EMITTER_Y: f32 = -30.0;

fn glass(name: &str, dispersion: f32) -> Material {
    Material {
        name: name.into(),
        base_color: Vec4::ONE,
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: IOR,
        dispersion,
        ..Default::default()
    }
}

/// Refracts unit direction `d` at a surface of unit normal `n` (facing against `d`) from index 1 into index `eta`
/// times the one it leaves (vector Snell's law); None on total internal reflection.
fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| eta * d + (eta * cos_i - k.sqrt()) * n)
}

/// How far sideways (world x) a ray going straight down lands on the emitter's plane after crossing the slab of
/// index `n` (its faces' normal `normal`, its middle at the origin): Snell's law at both faces, by hand.
fn lateral_shift(n: f32, normal: Vec3) -> f32 {
    let (origin, down) = (Vec3::new(0.0, 50.0, 0.0), Vec3::NEG_Y);
    let plane_hit = |o: Vec3, d: Vec3, point: Vec3| o + d * ((point - o).dot(normal) / d.dot(normal));
    let entry = plane_hit(origin, down, normal * THICKNESS / 2.0);
    let inside = refract(down, normal, 1.0 / n).unwrap();
    let exit = plane_hit(entry, inside, -normal * THICKNESS / 2.0);
    let out = refract(inside, normal, n).unwrap();
    let landing = exit + out * ((EMITTER_Y - exit.y) / out.y);
    assert!((out - down).length() < 1e-5, "a parallel slab leaves the direction as it was");
    landing.x - origin.x
}

/// Two slabs side by side in z, one dispersive (z < 0) and one not (z > 0), both tilted 45° about z, over an
/// emitter that covers x > 0: seen from above, each channel's edge is where the rays that cross the slab land on
/// x = 0, so it sits at x = −(that channel's lateral shift). Measured as the area under each channel's profile
/// (the edge of a box-filtered step, insensitive to noise), row by row; the tolerance is 4 standard errors of the
/// rows' mean plus 0.05 px.
#[test]
fn a_tilted_dispersive_slab_shifts_each_channel_by_its_own_refraction() {
    let gpu = GpuTest::new();
    let mut scene = Scene::default();
    scene.materials.push(glass("dispersive glass", DISPERSION));
    scene.materials.push(glass("plain glass", 0.0));
    let light = emitter(&mut scene, 1.0);
    let tilt = Mat4::from_rotation_z(TILT);
    let normal = tilt.transform_vector3(Vec3::Y);
    // 2 cm apart in z: rays inside a slab travel in x and y alone, so its side faces never meet them.
    for (material, z) in [(0, -5.0), (1, 5.0)] {
        let slab = strata::scene::shapes::cuboid(Vec3::new(20.0, THICKNESS / 2.0, 4.99), Some(material));
        place(&mut scene, "slab", slab, Mat4::from_translation(Vec3::Z * z) * tilt);
    }
    let (plane, at) = plane_at(Vec2::new(80.0, 80.0), Vec3::new(40.0, EMITTER_Y, 0.0), false, light);
    place(&mut scene, "emitter", plane, at);
    let shifts: [f32; 3] = std::array::from_fn(|c| lateral_shift(dispersed_ior(IOR, DISPERSION, c), normal));
    let plain = lateral_shift(IOR, normal);
    // The view: 128 px over 64 cm around the green edge, 5 mm per pixel; both slabs in view (z = ±32 cm).
    let (size, half) = (128u32, 0.32f32);
    let centre_x = -shifts[1];
    scene.camera = Some(ortho_down(Vec3::new(centre_x, 0.0, 0.0), 50.0, half));
    let s = RenderSettings { bounces: 4, ..settings(size, size, 128, SamplerKind::MultiJittered) };
    let frame = render(gpu.device(), &scene, &s);
    let pixel = 2.0 * half / size as f32;
    // Image x is world x (ortho_down); a channel's edge, in pixels from the left, for its world x.
    let column_of = |x: f32| (x - (centre_x - half)) / pixel;
    // Rows inside each slab (image y is world z: the dispersive slab above the middle, the plain one below).
    const WINDOW: f64 = 8.0;
    for (name, rows, expected) in
        [("dispersive", 4..60u32, shifts.map(|s| column_of(-s))), ("plain", 68..124u32, [column_of(-plain); 3])]
    {
        let mut edges = Vec::new();
        for (c, want) in expected.into_iter().enumerate() {
            let want = f64::from(want);
            let value = |x: u32, y: u32| f64::from(frame.linear.pixels[(y * size + x) as usize][c]);
            // The radiance the slab passes: the mean over every row of the 20 columns right of the window.
            let right = (want + WINDOW).ceil() as u32 + 2;
            let bright: Vec<f64> =
                rows.clone().flat_map(|y| (right..right + 20).map(move |x| (x, y))).map(|(x, y)| value(x, y)).collect();
            let (plateau, plateau_se) = mean_and_se(&bright);
            // A box-filtered step's edge from the area under it: (window's end) − Σ value / plateau.
            let (lo, hi) = ((want - WINDOW).floor() as u32, (want + WINDOW).ceil() as u32);
            let per_row: Vec<f64> =
                rows.clone().map(|y| f64::from(hi) - (lo..hi).map(|x| value(x, y)).sum::<f64>() / plateau).collect();
            let (got, se) = mean_and_se(&per_row);
            // The plateau's own error moves every row's edge alike, by up to the window's width times it.
            let se = (se * se + (f64::from(hi - lo) * plateau_se / plateau).powi(2)).sqrt();
            eprintln!("{name} slab, channel {c}: edge at {got:.3} ± {se:.3} px, Snell's law {want:.3} px");
            // Refraction through a slab in strata lands 0.23 px (plain) to 0.52 px (dispersive) short of Snell's
            // law here, a common offset of every channel (the rays' origin offsets off each face, the GGX lobe's
            // floor of α = 10⁻³): allowed 0.6 px on top of the noise. The channels' spacing is held tighter below.
            assert!((got - want).abs() <= 4.0 * se + 0.6, "{name}, channel {c}: {got} ± {se}, want {want}");
            edges.push((got, se, want));
        }
        // Red and blue apart by what their indices make of the slab, free of the common offset.
        let ((red, red_se, red_want), (blue, blue_se, blue_want)) = (edges[0], edges[2]);
        let (spacing, spacing_want) = (red - blue, red_want - blue_want);
        let spacing_se = (red_se * red_se + blue_se * blue_se).sqrt();
        eprintln!("{name} slab: red − blue {spacing:.3} ± {spacing_se:.3} px, Snell's law {spacing_want:.3} px");
        assert!((spacing - spacing_want).abs() <= 4.0 * spacing_se + 0.1, "{name}: red − blue {spacing} px");
    }
    // The claim has teeth: through the dispersive slab red and blue land many pixels apart.
    let spread = column_of(-shifts[0]) - column_of(-shifts[2]);
    assert!(spread.abs() > 10.0, "red and blue {spread} px apart");
    gpu.finish().unwrap();
}

/// In a white furnace (uniform environment of radiance 1) a clear dielectric sphere reflects and refracts all the
/// light that reaches it, whatever its index, so a dispersive one, each channel refracted by its own index, shows
/// 1 in every channel: the mean over the sphere within 4 standard errors (the channel choice is noise, not bias).
/// Smooth (roughness 0): a rough dielectric's single-scattering microfacet lobes lose a few percent on their own.
#[test]
fn a_dispersive_sphere_in_a_white_furnace_returns_one_in_every_channel() {
    let gpu = GpuTest::new();
    let mut scene = Scene::default();
    scene.materials.push(glass("dispersive glass", 1.0));
    strata::scene::library::add_sphere_in_view(&mut scene, 0, 5.0, 30.0);
    scene.environment = Some(Environment::uniform(Vec3::ONE));
    // One way to trace (the slab above holds the two to the same bits), so the test compiles one pipeline.
    let s = RenderSettings {
        indirect: true,
        bounces: 16,
        trace: Trace::Query,
        ..settings(48, 48, 64, SamplerKind::MultiJittered)
    };
    let frame = render(gpu.device(), &scene, &s);
    let covered: Vec<&[f32; 4]> = frame.linear.pixels.iter().filter(|p| p[3] >= 1.0).collect();
    assert!(covered.len() > 200, "{} pixels on the sphere", covered.len());
    for c in 0..3 {
        let values: Vec<f64> = covered.iter().map(|p| f64::from(p[c])).collect();
        let (mean, se) = mean_and_se(&values);
        eprintln!("channel {c}: {mean:.4} ± {se:.4} over {} pixels", values.len());
        assert!((mean - 1.0).abs() <= 4.0 * se + 0.003, "channel {c}: {mean} ± {se}, not 1");
    }
    gpu.finish().unwrap();
}

/// The mean of `values` and its standard error.
fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}
