#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell of level pc.level: adds the interpolated correction from the next coarser level.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    GridLevel level = load_level(pc.level);
    if (i >= level.dims.x * level.dims.y * level.dims.z) return;
    int j = int(level.cells) + i;
    store_cell(kCellPressure, j, load_cell(kCellPressure, j) + prolong_cell(pc.level, cell_from_index(level.dims, i)));
}
