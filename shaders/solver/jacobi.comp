#version 460
#extension GL_GOOGLE_include_directive : require
// The Jacobi baseline on the level-0 iterate, from zero. pc.mode kJacobiSweep: one damped sweep from
// kCellSolution into kCellSolutionB (SolverPush::swap's bit 1 alternates them), against b in kCellRhs.
// kJacobiCheck: the residual's maximum and, in the workgroup that finishes last, the convergence check (the
// iterate in buffer A).
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = grid_dims();
    bool inside = i < n.x * n.y * n.z;
    GridLevel level0 = load_level(0u);
    if (pc.mode == kJacobiSweep) {
        if (inside) store_cell(kCellSolutionB, i, jacobi_cell(level0, cell_from_index(n, i), kCellSolution));
        return;
    }
    group_max_begin();
    if (inside) {
        ivec3 c = cell_from_index(n, i);
        float diag, lap;
        cell_operator(level0, c, kCellSolution, load_cell(kCellSolution, i), diag, lap);
        if (diag > 0.0) group_max_add(load_cell(kCellRhs, i) - lap);
    }
    uint bits;
    if (group_max_end(bits) && bits > state().s.residual_scratch) atomicMax(state().s.residual_scratch, bits);
    if (last_group() && gl_LocalInvocationIndex == 0u) convergence_check(0u);
}
