#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell: the solver's divergence. pc.parity 0 (before projection): writes it as the right-hand side
// (and as conjugate gradients' b), zeroes φ and their x, p and r_old, and gathers its maximum and the
// fluid cells. 1 (after): gathers the maximum only.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    group_max_begin();
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i < n.x * n.y * n.z) {
        ivec3 c = cell_from_index(n, i);
        float diag, off;
        cell_operator(0u, c, kCellPressure, 0.0, diag, off);
        float d = diag > 0.0 ? cell_divergence(c) : 0.0;
        group_max_add(d);
        if (pc.parity == 0u) {
            store_cell(kCellRhs, i, d);
            store_cell(kCellPressure, i, 0.0);
            store_cell(kCellTarget, i, d);
            store_cell(kCellSolution, i, 0.0);
            store_cell(kCellDirection, i, 0.0);
            store_cell(kCellOldResidual, i, 0.0);
            if (diag > 0.0) atomicAdd(state().s.fluid_cells, 1u);
        }
    }
    uint bits;
    if (group_max_end(bits)) {
        if (pc.parity == 0u) {
            atomicMax(state().s.divergence_before, bits);
            atomicMax(state().s.residual_scratch, bits);
        } else {
            atomicMax(state().s.divergence_after, bits);
        }
    }
}
