#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell of level pc.level (> 0): right-hand side from the finer level's residual (restrict_cell
// computes it); φ starts at 0.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    GridLevel level = load_level(pc.level);
    if (i >= level.dims.x * level.dims.y * level.dims.z) return;
    store_cell(kCellRhs, int(level.cells) + i, restrict_cell(pc.level, cell_from_index(level.dims, i)));
    store_cell(kCellPressure, int(level.cells) + i, 0.0);
}
