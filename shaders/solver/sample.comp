#version 460
#extension GL_GOOGLE_include_directive : require
// Reading the field for engines. pc.parity 0: per point, the velocity there: inside a solid (a voxel that
// is not its cell's air, or a cell without air) the solid's own velocity, in the air trilinear on the faces
// (extended into the solid, so no wall's zeros mix in), the ambient wind outside the grid. 1: per cell, a
// texel of the wind texture: velocity at the centre (the solid's in a cell without air) and 1 − solid
// fraction, as four half floats. 2: per cell, the same velocity as three floats into `samples`.
#include "solver_common.glsl"

layout(buffer_reference, scalar) readonly buffer PointsRef { vec3 v[]; };
layout(buffer_reference, scalar) writeonly buffer SamplesRef { vec3 v[]; };
layout(buffer_reference, scalar) writeonly buffer TexelsRef { uvec2 v[]; };

layout(local_size_x = kSolverGroupSize) in;

/// Whether point p (cell units, inside the grid) lies in a solid: in a cell without air, or in a voxel of a
/// cut cell that is not the cell's air.
bool in_solid(vec3 p, int cell, uint flags) {
    if ((flags & kCellNoAir) != 0u) return true;
    if ((flags & kCellCut) == 0u) return false;
    ivec3 c = cell_from_index(grid_dims(), cell);
    int v = int(sb().b.voxels_per_cell);
    ivec3 voxel = clamp(ivec3(floor((p - vec3(c)) * float(v))), ivec3(0), ivec3(v - 1));
    return !bits_get(air_of(cell, flags), uint(voxel.x + v * (voxel.y + v * voxel.z)));
}

vec3 cell_output(int i) {
    uint flags = flags_at(i);
    if ((flags & kCellNoAir) != 0u) return motion_velocity(solid_motion_of(i, flags));
    return cell_velocity(kFieldVelocity, cell_from_index(grid_dims(), i));
}

void main() {
    int i = thread_index();
    ivec3 n = grid_dims();
    if (pc.parity == 0u) {
        if (i >= int(sb().b.point_count)) return;
        vec3 p = (PointsRef(sb().b.points).v[i] - grid_origin()) / grid_h();
        vec3 u;
        if (!inside_grid(p)) {
            u = grid_ambient();
        } else {
            int cell = cell_index(n, clamp(ivec3(floor(p)), ivec3(0), n - 1));
            uint flags = flags_at(cell);
            u = in_solid(p, cell, flags) ? motion_velocity(solid_motion_of(cell, flags))
                                         : sample_velocity(kFieldVelocity, p);
        }
        SamplesRef(sb().b.samples).v[i] = u;
    } else {
        if (i >= n.x * n.y * n.z) return;
        vec3 u = cell_output(i);
        if (pc.parity == 2u) {
            SamplesRef(sb().b.samples).v[i] = u;
        } else {
            float open = 1.0 - FloatsRef(sb().b.cell_solid).v[i];
            TexelsRef(sb().b.texels).v[i] = uvec2(packHalf2x16(u.xy), packHalf2x16(vec2(u.z, open)));
        }
    }
}
