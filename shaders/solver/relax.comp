#version 460
#extension GL_GOOGLE_include_directive : require
// pc.parity 0/1: red-black Gauss–Seidel sweep of that colour on level pc.level, in place, one thread
// per cell of the colour (colour_cell). 2: damped Jacobi from φ into pressure_tmp; 3: Jacobi from
// pressure_tmp into φ (level 0 only, one thread per cell).
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    GridLevel level = load_level(pc.level);
    if (pc.parity < 2u) {
        if (i >= colour_threads(level.dims)) return;
        ivec3 c = colour_cell(level.dims, pc.parity, i);
        if (c.x >= level.dims.x) return;
        store_cell(kCellPressure, int(level.cells) + cell_index(level.dims, c), relax_cell(pc.level, c, kCellPressure));
        return;
    }
    if (i >= level.dims.x * level.dims.y * level.dims.z) return;
    ivec3 c = cell_from_index(level.dims, i);
    if (pc.parity == 2u)
        store_cell(kCellPressureTmp, i, jacobi_cell(c, kCellPressure));
    else
        store_cell(kCellPressure, i, jacobi_cell(c, kCellPressureTmp));
}
