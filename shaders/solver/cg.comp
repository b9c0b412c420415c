#version 460
#extension GL_GOOGLE_include_directive : require
// Per level-0 cell, one step of multigrid-preconditioned conjugate gradients (McAdams et al. 2010) by
// pc.parity. The residual r lives in rhs (the V-cycle's right-hand side) and the preconditioned z in φ
// (its result):
//   0: partial sums of r·z and r_old·z        1: p = z + β·p
//   2: partial sums of p·Lp                   3: x += α·p, r_old = r, z = 0 (the next V-cycle's start)
//   4: r = b − Lx, its maximum to the convergence check. Recomputed rather than updated (r −= α·Lp):
//      the update drifts from b − Lx in float by more than the tolerance.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    bool inside = i < n.x * n.y * n.z;
    ivec3 c = inside ? cell_from_index(n, i) : ivec3(0);
    StateRef st = state();
    if (pc.parity == 0u) {
        vec2 sums = vec2(0.0);
        if (inside) {
            float z = load_cell(kCellPressure, i);
            sums = z * vec2(load_cell(kCellRhs, i), load_cell(kCellOldResidual, i));
        }
        group_sum_store(sums);
    } else if (pc.parity == 1u) {
        if (inside)
            store_cell(kCellDirection, i, load_cell(kCellPressure, i) + st.s.cg_beta * load_cell(kCellDirection, i));
    } else if (pc.parity == 2u) {
        float sum = inside ? load_cell(kCellDirection, i) * laplacian_cell(0u, c, kCellDirection) : 0.0;
        group_sum_store(vec2(sum, 0.0));
    } else if (pc.parity == 3u) {
        if (inside) {
            store_cell(kCellSolution, i, load_cell(kCellSolution, i) + st.s.cg_alpha * load_cell(kCellDirection, i));
            store_cell(kCellOldResidual, i, load_cell(kCellRhs, i));
            store_cell(kCellPressure, i, 0.0);
        }
    } else {
        group_max_begin();
        if (inside) {
            float r = load_cell(kCellTarget, i) - laplacian_cell(0u, c, kCellSolution);
            store_cell(kCellRhs, i, r);
            group_max_add(r);
        }
        uint bits;
        if (group_max_end(bits) && bits > st.s.residual_scratch) atomicMax(st.s.residual_scratch, bits);
    }
}
