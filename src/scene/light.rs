//! Lights: glTF `KHR_lights_punctual` (point, spot, directional) and the scene file's area lights (quad, disk,
//! sphere). Emission is linear RGB: radiance (W·sr⁻¹·m⁻²) for area lights, intensity (candela, W·sr⁻¹ in
//! strata's radiometric reading) for point and spot lights, irradiance (lux → W·m⁻²) for directional lights.
use glam::{Mat4, Vec2, Vec3};

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightShape {
    /// A point light; `radius > 0` makes it a sphere light that casts soft shadows.
    Point { radius: f32 },
    /// A spot light along the light's −Z (KHR_lights_punctual), cone angles in radians.
    Spot { inner_cone: f32, outer_cone: f32, radius: f32 },
    /// Parallel light along the light's −Z.
    Directional,
    /// A rectangle in the light's XY plane, emitting along −Z, `size` metres on a side.
    Quad { size: Vec2 },
    /// A disk in the light's XY plane, emitting along −Z.
    Disk { radius: f32 },
    /// A sphere emitting outwards.
    Sphere { radius: f32 },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    pub name: String,
    pub shape: LightShape,
    /// Linear RGB colour × intensity: radiance for area shapes, intensity for point/spot, irradiance for
    /// directional.
    pub emission: Vec3,
    /// The light's frame: position in column 3, emitting along its −Z.
    pub world_from_light: Mat4,
    /// The node that carries it (KHR lights), for animation.
    pub node: Option<usize>,
    /// `KHR_lights_punctual` range (0 = infinite).
    pub range: f32,
}

impl Light {
    /// Emitting surface area in m² of an area light (uniform scale of the frame applied); `None` for points.
    pub fn area(&self) -> Option<f32> {
        let scale = self.world_from_light.to_scale_rotation_translation().0;
        match self.shape {
            LightShape::Quad { size } => Some(size.x * size.y * scale.x * scale.y),
            LightShape::Disk { radius } => Some(std::f32::consts::PI * radius * radius * scale.x * scale.y),
            LightShape::Sphere { radius } => Some(4.0 * std::f32::consts::PI * radius * radius * scale.x * scale.x),
            _ => None,
        }
    }

    /// Radiance of a Lambertian area emitter of total power `watts` (per channel): Φ = π · L · A for a
    /// one-sided emitter, so L = Φ / (π A).
    pub fn radiance_from_power(power: Vec3, area: f32) -> Vec3 {
        power / (std::f32::consts::PI * area.max(f32::MIN_POSITIVE))
    }
}
