#version 460
// Skins one primitive's vertices for one sample (glTF 2.0 §3.7.3; docs/architecture.md, "Deformed meshes"): each
// vertex's blended matrix S = Σ wᵢ·Jᵢ over every JOINTS_n/WEIGHTS_n set, positions through S, surface derivatives
// through its linear part, normals through that part's cofactor matrix. The GPU twin of scene::skin::skin_vertices,
// which tests/animation.rs holds it to. Everything is reached by device address: the source streams (the mesh's
// own, or the sample's morphed copy), the influences, the sample's joint matrices and the sample's output streams.
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "shared_constants.glsl"

layout(local_size_x = SKIN_WORKGROUP_SIZE) in;

layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer SourceStream { vec3 v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) writeonly buffer OutputStream { vec3 v[]; };
// One vertex's four joints from one JOINTS_n/WEIGHTS_n pair (indices into the skin's joints, 16 bits each, two per
// word) and their weights.
struct GpuInfluence {
    uint joints01;
    uint joints23;
    vec4 weights;
};
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer Influences { GpuInfluence v[]; };
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer JointMatrices { mat4 m[]; };

layout(push_constant, scalar) uniform SkinPush {
    uint64_t positions;
    uint64_t normals;
    uint64_t dpdu;
    uint64_t dpdv;
    uint64_t out_positions;
    uint64_t out_normals;
    uint64_t out_dpdu;
    uint64_t out_dpdv;
    // vertex_count × set_count influences, vertex by vertex.
    uint64_t influences;
    // joint_count matrices: this sample's Jᵢ = world(jointᵢ) · inverse_bindᵢ.
    uint64_t joint_matrices;
    uint vertex_count;
    uint set_count;
    uint joint_count;
    uint pad;
} pc;

// det(m)·m⁻ᵀ, finite where m is singular: normals keep their direction under any blend (the shaders normalize).
mat3 cofactor(mat3 m) {
    return mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
}

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= pc.vertex_count) return;
    JointMatrices joints = JointMatrices(pc.joint_matrices);
    Influences influences = Influences(pc.influences);
    mat4 blended = mat4(0.0);
    for (uint s = 0u; s < pc.set_count; s++) {
        GpuInfluence influence = influences.v[v * pc.set_count + s];
        uint ids[4] = uint[4](influence.joints01 & 0xffffu, influence.joints01 >> 16u, influence.joints23 & 0xffffu,
                              influence.joints23 >> 16u);
        for (uint k = 0u; k < 4u; k++) {
            float w = influence.weights[k];
            // A joint beyond the skin reads a zero matrix, as on the host (the loader rejects such files).
            if (w != 0.0 && ids[k] < pc.joint_count) blended += joints.m[ids[k]] * w;
        }
    }
    mat3 linear = mat3(blended);
    OutputStream(pc.out_positions).v[v] = (blended * vec4(SourceStream(pc.positions).v[v], 1.0)).xyz;
    OutputStream(pc.out_normals).v[v] = cofactor(linear) * SourceStream(pc.normals).v[v];
    OutputStream(pc.out_dpdu).v[v] = linear * SourceStream(pc.dpdu).v[v];
    OutputStream(pc.out_dpdv).v[v] = linear * SourceStream(pc.dpdv).v[v];
}
