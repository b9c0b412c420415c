#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell: the solver's divergence, and the start of the pressure solve from it, by pc.parity.
//   0 (before projection): writes the divergence as the right-hand side b (rhs, and conjugate gradients'
//     target), zeroes their x, p and r_old, and gathers its maximum and the fluid cells. φ is kept: it
//     still holds the last step's solution, the warm start.
//   1 (after projection): gathers the maximum only, and zeroes φ after a diverged solve (which projected
//     nothing), so that it starts no later solve.
//   2 (warm start): q = Lφ into residual, and the partial sums of b·q and q·q (cg_scalars turns them into
//     the scale s of warm_scale()).
//   3 (start): x0 = s·φ and the first residual r0 = b − s·q (s = 0: from zero, r0 = b), whose maximum is
//     the first convergence check's. With pc.iterations 1 (conjugate gradients) x0 goes to x, r0 to rhs
//     and φ (the preconditioner's output) to 0; otherwise x0 goes to φ and rhs keeps b.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

shared uint group_fluid;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    bool inside = i < n.x * n.y * n.z;
    ivec3 c = inside ? cell_from_index(n, i) : ivec3(0);
    if (pc.parity == 2u) {
        vec2 sums = vec2(0.0);
        if (inside) {
            float q = laplacian_cell(0u, c, kCellPressure);
            store_cell(kCellScratch, i, q);
            sums = q * vec2(load_cell(kCellTarget, i), q);
        }
        group_sum_store(sums);
        return;
    }
    group_max_begin();
    if (gl_LocalInvocationIndex == 0u) group_fluid = 0u;
    barrier();
    if (inside && pc.parity == 3u) {
        float s = state().s.warm_scale;
        float b = load_cell(kCellTarget, i);
        // Written so that s = 0 ignores φ and q entirely (q is not computed on a cold start).
        float x0 = s != 0.0 ? s * load_cell(kCellPressure, i) : 0.0;
        float r0 = s != 0.0 ? b - s * load_cell(kCellScratch, i) : b;
        if (pc.iterations != 0u) {
            store_cell(kCellSolution, i, x0);
            store_cell(kCellRhs, i, r0);
            store_cell(kCellPressure, i, 0.0);
        } else {
            store_cell(kCellPressure, i, x0);
        }
        group_max_add(r0);
    } else if (inside) {
        if (pc.parity == 1u && state().s.diverged != 0u) store_cell(kCellPressure, i, 0.0);
        float diag, off;
        cell_operator(0u, c, kCellPressure, 0.0, diag, off);
        float d = diag > 0.0 ? cell_divergence(c) : 0.0;
        group_max_add(d);
        if (pc.parity == 0u) {
            store_cell(kCellRhs, i, d);
            store_cell(kCellTarget, i, d);
            store_cell(kCellSolution, i, 0.0);
            store_cell(kCellDirection, i, 0.0);
            store_cell(kCellOldResidual, i, 0.0);
            if (diag > 0.0) atomicAdd(group_fluid, 1u);
        }
    }
    // One global atomic per group, and none where an earlier group already left a larger maximum (it
    // only grows, so a stale read costs an atomic, never a lost maximum): tens of thousands of groups on
    // one word were most of this pass on an H100.
    uint bits;
    if (group_max_end(bits)) {
        StateRef st = state();
        if (pc.parity == 0u) {
            if (bits > st.s.divergence_before) atomicMax(st.s.divergence_before, bits);
            if (group_fluid > 0u) atomicAdd(st.s.fluid_cells, group_fluid);
        } else if (pc.parity == 1u) {
            if (bits > st.s.divergence_after) atomicMax(st.s.divergence_after, bits);
        } else if (bits > st.s.residual_scratch) {
            atomicMax(st.s.residual_scratch, bits);
        }
    }
}
