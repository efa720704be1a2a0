//! The project's own scenes, built in code and written to `scenes/` by `cargo run --example make_scenes`.
//! `tests/scenes.rs` checks that the committed files equal what this code writes.
use super::camera::look_at;
use super::shapes::{cuboid, plane, uv_sphere};
use super::surface::compute_surface_derivatives;
use super::{Camera, Instance, Material, Mesh, Node, NodeTransform, Primitive, Projection, Scene};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::path::PathBuf;

/// A unit sphere of material `material` at the origin (96 × 48 segments), seen down −Z from `distance` through a
/// pinhole of `yfov_degrees`: what the white-furnace and environment checks look at (tests/environment.rs,
/// `examples/furnace_rings.rs`). It covers tan(asin(1 / distance)) / tan(yfov / 2) of the image's half height.
pub fn add_sphere_in_view(scene: &mut Scene, material: usize, distance: f32, yfov_degrees: f32) {
    place(scene, "sphere", uv_sphere(1.0, 96, 48, Some(material)), Mat4::IDENTITY);
    scene.camera = Some(Camera {
        name: "front".into(),
        world_from_camera: look_at(Vec3::new(0.0, 0.0, distance), Vec3::ZERO, Vec3::Y),
        projection: Projection::Perspective { yfov: yfov_degrees.to_radians(), znear: 0.1, zfar: Some(100.0) },
        lens: super::camera::Lens::PINHOLE,
    });
}

/// Every scene in the library by file stem.
pub fn all() -> Vec<(&'static str, Scene)> {
    vec![
        ("cornell", cornell()),
        ("dof", dof()),
        ("motion", motion()),
        ("soft-shadows", soft_shadows()),
        ("showcase", showcase()),
    ]
}

/// Adds `primitive` (its surface derivatives computed) as a mesh of its own, placed by a root node of its own;
/// returns the node's index (what motion refers to).
pub fn place(scene: &mut Scene, name: &str, mut primitive: Primitive, world_from_object: Mat4) -> usize {
    compute_surface_derivatives(&mut primitive);
    scene.meshes.push(Mesh { name: name.into(), primitives: vec![primitive] });
    let mesh = scene.meshes.len() - 1;
    let node = scene.nodes.len();
    scene.nodes.push(Node {
        name: name.into(),
        parent: None,
        children: Vec::new(),
        transform: NodeTransform::Matrix(world_from_object),
        mesh: Some(mesh),
        camera: None,
        light: None,
        category: None,
        skin: None,
    });
    scene.roots.push(node);
    let node_from_object = Mat4::IDENTITY;
    scene.instances.push(Instance { name: name.into(), mesh, node: Some(node), world_from_object, node_from_object });
    node
}

struct Builder {
    scene: Scene,
}

impl Builder {
    fn new(name: &str) -> Self {
        Self { scene: Scene { source: PathBuf::from(format!("scenes/{name}.gltf")), ..Default::default() } }
    }

    /// A diffuse (dielectric, fairly rough) material.
    fn material(&mut self, name: &str, rgb: [f32; 3]) -> usize {
        self.material_with(Material {
            name: name.into(),
            base_color: Vec4::new(rgb[0], rgb[1], rgb[2], 1.0),
            ..matte()
        })
    }

    fn material_with(&mut self, material: Material) -> usize {
        self.scene.materials.push(material);
        self.scene.materials.len() - 1
    }

    fn place(&mut self, name: &str, primitive: Primitive, world_from_object: Mat4) {
        place(&mut self.scene, name, primitive, world_from_object);
    }

    fn finish(mut self) -> Scene {
        self.scene.cameras = self.scene.camera.iter().cloned().collect();
        self.scene
    }

    fn camera(&mut self, eye: Vec3, target: Vec3, yfov_degrees: f32) {
        self.scene.camera = Some(Camera {
            name: "camera".into(),
            world_from_camera: look_at(eye, target, Vec3::Y),
            projection: Projection::Perspective { yfov: yfov_degrees.to_radians(), znear: 0.05, zfar: Some(100.0) },
            lens: super::camera::Lens::PINHOLE,
        });
    }
}

fn matte() -> Material {
    Material { metallic: 0.0, roughness: 0.8, ..Default::default() }
}

/// A wall: a `size`² plane at `centre` facing `normal` (one of ±X, ±Y, ±Z), UVs in metres.
fn wall(size: f32, centre: Vec3, normal: Vec3, material: usize) -> (Primitive, Mat4) {
    let rotation = Quat::from_rotation_arc(Vec3::Y, normal);
    (plane(Vec2::splat(size), Vec2::splat(size), Some(material)), Mat4::from_rotation_translation(rotation, centre))
}

/// The Cornell box (Goral et al. 1984), 2 m on a side: white floor, ceiling and back, red left and green right
/// walls, two white boxes, and an emissive square in the ceiling as the area light.
pub fn cornell() -> Scene {
    let mut b = Builder::new("cornell");
    let white = b.material("white wall", [0.73, 0.73, 0.73]);
    let red = b.material("red wall", [0.63, 0.065, 0.05]);
    let green = b.material("green wall", [0.14, 0.45, 0.091]);
    let light = b.material_with(Material {
        name: "ceiling light".into(),
        base_color: Vec4::new(0.78, 0.78, 0.78, 1.0),
        emissive: Vec3::new(17.0, 12.0, 4.0),
        ..matte()
    });
    for (name, centre, normal, material) in [
        ("floor", Vec3::ZERO, Vec3::Y, white),
        ("ceiling", Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, white),
        ("back wall", Vec3::new(0.0, 1.0, -1.0), Vec3::Z, white),
        ("left wall", Vec3::new(-1.0, 1.0, 0.0), Vec3::X, red),
        ("right wall", Vec3::new(1.0, 1.0, 0.0), Vec3::NEG_X, green),
    ] {
        let (primitive, transform) = wall(2.0, centre, normal, material);
        b.place(name, primitive, transform);
    }
    let (lamp, lamp_transform) = wall(0.5, Vec3::new(0.0, 1.999, 0.0), Vec3::NEG_Y, light);
    b.place("ceiling light", lamp, lamp_transform);
    b.place(
        "tall box",
        cuboid(Vec3::new(0.3, 0.6, 0.3), Some(white)),
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.3), Vec3::new(-0.33, 0.6, -0.3)),
    );
    b.place(
        "short box",
        cuboid(Vec3::splat(0.3), Some(white)),
        Mat4::from_rotation_translation(Quat::from_rotation_y(-0.3), Vec3::new(0.35, 0.3, 0.35)),
    );
    b.camera(Vec3::new(0.0, 1.0, 3.9), Vec3::new(0.0, 1.0, 0.0), 39.0);
    b.finish()
}

/// Depth of field: five spheres in a row receding from the camera (2 to 10 m), on a floor; the scene file
/// focuses on the middle one.
pub fn dof() -> Scene {
    let mut b = Builder::new("dof");
    let floor = b.material("floor", [0.5, 0.5, 0.5]);
    let colours = [[0.8, 0.2, 0.1], [0.9, 0.6, 0.1], [0.2, 0.7, 0.2], [0.1, 0.4, 0.8], [0.5, 0.2, 0.7]];
    b.place("floor", plane(Vec2::new(20.0, 40.0), Vec2::new(20.0, 40.0), Some(floor)), Mat4::IDENTITY);
    for (i, rgb) in colours.iter().enumerate() {
        let m = b.material(&format!("sphere {i}"), *rgb);
        let depth = 2.0 + 2.0 * i as f32;
        b.place(
            &format!("sphere at {depth} m"),
            uv_sphere(0.4, 48, 24, Some(m)),
            Mat4::from_translation(Vec3::new(-1.2 + 0.6 * i as f32, 0.4, -depth)),
        );
    }
    b.camera(Vec3::new(0.0, 0.6, 0.0), Vec3::new(0.0, 0.4, -6.0), 40.0);
    b.finish()
}

/// Motion blur: a box sliding left to right, a spinning slab and a falling sphere (their motion is in the scene
/// file), and a still reference box.
pub fn motion() -> Scene {
    let mut b = Builder::new("motion");
    let floor = b.material("floor", [0.45, 0.45, 0.45]);
    let red = b.material("red", [0.8, 0.15, 0.1]);
    let blue = b.material("blue", [0.15, 0.3, 0.8]);
    let yellow = b.material("yellow", [0.9, 0.75, 0.2]);
    let grey = b.material("grey", [0.6, 0.6, 0.6]);
    b.place("floor", plane(Vec2::splat(12.0), Vec2::splat(12.0), Some(floor)), Mat4::IDENTITY);
    b.place("sliding box", cuboid(Vec3::splat(0.3), Some(red)), Mat4::from_translation(Vec3::new(-1.5, 0.3, 0.0)));
    b.place(
        "spinning slab",
        cuboid(Vec3::new(0.8, 0.1, 0.2), Some(blue)),
        Mat4::from_translation(Vec3::new(0.5, 1.0, -0.5)),
    );
    b.place("falling sphere", uv_sphere(0.3, 48, 24, Some(yellow)), Mat4::from_translation(Vec3::new(1.6, 1.6, 0.3)));
    b.place("still box", cuboid(Vec3::splat(0.25), Some(grey)), Mat4::from_translation(Vec3::new(-0.4, 0.25, -1.5)));
    b.camera(Vec3::new(0.0, 1.4, 4.5), Vec3::new(0.0, 0.6, 0.0), 40.0);
    b.finish()
}

/// Soft shadows: three thin square occluders on posts above a floor, each under its own area light of a
/// different size (the lights are in the scene file), so the penumbrae differ.
pub fn soft_shadows() -> Scene {
    let mut b = Builder::new("soft-shadows");
    let floor = b.material("floor", [0.7, 0.7, 0.7]);
    let occluder = b.material("occluder", [0.3, 0.3, 0.35]);
    b.place("floor", plane(Vec2::new(12.0, 8.0), Vec2::new(12.0, 8.0), Some(floor)), Mat4::IDENTITY);
    for (i, x) in [-2.5f32, 0.0, 2.5].into_iter().enumerate() {
        b.place(
            &format!("occluder {i}"),
            cuboid(Vec3::new(0.5, 0.02, 0.5), Some(occluder)),
            Mat4::from_translation(Vec3::new(x, 0.8, 0.0)),
        );
        b.place(
            &format!("post {i}"),
            cuboid(Vec3::new(0.03, 0.39, 0.03), Some(occluder)),
            Mat4::from_translation(Vec3::new(x, 0.39, 0.0)),
        );
    }
    b.camera(Vec3::new(0.0, 4.0, 5.0), Vec3::new(0.0, 0.3, 0.0), 45.0);
    b.finish()
}

/// The README's picture: objects of several shapes and colours at increasing depth on a floor.
pub fn showcase() -> Scene {
    let mut b = Builder::new("showcase");
    let floor = b.material("floor", [0.55, 0.52, 0.48]);
    let red = b.material("red clay", [0.7, 0.12, 0.08]);
    let blue = b.material_with(Material {
        name: "blue glaze".into(),
        base_color: Vec4::new(0.1, 0.25, 0.7, 1.0),
        roughness: 0.15,
        ..matte()
    });
    let gold = b.material_with(Material {
        name: "gold".into(),
        base_color: Vec4::new(1.0, 0.78, 0.34, 1.0),
        metallic: 1.0,
        roughness: 0.25,
        ..matte()
    });
    let green = b.material("green stone", [0.15, 0.5, 0.25]);
    let white = b.material_with(Material {
        name: "glass".into(),
        base_color: Vec4::new(0.95, 0.95, 0.95, 1.0),
        roughness: 0.05,
        transmission: 1.0,
        ior: 1.5,
        ..matte()
    });
    b.place("floor", plane(Vec2::new(16.0, 16.0), Vec2::new(8.0, 8.0), Some(floor)), Mat4::IDENTITY);
    b.place(
        "red box",
        cuboid(Vec3::splat(0.45), Some(red)),
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(-1.4, 0.45, 0.6)),
    );
    b.place("blue sphere", uv_sphere(0.6, 48, 24, Some(blue)), Mat4::from_translation(Vec3::new(0.2, 0.6, 0.0)));
    b.place("gold sphere", uv_sphere(0.4, 48, 24, Some(gold)), Mat4::from_translation(Vec3::new(1.5, 0.4, 1.2)));
    b.place(
        "green pillar",
        cuboid(Vec3::new(0.3, 1.0, 0.3), Some(green)),
        Mat4::from_rotation_translation(Quat::from_rotation_y(-0.3), Vec3::new(1.8, 1.0, -2.2)),
    );
    b.place("glass sphere", uv_sphere(0.5, 48, 24, Some(white)), Mat4::from_translation(Vec3::new(-1.9, 0.5, -3.0)));
    b.camera(Vec3::new(0.0, 1.7, 5.5), Vec3::new(0.0, 0.5, -0.5), 40.0);
    b.finish()
}
