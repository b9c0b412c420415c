#version 460
#extension GL_GOOGLE_include_directive : require
// One workgroup: pc.iterations red-black Gauss–Seidel sweeps on the coarsest level (a few dozen cells).
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    GridLevel level = load_level(pc.level);
    int count = level.dims.x * level.dims.y * level.dims.z;
    for (uint sweep = 0u; sweep < 2u * pc.iterations; ++sweep) {
        for (int i = int(gl_LocalInvocationIndex); i < count; i += int(kSolverGroupSize)) {
            ivec3 c = cell_from_index(level.dims, i);
            if (uint(c.x + c.y + c.z) % 2u == sweep % 2u)
                store_cell(kCellPressure, int(level.cells) + i, relax_cell(pc.level, c, kCellPressure));
        }
        memoryBarrierBuffer();
        barrier();
    }
}
