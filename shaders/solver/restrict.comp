#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell of level pc.level (> 0): its right-hand side, the mean residual of its children at the finer
// level after their smoothing (restrict_cell, which computes those residuals).
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    GridLevel level = load_level(pc.level), fine = load_level(pc.level - 1u);
    if (i >= level.dims.x * level.dims.y * level.dims.z) return;
    store_cell(kCellRhs, int(level.cells) + i, restrict_cell(fine, cell_from_index(level.dims, i)));
}
