//! The G-buffer's encoding on the host: the twin of `shaders/include/gbuffer_encoding.glsl`, which says what
//! each attachment holds. Read-backs (AOVs, tests) decode through it into the channels of
//! `gbuffer_layout::{POSITION, SHADING_NORMAL, ...}`.
use super::gbuffer_layout::{self as layout, attachment};
use glam::{Vec2, Vec3};

/// A unit vector onto the octahedron |x| + |y| + |z| = 1,, lower half folded over the upper, as two snorm16s (`encode_unit_vector`; Cigolle et al. 2014). GLSL's `packSnorm2x16`: round(clamp(v, −1, 1) · 32767).
pub fn encode_unit_vector(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    // Also a NaN's: nothing better exists for a vector without a direction.
    if l1.is_nan() || l1 <= 0.0 {
        return 0;
    }
    let o = n / l1;
    let folded =
        if o.z >= 0.0 { Vec2::new(o.x, o.y) } else { (Vec2::ONE - Vec2::new(o.y, o.x).abs()) * sign_not_zero(o) };
    let snorm = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    snorm(folded.x) | (snorm(folded.y) << 16)
}

/// The inverse of [`encode_unit_vector`] (`decode_unit_vector`): GLSL's `unpackSnorm2x16` is
/// max(v / 32767, −1).
pub fn decode_unit_vector(packed: u32) -> Vec3 {
    let unsnorm = |bits: u32| (f32::from(bits as u16 as i16) / 32767.0).max(-1.0);
    let f = Vec2::new(unsnorm(packed & 0xffff), unsnorm(packed >> 16));
    let mut n = Vec3::new(f.x, f.y, 1.0 - f.x.abs() - f.y.abs());
    if n.z < 0.0 {
        let xy = (Vec2::ONE - Vec2::new(n.y, n.x).abs()) * sign_not_zero(n);
        (n.x, n.y) = (xy.x, xy.y);
    }
    n.normalize()
}

fn sign_not_zero(v: Vec3) -> Vec2 {
    Vec2::new(if v.x >= 0.0 { 1.0 } else { -1.0 }, if v.y >= 0.0 { 1.0 } else { -1.0 })
}

/// One pixel's channels from its attachments: `floats` the float attachments as read back (sRGB decoded), at
/// their locations; `ids` the surface ids. Returns the channels at `layout::{POSITION, ...}` and
/// (instance + 1, material).
pub fn decode_texel(floats: &[[f32; 4]], ids: [u32; 4]) -> ([[f32; 4]; layout::CHANNELS], [u32; 2]) {
    let emission = floats[attachment::EMISSION];
    let specular = floats[attachment::SPECULAR];
    let shading = decode_unit_vector(ids[2]);
    let geometric = decode_unit_vector(ids[3]);
    let mut channels = [[0.0; 4]; layout::CHANNELS];
    channels[layout::POSITION] = floats[attachment::POSITION];
    channels[layout::SHADING_NORMAL] = shading.extend(emission[3]).to_array();
    channels[layout::GEOMETRIC_NORMAL] = geometric.extend(specular[3]).to_array();
    channels[layout::ALBEDO] = floats[attachment::ALBEDO];
    channels[layout::MATERIAL] = floats[attachment::MATERIAL];
    channels[layout::EMISSION] = [emission[0], emission[1], emission[2], 0.0];
    channels[layout::SPECULAR_COLOR] = [specular[0], specular[1], specular[2], 1.0];
    (channels, [ids[0], ids[1]])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over 40,000 directions spread over the sphere (and the axes, where the fold's edges are), a round trip
    /// stays within the 16-bit grid's reach: half a step is 0.5/32767 per coordinate on the octahedron, which the
    /// map onto the sphere stretches by a few times near the fold (measured worst 6.0e-5 rad; bound 9.2e-5).
    #[test]
    fn unit_vectors_survive_the_round_trip_within_the_grid() {
        let mut worst = 0.0f32;
        let mut directions: Vec<Vec3> = vec![Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        let n = 200;
        for i in 0..n {
            for j in 0..n {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let phi = std::f32::consts::TAU * j as f32 / n as f32;
                let r = (1.0 - z * z).sqrt();
                directions.push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
            }
        }
        for d in directions {
            let back = decode_unit_vector(encode_unit_vector(d));
            // The chord, not angle_between: acos near 1 in f32 cannot see angles this small.
            worst = worst.max((back - d).length());
        }
        assert!(worst < 1.5 * 2.0 / 32767.0, "worst error {worst} rad");
        // The axes come back exactly: the G-buffer test of a flat floor asks for +y to 1e-5.
        for axis in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z] {
            assert_eq!(decode_unit_vector(encode_unit_vector(axis)), axis);
        }
        assert_eq!(decode_unit_vector(encode_unit_vector(Vec3::ZERO)), Vec3::Z);
    }
}
