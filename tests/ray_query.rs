//! Ray-query smoke test: a BLAS of two triangles, a TLAS with two instances at known transforms, and a compute
//! shader that casts known rays; hit/miss, distance, custom index and instance id are checked per ray.
use crate::common;

use glam::{Mat4, Vec3};
use strata::render::ray_probe::{ProbeRay, RayProbe};
use strata::vk::accel::{AccelerationStructure, TlasInstance, TriangleGeometry, BUILD_INPUT_USAGE};
use strata::vk::Buffer;

#[test]
fn rays_hit_the_instances_they_aim_at() {
    let gpu = common::GpuTest::ray_queries();
    let device = gpu.device();
    // A unit square in the z = 0 plane, [−0.5, 0.5]², as two triangles.
    let positions =
        [Vec3::new(-0.5, -0.5, 0.0), Vec3::new(0.5, -0.5, 0.0), Vec3::new(0.5, 0.5, 0.0), Vec3::new(-0.5, 0.5, 0.0)];
    let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let vertex_buffer = Buffer::with_data(device, "square positions", &positions, BUILD_INPUT_USAGE, 16).unwrap();
    let index_buffer = Buffer::with_data(device, "square indices", &indices, BUILD_INPUT_USAGE, 16).unwrap();
    let blas = AccelerationStructure::build_blas(
        device,
        "square BLAS",
        &[TriangleGeometry {
            vertex_address: vertex_buffer.address,
            vertex_stride: 12,
            vertex_count: 4,
            index_address: index_buffer.address,
            triangle_count: 2,
            opaque: true,
        }],
    )
    .unwrap();
    // Instance 0: at z = −5, scaled ×2 (covers [−1, 1]²). Instance 1: at x = 10, z = −3, turned 90° about Y so
    // it faces +X (covers y, z within ±0.5 of its centre).
    let transforms = [
        Mat4::from_translation(Vec3::new(0.0, 0.0, -5.0)) * Mat4::from_scale(Vec3::splat(2.0)),
        Mat4::from_translation(Vec3::new(10.0, 0.0, -3.0)) * Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2),
    ];
    let instances = [
        TlasInstance { blas: &blas, transform: transforms[0], custom_index: 7, mask: 0xff },
        TlasInstance { blas: &blas, transform: transforms[1], custom_index: 42, mask: 0xff },
    ];
    let tlas = AccelerationStructure::build_tlas(device, "smoke TLAS", &instances).unwrap();
    let ray = |origin: Vec3, direction: Vec3| ProbeRay::closest(origin, direction, 0.0, 100.0);
    let rays = [
        ray(Vec3::ZERO, -Vec3::Z),                         // 0: hits instance 0 at t = 5
        ray(Vec3::new(0.9, -0.9, 1.0), -Vec3::Z),          // 1: inside the scaled square, t = 6
        ray(Vec3::new(1.1, 0.0, 0.0), -Vec3::Z),           // 2: just outside the scaled square: miss
        ray(Vec3::new(0.0, 0.0, -3.0), Vec3::X),           // 3: hits instance 1 at t = 10
        ray(Vec3::new(0.0, 0.4, -3.4), Vec3::X * 2.0),     // 4: unnormalised direction: t = 5 (ray units)
        ray(Vec3::new(0.0, 0.0, -3.0), -Vec3::X),          // 5: away from everything: miss
        ray(Vec3::new(0.0, 0.0, -6.0), Vec3::Z),           // 6: from behind instance 0 (cull disabled): t = 1
        ProbeRay::closest(Vec3::ZERO, -Vec3::Z, 0.0, 4.0), // 7: t_max short: miss
        // Shadow rays (the first hit ends them), as the accumulation pass casts and the benchmark replays:
        ProbeRay { flags: ProbeRay::FIRST_HIT, ..ray(Vec3::new(0.0, 0.0, -3.0), Vec3::X) }, // 8: t = 10
        ProbeRay { flags: ProbeRay::FIRST_HIT, t_max: 9.0, ..ray(Vec3::new(0.0, 0.0, -3.0), Vec3::X) }, // 9: miss
    ];
    // (hit, t, custom index, instance id)
    let expected: [(bool, f32, i32, i32); 10] = [
        (true, 5.0, 7, 0),
        (true, 6.0, 7, 0),
        (false, -1.0, -1, -1),
        (true, 10.0, 42, 1),
        (true, 5.0, 42, 1),
        (false, -1.0, -1, -1),
        (true, 1.0, 7, 0),
        (false, -1.0, -1, -1),
        (true, 10.0, 42, 1),
        (false, -1.0, -1, -1),
    ];
    let probe = RayProbe::new(device).unwrap();
    let hits = probe.cast(&tlas, &rays).unwrap();
    assert_eq!(hits.len(), rays.len());
    for (i, (hit, want)) in hits.iter().zip(expected).enumerate() {
        assert_eq!(hit.is_hit(), want.0, "ray {i}: hit/miss; got {hit:?}");
        if want.0 {
            assert!((hit.t - want.1).abs() < 1e-4, "ray {i}: t = {} want {}", hit.t, want.1);
            assert_eq!(hit.instance_custom_index, want.2, "ray {i}: custom index");
            assert_eq!(hit.instance_id, want.3, "ray {i}: instance id");
            assert!(hit.primitive_id == 0 || hit.primitive_id == 1, "ray {i}: primitive {}", hit.primitive_id);
        }
    }
}
