#version 460
#extension GL_GOOGLE_include_directive : require
// Reading the field for engines. pc.parity 0: per point, the velocity there (trilinear on the faces; the
// ambient wind outside the grid). 1: per cell, a texel of the wind texture: velocity at the centre and
// 1 − solid fraction, as four half floats.
#include "solver_common.glsl"

layout(buffer_reference, scalar) readonly buffer PointsRef { vec3 v[]; };
layout(buffer_reference, scalar) writeonly buffer SamplesRef { vec3 v[]; };
layout(buffer_reference, scalar) writeonly buffer TexelsRef { uvec2 v[]; };

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    if (pc.parity == 0u) {
        if (i >= int(sb().b.point_count)) return;
        vec3 p = (PointsRef(sb().b.points).v[i] - grid_origin()) / grid_h();
        SamplesRef(sb().b.samples).v[i] = sample_velocity(kFieldVelocity, p);
    } else {
        ivec3 n = grid_dims();
        if (i >= n.x * n.y * n.z) return;
        vec3 u = cell_velocity(kFieldVelocity, cell_from_index(n, i));
        float open = 1.0 - FloatsRef(sb().b.cell_solid).v[i];
        TexelsRef(sb().b.texels).v[i] = uvec2(packHalf2x16(u.xy), packHalf2x16(vec2(u.z, open)));
    }
}
