#version 460
#extension GL_GOOGLE_include_directive : require
// One workgroup: pc.iterations red-black Gauss–Seidel sweeps on the coarsest level, at most 4^3 cells
// (build_levels), one thread per cell. Each thread reads its cell's weights and right-hand side once
// and the sweeps run on φ in shared memory, so a sweep waits on no global load: relax_cell with the
// operator gathered up front.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

shared float phi_shared[kSolverGroupSize];

void main() {
    GridLevel level = load_level(pc.level);
    int count = level.dims.x * level.dims.y * level.dims.z;
    int i = int(gl_LocalInvocationIndex);
    bool mine = i < count;
    // cell_operator's faces in its order (face_coupling): the weight, 0 for a closed face, and the
    // neighbour's index, or -1 for an open domain side (its φ is 0).
    float w[6];
    int neighbour[6];
    float diag = 0.0;
    float rhs = 0.0;
    uint colour = 0u;
    if (mine) {
        ivec3 c = cell_from_index(level.dims, i);
        colour = uint(c.x + c.y + c.z) % 2u;
        uint open = grid_open_sides();
        for (uint a = 0u; a < 3u; ++a)
            for (uint s = 0u; s < 2u; ++s) {
                w[2u * a + s] = face_coupling(level, open, c, a, s, neighbour[2u * a + s]);
                diag += w[2u * a + s];
            }
        phi_shared[i] = load_cell(kCellPressure, int(level.cells) + i);
        rhs = load_cell(kCellRhs, int(level.cells) + i);
    }
    barrier();
    for (uint sweep = 0u; sweep < 2u * pc.iterations; ++sweep) {
        if (mine && colour == sweep % 2u) {
            float phi = phi_shared[i];
            float off = 0.0;
            for (uint k = 0u; k < 6u; ++k) {
                if (w[k] == 0.0) continue;
                off += neighbour[k] >= 0 ? w[k] * (phi_shared[neighbour[k]] - phi) : -w[k] * phi;
            }
            phi_shared[i] = diag > 0.0 ? phi + (off - rhs) / diag : 0.0;
        }
        barrier();
    }
    if (mine) store_cell(kCellPressure, int(level.cells) + i, phi_shared[i]);
}
