//! The project's own scenes, built in code and written to `scenes/` by `cargo run --example make_scenes`.
//! `tests/scenes.rs` checks that the committed files equal what this code writes.
use super::camera::look_at;
use super::shapes::{cuboid, plane, uv_sphere};
use super::surface::compute_surface_derivatives;
use super::{Camera, Instance, Material, Mesh, Node, NodeTransform, Primitive, Projection, Scene};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::path::PathBuf;

/// Every scene in the library by file stem.
pub fn all() -> Vec<(&'static str, Scene)> {
    vec![("showcase", showcase())]
}

struct Builder {
    scene: Scene,
}

impl Builder {
    fn new(name: &str) -> Self {
        Self { scene: Scene { source: PathBuf::from(format!("scenes/{name}.gltf")), ..Default::default() } }
    }

    fn material(&mut self, name: &str, rgb: [f32; 3]) -> usize {
        self.scene.materials.push(Material {
            name: name.into(),
            base_color: Vec4::new(rgb[0], rgb[1], rgb[2], 1.0),
            metallic: 0.0,
            roughness: 0.5,
            ..Default::default()
        });
        self.scene.materials.len() - 1
    }

    fn place(&mut self, name: &str, mut primitive: Primitive, world_from_object: Mat4) {
        compute_surface_derivatives(&mut primitive);
        self.scene.meshes.push(Mesh { name: name.into(), primitives: vec![primitive] });
        let mesh = self.scene.meshes.len() - 1;
        let node = self.scene.nodes.len();
        self.scene.nodes.push(Node {
            name: name.into(),
            parent: None,
            children: Vec::new(),
            transform: NodeTransform::Matrix(world_from_object),
            mesh: Some(mesh),
            camera: None,
            light: None,
        });
        self.scene.roots.push(node);
        self.scene.instances.push(Instance { name: name.into(), mesh, node: Some(node), world_from_object });
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

/// The README's picture: objects of several shapes and colours at increasing depth on a floor.
pub fn showcase() -> Scene {
    let mut b = Builder::new("showcase");
    let floor = b.material("floor", [0.55, 0.52, 0.48]);
    let red = b.material("red clay", [0.7, 0.12, 0.08]);
    let blue = b.material("blue glaze", [0.1, 0.25, 0.7]);
    let gold = b.material("gold", [0.9, 0.65, 0.2]);
    let green = b.material("green stone", [0.15, 0.5, 0.25]);
    let white = b.material("white", [0.85, 0.85, 0.85]);
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
    b.place("white sphere", uv_sphere(0.5, 48, 24, Some(white)), Mat4::from_translation(Vec3::new(-1.9, 0.5, -3.0)));
    b.camera(Vec3::new(0.0, 1.7, 5.5), Vec3::new(0.0, 0.5, -0.5), 40.0);
    b.finish()
}
