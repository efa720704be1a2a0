//! glTF 2.0 import: the default scene's node hierarchy flattened into placed meshes, materials and the
//! first camera. Every error names the file and what is wrong with it.
use super::{Camera, Instance, Material, Mesh, Primitive, Projection, Scene};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::path::Path;

/// Loads a `.gltf` or `.glb` file.
pub fn load_gltf(path: &Path) -> Result<Scene> {
    let shown = path.display();
    if !path.is_file() {
        bail!("{shown}: no such file");
    }
    let gltf = gltf::Gltf::open(path).map_err(|e| anyhow!("{shown}: not a valid glTF file: {e}"))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())
        .map_err(|e| anyhow!("{shown}: cannot load buffers: {e}"))?;
    import_document(path, &gltf.document, &buffers)
}

fn import_document(path: &Path, document: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Result<Scene> {
    let shown = path.display();
    let materials: Vec<Material> = document
        .materials()
        .map(|m| Material {
            name: m.name().map(str::to_owned).unwrap_or_else(|| format!("material {}", m.index().unwrap_or(0))),
            base_color: Vec4::from_array(m.pbr_metallic_roughness().base_color_factor()),
        })
        .collect();

    let mut meshes = Vec::new();
    for mesh in document.meshes() {
        let name = mesh.name().map(str::to_owned).unwrap_or_else(|| format!("mesh {}", mesh.index()));
        let mut primitives = Vec::new();
        for (p_index, primitive) in mesh.primitives().enumerate() {
            let what = format!("{shown}: {name}, primitive {p_index}");
            primitives.push(import_primitive(&primitive, buffers).with_context(|| what)?);
        }
        meshes.push(Mesh { name, primitives });
    }

    let scene = document.default_scene().or_else(|| document.scenes().next());
    let mut instances = Vec::new();
    let mut camera = None;
    if let Some(scene) = scene {
        for node in scene.nodes() {
            visit_node(&node, Mat4::IDENTITY, &mut instances, &mut camera, 0)
                .with_context(|| format!("{shown}: in the node hierarchy"))?;
        }
    }
    Ok(Scene { source: path.to_path_buf(), meshes, materials, instances, camera })
}

fn visit_node(
    node: &gltf::Node<'_>,
    parent: Mat4,
    instances: &mut Vec<Instance>,
    camera: &mut Option<Camera>,
    depth: usize,
) -> Result<()> {
    // glTF forbids cycles (§3.5.1); a malformed file could still have one.
    if depth > 1024 {
        bail!("node {} is nested over 1024 deep (a cycle?)", node.index());
    }
    let local = Mat4::from_cols_array_2d(&node.transform().matrix());
    let world = parent * local;
    let name = node.name().map(str::to_owned).unwrap_or_else(|| format!("node {}", node.index()));
    if !world.is_finite() {
        bail!("{name}: transform is not finite");
    }
    if let Some(mesh) = node.mesh() {
        instances.push(Instance { name: name.clone(), mesh: mesh.index(), world_from_object: world });
    }
    if let (Some(cam), None) = (node.camera(), camera.as_ref()) {
        let projection = match cam.projection() {
            gltf::camera::Projection::Perspective(p) => {
                Projection::Perspective { yfov: p.yfov(), znear: p.znear(), zfar: p.zfar() }
            }
            gltf::camera::Projection::Orthographic(o) => {
                Projection::Orthographic { xmag: o.xmag(), ymag: o.ymag(), znear: o.znear(), zfar: o.zfar() }
            }
        };
        // Cameras must not be scaled (§3.10.1); remove any scale so the view stays rigid.
        let (_, rotation, translation) = world.to_scale_rotation_translation();
        *camera = Some(Camera {
            name: cam.name().map(str::to_owned).unwrap_or(name.clone()),
            world_from_camera: Mat4::from_rotation_translation(rotation, translation),
            projection,
        });
    }
    for child in node.children() {
        visit_node(&child, world, instances, camera, depth + 1)?;
    }
    Ok(())
}

fn import_primitive(primitive: &gltf::Primitive<'_>, buffers: &[gltf::buffer::Data]) -> Result<Primitive> {
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        bail!("mode {:?} is not supported (only TRIANGLES)", primitive.mode());
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| anyhow!("has no POSITION attribute (or its buffer is too short)"))?
        .map(Vec3::from_array)
        .collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        bail!("POSITION {i} is not finite ({})", positions[i]);
    }
    let indices: Vec<u32> = match reader.read_indices() {
        Some(indices) => indices.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    if indices.len() % 3 != 0 {
        bail!("{} indices do not make whole triangles", indices.len());
    }
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
        bail!("index {bad} is out of range ({} vertices)", positions.len());
    }
    let normals: Vec<Vec3> = match reader.read_normals() {
        Some(n) => n.map(|v| Vec3::from_array(v).normalize_or_zero()).collect(),
        None => Vec::new(),
    };
    let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
        Some(uv) => uv.into_f32().map(Vec2::from_array).collect(),
        None => Vec::new(),
    };
    if !uvs.is_empty() && uvs.len() != positions.len() {
        bail!("TEXCOORD_0 has {} entries for {} vertices", uvs.len(), positions.len());
    }
    let mut primitive_out = Primitive { positions, normals, uvs, indices, material: primitive.material().index() };
    if primitive_out.normals.len() != primitive_out.positions.len() {
        flatten_with_face_normals(&mut primitive_out);
    }
    Ok(primitive_out)
}

/// Without NORMAL, glTF asks for flat normals (§3.7.2.1): give every triangle its own three vertices.
fn flatten_with_face_normals(primitive: &mut Primitive) {
    let mut positions = Vec::with_capacity(primitive.indices.len());
    let mut normals = Vec::with_capacity(primitive.indices.len());
    let mut uvs = Vec::new();
    for tri in primitive.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| primitive.positions[tri[k] as usize]);
        // Zero-area triangles get a zero normal rather than NaN.
        let n = (b - a).cross(c - a).normalize_or_zero();
        positions.extend([a, b, c]);
        normals.extend([n, n, n]);
        if !primitive.uvs.is_empty() {
            uvs.extend(tri.iter().map(|&i| primitive.uvs[i as usize]));
        }
    }
    primitive.indices = (0..positions.len() as u32).collect();
    primitive.positions = positions;
    primitive.normals = normals;
    primitive.uvs = uvs;
}
