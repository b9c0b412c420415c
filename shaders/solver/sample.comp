#version 460
#extension GL_GOOGLE_include_directive : require
// Reading the field for engines. pc.mode kSamplePoints: per point, the velocity there: inside a solid (a
// voxel that is not its cell's air, or a cell without air) the solid's own velocity, in the air trilinear on
// the faces (extended into the solid, so no wall's zeros mix in) plus the omni emitters' wind, the ambient
// wind outside the grid. kSampleTexels: per cell, a texel of the wind texture (store_texel; a step's
// finish.comp writes the bound texels, so this serves the first fill and tests). kSampleCells: per cell,
// the velocity at its centre (cell_output) as three floats into `samples`.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

layout(buffer_reference, scalar) readonly buffer PointsRef { vec3 v[]; };
layout(buffer_reference, scalar) writeonly buffer SamplesRef { vec3 v[]; };

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = grid_dims();
    if (pc.mode == kSamplePoints) {
        if (i >= int(sb().b.point_count)) return;
        vec3 p = (PointsRef(sb().b.points).v[i] - grid_origin()) / grid_h();
        vec3 u;
        if (!inside_grid(p)) {
            u = grid_ambient();
        } else {
            int cell = cell_index(n, clamp(ivec3(floor(p)), ivec3(0), n - 1));
            uint flags = flags_at(cell);
            u = in_solid(p, cell, flags) ? solid_velocity_at(p, cell, flags)
                                         : sample_velocity(kFieldVelocity, p) + omni_velocity(p);
        }
        SamplesRef(sb().b.samples).v[i] = u;
    } else {
        if (i >= n.x * n.y * n.z) return;
        if (pc.mode == kSampleCells)
            SamplesRef(sb().b.samples).v[i] = cell_output(i);
        else
            store_texel(i);
    }
}
