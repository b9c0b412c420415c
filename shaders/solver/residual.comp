#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell of level pc.level: residual b − Lφ; with pc.parity 1 its maximum joins the convergence check.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    group_max_begin();
    int i = thread_index();
    GridLevel level = load_level(pc.level);
    if (i < level.dims.x * level.dims.y * level.dims.z) {
        float r = residual_cell(pc.level, cell_from_index(level.dims, i));
        store_cell(kCellResidual, int(level.cells) + i, r);
        group_max_add(r);
    }
    uint bits;
    if (group_max_end(bits) && pc.parity == 1u && bits > state().s.residual_scratch)
        atomicMax(state().s.residual_scratch, bits);
}
