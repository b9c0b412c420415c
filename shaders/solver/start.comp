#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell, what the pressure solve needs before its first pass (docs/solver.md, "The solve's start").
// pc.mode:
//   kStartRhs (the Jacobi baseline): the solver's divergence as the right-hand side b (kCellTarget, and the
//     level-0 residual kCellRhs, which the baseline relaxes against), its maximum and the fluid cells.
//   kStartScale (the warm start, in a stage of its own): q = Lφ of the last step's φ (kCellScratch) and the
//     sums b·q and q·q, which the workgroup that finishes last turns into the scale s of x0 = s·φ
//     (warm_scale). The solve's first pass (smooth.comp, kSmoothStart) makes b itself.
//   kStartQ (the warm start beside the advection's first pass): q and q·q only (SolverState::warm_qq); the
//     advection's last pass sums b·q over the faces it writes and makes the scale (warm_face_product).
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

shared uint group_fluid;

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    bool inside = i < n.x * n.y * n.z;
    ivec3 c = inside ? cell_from_index(n, i) : ivec3(0);
    GridLevel level0 = load_level(0u);
    if (pc.mode != kStartRhs) {
        vec2 sums = vec2(0.0);
        if (inside) {
            float q = laplacian_cell(level0, c, kCellPhi);
            store_cell(kCellScratch, i, q);
            float b = pc.mode == kStartScale && q != 0.0 ? cell_divergence(c) : 0.0;
            sums = q * vec2(b, q);
        }
        vec2 total;
        if (sum_dispatch(sums, total) && gl_LocalInvocationIndex == 0u) {
            if (pc.mode == kStartScale)
                state().s.warm_scale = warm_scale(total.x, total.y);
            else
                state().s.warm_qq = total.y;
        }
        return;
    }
    group_max_begin();
    if (gl_LocalInvocationIndex == 0u) group_fluid = 0u;
    barrier();
    if (inside) {
        float diag, off;
        cell_operator(level0, c, kCellPhi, 0.0, diag, off);
        float d = diag > 0.0 ? cell_divergence(c) : 0.0;
        group_max_add(d);
        store_cell(kCellTarget, i, d);
        store_cell(kCellRhs, i, d);
        if (diag > 0.0) atomicAdd(group_fluid, 1u);
    }
    // One global atomic per group, and none where an earlier group already left a larger maximum.
    uint bits;
    if (group_max_end(bits)) {
        StateRef st = state();
        if (bits > st.s.divergence_before) atomicMax(st.s.divergence_before, bits);
        if (group_fluid > 0u) atomicAdd(st.s.fluid_cells, group_fluid);
        if (gl_WorkGroupID.x + gl_WorkGroupID.y == 0u) st.s.recorded = sb().b.cycles_recorded;
    }
}
