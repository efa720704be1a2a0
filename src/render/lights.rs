//! The lights of one sample time as the accumulation pass reads them: the scene's lights (moved with their
//! nodes) and every emissive triangle, in world space, with a selection probability proportional to each
//! light's power (so bright lights get most of the shadow rays). Lights that are not geometry come first: the
//! shader intersects those analytically along specular rays; emissive triangles are in the TLAS.
use super::accumulate_layout::{light_kind, GpuLight};
use crate::scene::{LightShape, Scene};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use std::f32::consts::PI;

/// Emissive triangles beyond this many are still seen and reflected, but not sampled as lights (a warning says
/// so): the light buffer holds one record per triangle per sample in a batch.
pub const MAX_EMISSIVE_TRIANGLES: usize = 1 << 16;

/// One sample time's lights.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LightSet {
    pub lights: Vec<GpuLight>,
    /// `lights[..analytic]` are not geometry.
    pub analytic: usize,
    /// Emissive triangles not sampled because of `MAX_EMISSIVE_TRIANGLES`.
    pub skipped_triangles: usize,
    /// The sum of the selection powers; a light's probability is its power over this.
    pub total_power: f32,
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722)).max(0.0)
}

impl LightSet {
    /// The lights at time `t` (None: the rest pose), from the node transforms then (`Scene::node_world_transforms`)
    /// and the instance transforms they give (`Scene::instance_transforms_from`); emissive triangles of deformed
    /// (skinned or morphing) instances where the deformation puts them at `t`. `rest` are the node transforms at
    /// rest (`node_world_transforms(None)`, once per frame); `scene_radius` turns a directional light's
    /// irradiance into a power for selection.
    pub fn at(
        scene: &Scene,
        (t, moved): (Option<f32>, &[Mat4]),
        transforms: &[Mat4],
        rest: &[Mat4],
        scene_radius: f32,
    ) -> Self {
        let mut lights = Vec::new();
        let mut powers = Vec::new();
        // The environment comes first (the shader finds its selection probability there). Its power for
        // selection is what it would pour onto a disk of the scene's radius: π R² · π · mean radiance.
        if let Some(environment) = &scene.environment {
            lights.push(GpuLight {
                position_kind: Vec4::new(0.0, 0.0, 0.0, light_kind::ENVIRONMENT),
                axis_u: Vec4::ZERO,
                axis_v: Vec4::ZERO,
                normal: Vec4::ZERO,
                emission: Vec4::ZERO,
                cone: Vec4::ZERO,
                uv01: Vec4::ZERO,
                uv2_material: Vec4::new(0.0, 0.0, -1.0, 0.0),
                corner_alpha: Vec4::ONE,
                uv1_01: Vec4::ZERO,
                uv1_2: Vec4::ZERO,
            });
            powers.push(PI * scene_radius * scene_radius * PI * luminance(environment.mean_radiance()));
        }
        for light in &scene.lights {
            let world = match light.node {
                Some(n) if n < moved.len() && n < rest.len() => moved[n] * rest[n].inverse() * light.world_from_light,
                _ => light.world_from_light,
            };
            if !world.is_finite() {
                continue;
            }
            let position = world.w_axis.truncate();
            let x = world.x_axis.truncate();
            let y = world.y_axis.truncate();
            let travel = (-world.z_axis.truncate()).normalize_or_zero();
            let e = light.emission;
            let mut g = GpuLight {
                position_kind: position.extend(0.0),
                axis_u: Vec4::ZERO,
                axis_v: Vec4::ZERO,
                normal: travel.extend(0.0),
                emission: e.extend(0.0),
                // KHR_lights_punctual: range is not scaled by the node's transform.
                cone: Vec4::new(0.0, 0.0, light.range.max(0.0), 0.0),
                uv01: Vec4::ZERO,
                uv2_material: Vec4::new(0.0, 0.0, -1.0, 0.0),
                corner_alpha: Vec4::ONE,
                uv1_01: Vec4::ZERO,
                uv1_2: Vec4::ZERO,
            };
            let power = match light.shape {
                LightShape::Point { radius } => {
                    g.position_kind.w = light_kind::POINT;
                    g.axis_u.w = radius * x.length();
                    4.0 * PI * luminance(e)
                }
                LightShape::Spot { inner_cone, outer_cone, radius } => {
                    g.position_kind.w = light_kind::SPOT;
                    g.axis_u.w = radius * x.length();
                    (g.cone.x, g.cone.y) = (outer_cone.cos(), inner_cone.cos());
                    2.0 * PI * (1.0 - outer_cone.cos()).max(1e-4) * luminance(e)
                }
                LightShape::Directional => {
                    g.position_kind.w = light_kind::DIRECTIONAL;
                    PI * scene_radius * scene_radius * luminance(e)
                }
                LightShape::Quad { size } => {
                    g.position_kind.w = light_kind::QUAD;
                    g.axis_u = (x * size.x * 0.5).extend(0.0);
                    g.axis_v = (y * size.y * 0.5).extend(0.0);
                    let area = (x * size.x).cross(y * size.y).length();
                    g.axis_v.w = area;
                    PI * luminance(e) * area
                }
                LightShape::Disk { radius } => {
                    g.position_kind.w = light_kind::DISK;
                    g.axis_u = (x * radius).extend(0.0);
                    g.axis_v = (y * radius).extend(0.0);
                    let area = PI * (x * radius).cross(y * radius).length();
                    g.axis_v.w = area;
                    PI * luminance(e) * area
                }
                LightShape::Sphere { radius } => {
                    g.position_kind.w = light_kind::SPHERE;
                    let r = radius * x.length();
                    g.axis_u.w = r;
                    g.axis_v.w = 4.0 * PI * r * r;
                    PI * luminance(e) * 4.0 * PI * r * r
                }
            };
            lights.push(g);
            powers.push(power);
        }
        let analytic = lights.len();
        let skipped_triangles = push_emissive_triangles(scene, (t, moved), transforms, &mut lights, &mut powers);
        // Selection: proportional to power; lights with no power are never chosen.
        let total: f64 = powers.iter().map(|&p| f64::from(p.max(0.0))).sum();
        let mut running = 0.0f64;
        for (light, power) in lights.iter_mut().zip(&powers) {
            let p = if total > 0.0 { f64::from(power.max(0.0)) / total } else { 0.0 };
            running += p;
            light.cone.w = p as f32;
            light.emission.w = running as f32;
        }
        if let Some(last) = lights.iter_mut().rev().find(|l| l.cone.w > 0.0) {
            // Rounding must not leave a gap at the top of the CDF.
            last.emission.w = 1.0;
        }
        Self { lights, analytic, skipped_triangles, total_power: total as f32 }
    }
}

/// Every emissive triangle of the scene's instances (at `transforms`) as a light after `lights`, with its power for
/// selection in `powers`; plain quads made of two triangles become one parallelogram. Returns how many triangles
/// were left out beyond `MAX_EMISSIVE_TRIANGLES`.
fn push_emissive_triangles(
    scene: &Scene,
    (t, moved): (Option<f32>, &[Mat4]),
    transforms: &[Mat4],
    lights: &mut Vec<GpuLight>,
    powers: &mut Vec<f32>,
) -> usize {
    let analytic = lights.len();
    let mut skipped_triangles = 0;
    let emits = |material: Option<usize>| {
        let material = material.and_then(|m| scene.materials.get(m));
        material.is_some_and(|m| luminance(m.emissive) > 0.0 && !m.unlit)
    };
    'instances: for (index, (instance, world)) in scene.instances.iter().zip(transforms).enumerate() {
        let normal_matrix = Mat3::from_mat4(*world).inverse().transpose();
        let primitives = &scene.meshes[instance.mesh].primitives;
        // A deformed instance's emitters are where its deformation puts them (deformed once, and only if it emits).
        let deformed = match primitives.iter().any(|p| emits(p.material)) {
            true => scene.deform_instance(index, moved, t),
            false => None,
        };
        for (p_index, primitive) in primitives.iter().enumerate() {
            let Some((material_index, material)) = primitive.material.and_then(|m| Some((m, scene.materials.get(m)?)))
            else {
                continue;
            };
            // Chosen by the factor's power over the whole triangle; the shader scales each sample by the
            // emissive texture at the point it landed on, and drops it where alpha-masking cuts the surface
            // out (rays pass there), which keeps the estimate unbiased.
            if !emits(primitive.material) {
                continue;
            }
            let moved_vertices = deformed.as_ref().and_then(|d| d.get(p_index));
            let positions = moved_vertices.map_or(&primitive.positions, |d| &d.positions);
            let normals = moved_vertices.map_or(&primitive.normals, |d| &d.normals);
            let first_of_primitive = lights.len();
            for tri in primitive.indices.chunks_exact(3) {
                if lights.len() - analytic >= MAX_EMISSIVE_TRIANGLES {
                    skipped_triangles += primitive.indices.len() / 3;
                    continue 'instances;
                }
                let Some(p) = tri.iter().map(|&i| positions.get(i as usize)).collect::<Option<Vec<_>>>() else {
                    continue;
                };
                let [p0, p1, p2] = [0, 1, 2].map(|k| world.transform_point3(*p[k]));
                let corners = |uvs: &[Vec2]| [0, 1, 2].map(|k| uvs.get(tri[k] as usize).copied().unwrap_or(Vec2::ZERO));
                let (uv, uv1) = (corners(&primitive.uvs), corners(primitive.uvs1_or_uvs()));
                let alpha = [0, 1, 2].map(|k| primitive.colors.get(tri[k] as usize).map_or(1.0, |c| c.w));
                let (e1, e2) = (p1 - p0, p2 - p0);
                let cross = e1.cross(e2);
                let area = 0.5 * cross.length();
                if area.is_nan() || area <= 0.0 || !area.is_finite() {
                    continue;
                }
                let mut n = cross.normalize();
                // glTF's front face winds counter-clockwise; vertex normals, when present, say which side
                // the surface faces.
                let normal_sum: Vec3 =
                    tri.iter().filter_map(|&i| normals.get(i as usize)).map(|&v| normal_matrix * v).sum();
                if normal_sum.dot(n) < 0.0 {
                    n = -n;
                }
                let two_sided = material.double_sided;
                lights.push(GpuLight {
                    position_kind: p0.extend(light_kind::TRIANGLE),
                    axis_u: e1.extend(0.0),
                    axis_v: e2.extend(area),
                    normal: n.extend(if two_sided { 1.0 } else { 0.0 }),
                    emission: material.emissive.extend(0.0),
                    cone: Vec4::ZERO,
                    uv01: uv[0].extend(uv[1].x).extend(uv[1].y),
                    uv2_material: uv[2].extend(material_index as f32).extend(0.0),
                    corner_alpha: Vec3::from_array(alpha).extend(1.0),
                    uv1_01: uv1[0].extend(uv1[1].x).extend(uv1[1].y),
                    uv1_2: uv1[2].extend(0.0).extend(0.0),
                });
                powers.push(PI * luminance(material.emissive) * area * if two_sided { 2.0 } else { 1.0 });
            }
            // A plain emitter (its factor alone: no texture to read and nothing cut out at the sampled point)
            // needs no barycentrics, so its quads can be sampled whole.
            if material.emissive_texture.is_none() && material.alpha_mode == crate::scene::AlphaMode::Opaque {
                merge_parallelograms(lights, powers, first_of_primitive);
            }
        }
    }
    skipped_triangles
}

/// The corners of a triangle light as `LightSet::at` stores it (p0, p0 + e1, p0 + e2).
fn triangle_corners(l: &GpuLight) -> [Vec3; 3] {
    let p0 = l.position_kind.truncate();
    [p0, p0 + l.axis_u.truncate(), p0 + l.axis_v.truncate()]
}

/// The parallelogram two triangle lights make, if they do: they share an edge (the diagonal), face the same way,
/// and the corners off the diagonal mirror each other through its midpoint. Returns its corner off the diagonal
/// and the two edges from it.
fn parallelogram(a: &GpuLight, b: &GpuLight) -> Option<(Vec3, Vec3, Vec3)> {
    if a.normal != b.normal || a.emission.truncate() != b.emission.truncate() {
        return None;
    }
    let (ca, cb) = (triangle_corners(a), triangle_corners(b));
    let scale = ca.iter().chain(&cb).map(|p| p.abs().max_element()).fold(0.0f32, f32::max).max(1e-6);
    let same = |p: Vec3, q: Vec3| (p - q).abs().max_element() <= 1e-6 * scale;
    // Called per light per sample: the corner off the diagonal is found without allocating.
    let in_b = ca.map(|p| cb.iter().any(|&q| same(p, q)));
    if in_b.iter().filter(|&&shared| shared).count() != 2 {
        return None;
    }
    let off = in_b.iter().position(|&shared| !shared)?;
    // The diagonal's ends in the triangle's own order, which decides which edge the sample's u.x runs along.
    let (first, second) = match off {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let (off_a, d1, d2) = (ca[off], ca[first], ca[second]);
    let off_b = cb.iter().copied().find(|&q| !same(q, d1) && !same(q, d2))?;
    let mirrored = (d1 + d2 - off_a - off_b).abs().max_element() <= 1e-5 * scale;
    mirrored.then_some((off_a, d1 - off_a, d2 - off_a))
}

/// Joins each pair of consecutive triangle lights from `from` on that makes a parallelogram (a quad emitter,
/// as exporters write rectangles) into one light of kind PARALLELOGRAM, sampled uniformly over the whole: a
/// stratified 2D sample then stays stratified over the quad, where split between two triangles it was not
/// (Cornell box direct light, 64 spp: 1.3× the variance of Mitsuba 3's rectangle emitter; docs/performance.md,
/// "Speed at equal error"). Power and area add, so the selection probability per unit area, and with it every
/// MIS weight, is unchanged.
fn merge_parallelograms(lights: &mut Vec<GpuLight>, powers: &mut Vec<f32>, from: usize) {
    let (mut read, mut write) = (from, from);
    while read < lights.len() {
        let pair = (read + 1 < lights.len()).then(|| parallelogram(&lights[read], &lights[read + 1])).flatten();
        let (light, power, taken) = match pair {
            Some((corner, e1, e2)) => {
                let mut quad = lights[read];
                quad.position_kind = corner.extend(light_kind::PARALLELOGRAM);
                quad.axis_u = e1.extend(0.0);
                quad.axis_v = e2.extend(e1.cross(e2).length());
                quad.uv2_material.z = -1.0;
                (quad, powers[read] + powers[read + 1], 2)
            }
            None => (lights[read], powers[read], 1),
        };
        lights[write] = light;
        powers[write] = power;
        write += 1;
        read += taken;
    }
    lights.truncate(write);
    powers.truncate(write);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::library;

    fn lights_at_rest(scene: &Scene) -> LightSet {
        let rest = scene.node_world_transforms(None);
        LightSet::at(scene, (None, &rest), &scene.instance_transforms_from(&rest), &rest, 1.0)
    }

    /// A skinned emitter lights from where its joints put it at the sample's time, not from its bind pose.
    #[test]
    fn a_skinned_emitter_lights_from_where_its_skin_puts_it() {
        let mut tube = crate::scene::fixtures::skinned_tube(2, 4);
        tube.materials.push(crate::scene::Material { emissive: Vec3::ONE, ..Default::default() });
        tube.meshes[0].primitives[0].material = Some(0);
        let rest = tube.node_world_transforms(None);
        let bent = tube.node_world_transforms(Some(1.0));
        let set = LightSet::at(&tube, (Some(1.0), &bent), &tube.instance_transforms_from(&bent), &rest, 1.0);
        let skinned = tube.deform_instance(0, &bent, Some(1.0)).unwrap();
        let on = |p: Vec3, points: &[Vec3]| points.iter().any(|q| (*q - p).length() < 1e-5);
        assert!(!set.lights.is_empty());
        for light in &set.lights {
            let corner = light.position_kind.truncate();
            assert!(on(corner, &skinned[0].positions), "light corner {corner} is not a skinned vertex");
        }
        // The tip ring turned 90°: some corners are nowhere near the tube as built.
        let built = &tube.meshes[0].primitives[0].positions;
        assert!(set.lights.iter().any(|l| !on(l.position_kind.truncate(), built)));
    }

    /// KHR_materials_unlit: an unlit emissive material is no light (its emissive factor means nothing).
    #[test]
    fn an_unlit_material_is_no_light() {
        let mut scene = library::cornell();
        let lamp = scene.materials.iter().position(|m| m.is_emissive()).expect("the Cornell box has a lamp");
        assert!(!lights_at_rest(&scene).lights.is_empty());
        scene.materials[lamp].unlit = true;
        assert!(lights_at_rest(&scene).lights.is_empty(), "an unlit lamp was sampled as a light");
    }

    #[test]
    fn the_cornell_ceiling_light_is_sampled_as_one_parallelogram_facing_down() {
        let scene = library::cornell();
        let set = lights_at_rest(&scene);
        let quads: Vec<&GpuLight> =
            set.lights.iter().filter(|l| l.position_kind.w == light_kind::PARALLELOGRAM).collect();
        assert_eq!(quads.len(), 1, "the two triangles of the ceiling light make one quad: {:?}", set.lights);
        let quad = quads[0];
        assert!(quad.normal.y < -0.99, "the ceiling light must face down, normal {:?}", quad.normal);
        // The lamp is 0.5 m square (library::cornell): the quad covers it, edges and area.
        let (e1, e2) = (quad.axis_u.truncate(), quad.axis_v.truncate());
        assert!((quad.axis_v.w - 0.25).abs() < 1e-5, "area {}", quad.axis_v.w);
        assert!(e1.dot(e2).abs() < 1e-6 && (e1.length() - 0.5).abs() < 1e-5 && (e2.length() - 0.5).abs() < 1e-5);
        assert_eq!(quad.uv2_material.z, -1.0, "a merged quad reads no texture at the sampled point");
        let total: f32 = set.lights.iter().map(|l| l.cone.w).sum();
        assert!((total - 1.0).abs() < 1e-5);
        assert_eq!(set.lights.last().map(|l| l.emission.w), Some(1.0));
    }

    /// What the shader needs to evaluate the emitter's material at a sampled point: the corner UVs as stored
    /// (each texture applies its own KHR_texture_transform there), the material, COLOR_0's alpha at the corners.
    #[test]
    fn emissive_triangles_carry_their_uvs_material_and_vertex_alpha() {
        use glam::Vec4Swizzles as _;
        let mut scene = library::cornell();
        let lamp = scene.materials.iter().position(|m| luminance(m.emissive) > 0.0).expect("cornell has a lamp");
        let (mesh, primitive) = scene
            .meshes
            .iter()
            .enumerate()
            .find_map(|(i, mesh)| Some((i, mesh.primitives.iter().position(|p| p.material == Some(lamp))?)))
            .expect("a primitive wears the lamp's material");
        // A texture at the sampled point needs the triangle's barycentrics: such emitters stay triangles.
        scene.materials[lamp].emissive_texture =
            Some(crate::scene::TextureRef { texture: 0, tex_coord: 0, transform: None });
        let p = &mut scene.meshes[mesh].primitives[primitive];
        p.uvs = (0..p.positions.len()).map(|i| Vec2::new(i as f32, 0.5 * i as f32)).collect();
        p.colors = (0..p.positions.len()).map(|i| Vec4::new(1.0, 1.0, 1.0, 0.1 * i as f32)).collect();
        let p = p.clone();
        scene.lights.push(crate::scene::Light {
            name: "bulb".into(),
            shape: LightShape::Point { radius: 0.0 },
            emission: Vec3::ONE,
            world_from_light: Mat4::IDENTITY,
            node: None,
            range: 0.0,
        });
        let set = lights_at_rest(&scene);
        assert_eq!(set.analytic, 1);
        let triangles: Vec<&GpuLight> =
            set.lights.iter().filter(|l| l.position_kind.w == light_kind::TRIANGLE).collect();
        assert_eq!(triangles.len(), p.indices.len() / 3);
        for (light, tri) in triangles.iter().zip(p.indices.chunks_exact(3)) {
            let corners = [light.uv01.xy(), light.uv01.zw(), light.uv2_material.xy()];
            for (k, &i) in tri.iter().enumerate() {
                assert_eq!(corners[k], p.uvs[i as usize], "corner {k}'s UV");
                assert_eq!(light.corner_alpha[k], p.colors[i as usize].w, "corner {k}'s vertex alpha");
            }
            assert_eq!(light.uv2_material.z, lamp as f32, "the material index");
        }
        let analytic = &set.lights[..set.analytic];
        assert!(analytic.iter().all(|l| l.uv2_material.z == -1.0), "lights that are not geometry have no material");
    }

    #[test]
    fn selection_follows_power() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/soft-shadows.toml");
        let scene = crate::scene::scene_file::load_scene_file(&path, None).expect("the committed scene loads").scene;
        let set = lights_at_rest(&scene);
        assert_eq!(set.analytic, set.lights.len());
        // Three area lights of 60 W each (radiance from power): equal power, equal probability.
        let areas: Vec<f32> = set
            .lights
            .iter()
            .filter(|l| [light_kind::QUAD, light_kind::DISK, light_kind::SPHERE].contains(&l.position_kind.w))
            .map(|l| l.cone.w)
            .collect();
        assert_eq!(areas.len(), 3);
        assert!((areas[0] - areas[1]).abs() < 1e-4 && (areas[1] - areas[2]).abs() < 1e-4, "{areas:?}");
    }
}
