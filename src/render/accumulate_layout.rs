//! The accumulation and resolve passes' data, defined once for Rust; mirrored by
//! `shaders/include/accumulate_layout.glsl` (sizes and offsets pinned by the tests below).
use glam::Vec4;

/// Light kinds as the shader reads them (`GpuLight::position_kind.w`), from shared_constants.glsl.
pub mod light_kind {
    use crate::shaders::constants as c;
    pub const POINT: f32 = c::LIGHT_POINT;
    pub const SPOT: f32 = c::LIGHT_SPOT;
    pub const DIRECTIONAL: f32 = c::LIGHT_DIRECTIONAL;
    pub const QUAD: f32 = c::LIGHT_QUAD;
    pub const DISK: f32 = c::LIGHT_DISK;
    pub const SPHERE: f32 = c::LIGHT_SPHERE;
    pub const TRIANGLE: f32 = c::LIGHT_TRIANGLE;
    /// The environment: the first of a sample's lights when the scene has one.
    pub const ENVIRONMENT: f32 = c::LIGHT_ENVIRONMENT;
    /// Two emissive triangles that make a parallelogram with a plain emissive factor (lights::merge_parallelograms),
    /// sampled as one: corner + s·axis_u + t·axis_v for s, t in [0, 1].
    pub const PARALLELOGRAM: f32 = c::LIGHT_PARALLELOGRAM;
}

/// One light at one sample time, in world space. Area lights carry radiance, point and spot lights intensity,
/// directional lights irradiance (see `scene::light`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuLight {
    /// xyz: centre (quad, disk, sphere, point, spot) or first vertex (triangle); w: kind.
    pub position_kind: Vec4,
    /// xyz: quad half-extent along u, disk radius × u axis, triangle edge p1 − p0; w: radius (point, spot,
    /// sphere).
    pub axis_u: Vec4,
    /// xyz: quad half-extent along v, disk radius × v axis, triangle edge p2 − p0; w: emitting area in m².
    pub axis_v: Vec4,
    /// xyz: unit direction the light travels (area lights emit along it; spot and directional lights shine
    /// along it); w: 1 when both sides emit.
    pub normal: Vec4,
    /// rgb: radiance, intensity or irradiance; w: the selection CDF up to and including this light.
    pub emission: Vec4,
    /// x: cos(outer cone), y: cos(inner cone) for spots; z: range of points and spots (0: infinite); w: the
    /// probability of selecting it.
    pub cone: Vec4,
    /// Emissive triangles: the UVs (TEXCOORD_0 as stored; each texture's transform is applied in the shader)
    /// of p0 (xy) and p1 (zw).
    pub uv01: Vec4,
    /// Emissive triangles: the UV of p2 (xy); z: the material's index, -1 for lights that are not geometry (the
    /// shader reads the emissive texture and the alpha coverage at the sampled point from it); w: unused.
    pub uv2_material: Vec4,
    /// Emissive triangles: COLOR_0's alpha at p0, p1 and p2 (xyz; 1 without vertex colours), which alpha-masked
    /// materials multiply in; w: unused.
    pub corner_alpha: Vec4,
    /// Emissive triangles: TEXCOORD_1 (TEXCOORD_0 without it) of p0 (xy) and p1 (zw), for textures that read it.
    pub uv1_01: Vec4,
    /// Emissive triangles: TEXCOORD_1 of p2 (xy); zw: unused.
    pub uv1_2: Vec4,
}

/// What the shader needs to shade a ray's hit on a primitive: its vertex streams by device address
/// (`GL_EXT_buffer_reference`) and its material. Indexed by the TLAS instance's custom index (its mesh's first
/// record) plus the BLAS geometry index (the primitive within the mesh).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuPrimitiveRecord {
    pub positions: u64,
    pub normals: u64,
    pub uvs: u64,
    pub indices: u64,
    /// Linear RGBA vertex colours (white without COLOR_0).
    pub colors: u64,
    /// Surface derivatives Q_u and Q_v (bump mapping's tangent frame, as the G-buffer pass reads them).
    pub dpdu: u64,
    pub dpdv: u64,
    pub material: u32,
    pub pad: u32,
    /// TEXCOORD_1 (TEXCOORD_0's values without it), for textures that read the second set.
    pub uvs1: u64,
}

/// One sample's camera for primary rays traced per pixel (`Primary::Rays`): the thin lens of docs/architecture.md in the
/// camera's own frame, which the shader maps to world space with `world_from_camera`'s columns.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuCamera {
    /// The columns of world_from_camera (x right, y up, z back, w the lens centre).
    pub world_from_camera: [Vec4; 4],
    /// x, y: half the image's width and height on the plane at distance 1 (perspective) or in metres
    /// (orthographic); z: aperture radius; w: focus distance.
    pub lens: Vec4,
    /// x: near, y: far clip distance (along the view axis); z: 1 for orthographic; w unused.
    pub range: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AccumulatePush {
    /// xyz: this sample's eye (the lens point); w: 1 for an orthographic camera.
    pub eye: Vec4,
    /// xyz: the camera's viewing direction (for orthographic view vectors).
    pub forward: Vec4,
    /// rgb: radiance where rays escape.
    pub background: Vec4,
    pub width: u32,
    pub height: u32,
    pub sample_index: u32,
    pub sample_count: u32,
    pub sampler_kind: u32,
    pub seed: u32,
    /// This sample's lights start at `light_offset` in the light buffer.
    pub light_offset: u32,
    pub light_count: u32,
    /// Lights `0..analytic_light_count` of the sample are not geometry (quads, disks, spheres, points): specular
    /// rays intersect them analytically.
    pub analytic_light_count: u32,
    /// The slot of the ray counters this sample adds to.
    pub counter_slot: u32,
    /// Path vertices along the specular chain (1: no gloss or translucency rays).
    pub max_depth: u32,
    /// The sum of the lights' selection powers (for the selection probability of an emissive triangle a
    /// gloss ray hits).
    pub total_light_power: f32,
    /// The device address of a `RayLog` (render::ray_log) to record every ray cast into, or 0.
    pub ray_log: u64,
    /// 1: paths also go on by the diffuse lobe (diffuse interreflection), 0: Cook's effects alone.
    pub indirect: u32,
    /// How direct light is estimated: one of the `DIRECT_*` constants (accumulate_layout.glsl).
    pub direct_light: u32,
    /// 1: the accumulation's alpha sums each sample's squared luminance instead of its coverage.
    pub alpha_moment: u32,
    /// `SABOTAGE_*` bits (shared_constants.glsl): the deliberately broken renders of `strata check`'s canaries.
    pub sabotage: u32,
    /// Paths traced from each camera sample's visible surface (`RenderSettings::shading_samples`, at least 1):
    /// the sums take their mean as the camera sample's value.
    pub shading_samples: u32,
    pub pad: u32,
}

/// `pc.direct_light`'s values (shared_constants.glsl): multiple importance sampling of lights and BSDF, or
/// either alone.
pub use crate::shaders::constants::{DIRECT_BSDF_SAMPLING, DIRECT_LIGHT_SAMPLING, DIRECT_MIS};

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ResolvePush {
    pub width: u32,
    pub height: u32,
    /// N, the samples the sums hold.
    pub samples: u32,
    /// 2^exposure.
    pub exposure_scale: f32,
    /// 0: clamp, 1: filmic.
    pub tone_map: u32,
    /// 1: a transparent background: the display image keeps coverage in alpha, its colour unpremultiplied
    /// (straight alpha, as PNG stores it); 0: opaque.
    pub transparent: u32,
    pub pad: [u32; 2],
}

/// Counters per sample slot: shadow rays, secondary rays, and the next run of pixels a subgroup takes (the
/// accumulation pass's queue; zeroed with the rest before each batch). Defined in shared_constants.glsl.
pub const COUNTERS_PER_SLOT: usize = crate::shaders::constants::COUNTERS_PER_SLOT as usize;
pub const COUNTER_SHADOW_RAYS: usize = crate::shaders::constants::COUNTER_SHADOW_RAYS as usize;
pub const COUNTER_SECONDARY_RAYS: usize = crate::shaders::constants::COUNTER_SECONDARY_RAYS as usize;

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    #[test]
    fn layouts_match_the_glsl_structs() {
        assert_eq!(size_of::<GpuLight>(), 176);
        assert_eq!(offset_of!(GpuLight, uv1_2), 160);
        assert_eq!(offset_of!(GpuLight, uv2_material), 112);
        assert_eq!(offset_of!(GpuLight, corner_alpha), 128);
        assert_eq!(offset_of!(GpuLight, emission), 64);
        assert_eq!(size_of::<GpuPrimitiveRecord>(), 72);
        assert_eq!(offset_of!(GpuPrimitiveRecord, uvs1), 64);
        assert_eq!(offset_of!(GpuPrimitiveRecord, dpdv), 48);
        assert_eq!(offset_of!(GpuPrimitiveRecord, material), 56);
        assert_eq!(size_of::<GpuCamera>(), 96);
        assert_eq!(offset_of!(GpuCamera, range), 80);
        assert_eq!(size_of::<AccumulatePush>(), 128);
        assert_eq!(offset_of!(AccumulatePush, ray_log), 96);
        assert_eq!(offset_of!(AccumulatePush, width), 48);
        assert_eq!(offset_of!(AccumulatePush, max_depth), 88);
        assert_eq!(offset_of!(AccumulatePush, indirect), 104);
        assert_eq!(offset_of!(AccumulatePush, direct_light), 108);
        assert_eq!(offset_of!(AccumulatePush, alpha_moment), 112);
        assert_eq!(offset_of!(AccumulatePush, shading_samples), 120);
        assert_eq!(size_of::<ResolvePush>(), 32);
    }
}
