#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell of level pc.level. pc.parity 0/1: red-black Gauss–Seidel sweep of that colour, in place.
// 2: damped Jacobi from φ into pressure_tmp; 3: Jacobi from pressure_tmp into φ (level 0 only).
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    GridLevel level = load_level(pc.level);
    if (i >= level.dims.x * level.dims.y * level.dims.z) return;
    ivec3 c = cell_from_index(level.dims, i);
    if (pc.parity < 2u) {
        if (uint(c.x + c.y + c.z) % 2u != pc.parity) return;
        store_cell(kCellPressure, int(level.cells) + i, relax_cell(pc.level, c, kCellPressure));
    } else if (pc.parity == 2u) {
        store_cell(kCellPressureTmp, i, jacobi_cell(c, kCellPressure));
    } else {
        store_cell(kCellPressure, i, jacobi_cell(c, kCellPressureTmp));
    }
}
