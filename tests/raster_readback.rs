//! Raster readback: known triangles into an 8×8 offscreen image, read back and checked texel by texel for
//! RGBA8, RGBA16F and RGBA32F targets.
//!
//! Triangle A covers framebuffer (0,0),(8,0),(0,8); triangle B the complement (8,0),(8,8),(0,8). Pixel (i, j) has
//! its centre at (i+½, j+½), so it lies inside A when i+j < 7, inside B when i+j > 7, and exactly on the shared
//! diagonal when i+j = 7. Vulkan's polygon rasterization rule (spec §28.7.1, "Basic Polygon Rasterization"): a sample
//! on an edge shared by two triangles is covered by exactly one of them. Blending is additive, so a pixel's value
//! counts its coverage: the test asserts zero, one colour or the other, never both and never neither.
use crate::common;

use ash::vk;
use glam::{Vec2, Vec4};
use strata::render::solid::{SolidDraw, SolidPass};
use strata::vk::readback::Readback;

const SIZE: u32 = 8;

/// Framebuffer pixel coordinates → clip space (Vulkan: y down in both).
fn clip(x: f32, y: f32) -> Vec2 {
    Vec2::new(2.0 * x / SIZE as f32 - 1.0, 2.0 * y / SIZE as f32 - 1.0)
}

fn triangle_a() -> [Vec2; 3] {
    [clip(0.0, 0.0), clip(8.0, 0.0), clip(0.0, 8.0)]
}

fn triangle_b() -> [Vec2; 3] {
    [clip(8.0, 0.0), clip(8.0, 8.0), clip(0.0, 8.0)]
}

/// Reads texel (x, y) as exact integers or floats (in a comparable form per format).
fn texel(readback: &Readback, x: u32, y: u32) -> [f32; 4] {
    match readback.format {
        vk::Format::R8G8B8A8_UNORM => {
            let t = readback.texel(x, y);
            [t[0] as f32, t[1] as f32, t[2] as f32, t[3] as f32]
        }
        _ => readback.to_rgba_f32().unwrap()[(y * readback.width + x) as usize],
    }
}

/// Runs the checks for one format; `a` and `b` are colours exact in that format, `expect` maps them to the
/// read-back representation.
fn check_format(format: vk::Format, a: Vec4, b: Vec4, expect: impl Fn(Vec4) -> [f32; 4]) {
    let gpu = common::GpuTest::raster_only();
    let pass = SolidPass::new(gpu.device(), format, true).unwrap();
    let zero = [0.0; 4];

    // A alone: inside exact, outside exactly zero, on the diagonal one or the other.
    let tri_a = triangle_a();
    let only_a = pass.draw(SIZE, SIZE, &[SolidDraw { vertices: &tri_a, color: a }]).unwrap();
    assert_eq!((only_a.width, only_a.height, only_a.row_pitch), (SIZE, SIZE, SIZE as usize * only_a.texel_size));
    let mut a_on_edge = 0;
    for j in 0..SIZE {
        for i in 0..SIZE {
            let got = texel(&only_a, i, j);
            match (i + j).cmp(&7) {
                std::cmp::Ordering::Less => assert_eq!(got, expect(a), "{format:?} A alone: inside pixel ({i},{j})"),
                std::cmp::Ordering::Greater => assert_eq!(got, zero, "{format:?} A alone: outside pixel ({i},{j})"),
                std::cmp::Ordering::Equal => {
                    assert!(got == expect(a) || got == zero, "{format:?} A alone: edge pixel ({i},{j}) = {got:?}");
                    a_on_edge += usize::from(got == expect(a));
                }
            }
        }
    }

    // A and B together: every pixel covered exactly once.
    let tri_b = triangle_b();
    let both = pass
        .draw(SIZE, SIZE, &[SolidDraw { vertices: &tri_a, color: a }, SolidDraw { vertices: &tri_b, color: b }])
        .unwrap();
    let mut b_on_edge = 0;
    for j in 0..SIZE {
        for i in 0..SIZE {
            let got = texel(&both, i, j);
            match (i + j).cmp(&7) {
                std::cmp::Ordering::Less => assert_eq!(got, expect(a), "{format:?} A+B: pixel ({i},{j})"),
                std::cmp::Ordering::Greater => assert_eq!(got, expect(b), "{format:?} A+B: pixel ({i},{j})"),
                std::cmp::Ordering::Equal => {
                    assert!(
                        got == expect(a) || got == expect(b),
                        "{format:?} A+B: shared-edge pixel ({i},{j}) covered {} times: {got:?}",
                        if got == zero { "zero" } else { "two" }
                    );
                    b_on_edge += usize::from(got == expect(b));
                }
            }
        }
    }
    // The shared edge is split consistently: what A did not take alone, B takes.
    assert_eq!(a_on_edge + b_on_edge, 8, "{format:?}: the 8 diagonal pixels split {a_on_edge} + {b_on_edge}");
    drop(pass);
    gpu.finish().unwrap();
}

#[test]
fn rgba8_unorm_triangles_read_back_exactly() {
    // k/255 is exact in UNORM8: compare the bytes.
    let a = Vec4::new(51.0, 102.0, 153.0, 100.0) / 255.0;
    let b = Vec4::new(17.0, 0.0, 34.0, 155.0) / 255.0;
    check_format(vk::Format::R8G8B8A8_UNORM, a, b, |c| (c * 255.0).round().to_array());
}

#[test]
fn rgba16f_triangles_read_back_exactly() {
    // Dyadic fractions are exact in half floats.
    let a = Vec4::new(0.25, 0.5, 0.75, 1.0);
    let b = Vec4::new(0.125, 2.0, 0.0, 0.5);
    check_format(vk::Format::R16G16B16A16_SFLOAT, a, b, |c| c.to_array());
}

#[test]
fn rgba32f_triangles_read_back_exactly() {
    let a = Vec4::new(0.1, 0.2, 0.3, 1.0);
    let b = Vec4::new(1e-3, 17.5, 0.0, 0.25);
    check_format(vk::Format::R32G32B32A32_SFLOAT, a, b, |c| c.to_array());
}
