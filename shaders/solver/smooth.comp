#version 460
#extension GL_GOOGLE_include_directive : require
// The V-cycle's smoothing in shared-memory tiles: a workgroup owns an 8^3 tile of level pc.level's cells,
// loads it with a one-cell halo, and runs SolverBindings::smoothing red-black Gauss–Seidel sweeps on the
// tile with the halo held at its loaded values (block Gauss–Seidel: exact inside a tile, Jacobi-like
// across tiles), so a level's smoothing costs one dispatch, not one per half-sweep. pc.mode:
//   kSmoothStart (level 0, the solve's first pass, k = 0): the right-hand side b, the divergence
//     (kCellTarget), its maximum and the fluid cells, then as kSmoothFirst.
//   kSmoothFirst, kSmoothFirstPlain (level 0, first pass of an iteration): the iterate
//     x_k = x_{k-1} + α p_{k-1} (k = pc.iterations; x_0 = s φ, the warm start; kSmoothFirstPlain is plain
//     multigrid, where p is last iteration's z and α = 1), written to the other iterate, and its residual
//     r = b − L x_k computed exactly (the last residual kept as r_old), with the convergence check in the
//     workgroup that finishes last; then smoothing from zero against r, unless the coarse solve holds
//     level 0 (SolverBindings::coarse_level 0), which smooths it itself.
//   kSmoothDown (a level between): the level's right-hand side restricted from the finer level's residual
//     (restrict_cell, stored as kCellRhs for the upward pass), then smoothing from zero against it: the
//     restriction needs the finer level's smoothing done, which the dispatch before this one is, so it
//     costs no dispatch of its own.
//   kSmoothUp (upward): the level's downward values plus the coarser level's correction (prolong_cell from
//     kCellPressureUp), smoothed against the right-hand side, into kCellPressureUp.
//   kSmoothUpBeta (level 0 upward, conjugate gradients): as kSmoothUp, then the sums z·r and z·r_old,
//     which the workgroup that finishes last turns into β.
// The mode is the pipeline's specialization constant 0 (pc.mode holds it too), so a compiler keeps only
// that mode's code: a CPU device executes every branch, taken or not.
// Built with GUST_THEN_COARSE (PassLayout::FewerStages; the pass just above the coarse solve's levels:
// kSmoothStart, kSmoothFirst or kSmoothFirstPlain when that is level 1, else kSmoothDown), the workgroup that
// finishes last then runs the coarse solve (coarse_levels.glsl), whose restriction needs this level smoothed
// everywhere: a V-cycle's dispatch and stage fewer. The first pass's convergence check moves there too, so a
// solve that converged skips the coarse solve as its emptied dispatch did.
#include "solver_io.h"
#ifdef GUST_THEN_COARSE
#define GUST_COHERENT_CELLS 1
#include "coarse_shared.glsl"
const bool kThenCoarse = true;
#else
const bool kThenCoarse = false;
#endif
layout(local_size_x = kTileSide, local_size_y = kTileSide, local_size_z = kTileSide) in;
layout(constant_id = 0) const uint kMode = 0u;
#include "solver_common.glsl"
#ifdef GUST_THEN_COARSE
#include "coarse_levels.glsl"
#endif

const int kSide = int(kTileSide);
const int kSpan = kSide + 2;
shared float tile[kSpan * kSpan * kSpan];
shared uint group_b_max;
shared uint group_fluid;

int slot_of(ivec3 local) { return (local.x + 1) + kSpan * ((local.y + 1) + kSpan * (local.z + 1)); }

#ifdef GUST_THEN_COARSE
shared bool group_converged;

/// In the workgroup that finishes last: the first pass's convergence check, then, unless the solve is done,
/// the coarse solve from the level below this one.
void then_coarse(bool first) {
    if (!last_group()) return;
    if (first) {
        if (gl_LocalInvocationIndex == 0u) {
            // The iterate this pass wrote is x_k; in absolute terms kCellSolutionB is buffer B on even iterations.
            convergence_check((pc.swap & 2u) != 0u ? 0u : 1u);
            group_converged = state().s.done != 0u;
        }
        barrier();
        if (group_converged) return;
    }
    coarse_solve(sb().b.coarse_level, kCoarseSweeps, kCoarseCorrection);
}
#endif

/// Value of level-0 cell c of the iterate x_k.
float iterate(ivec3 c, bool plain) {
    int i = cell_index(grid_dims(), c);
    if (pc.iterations == 0u) {
        float s = state().s.warm_scale;
        return s != 0.0 ? s * load_cell(kCellPhi, i) : 0.0;
    }
    float alpha = plain ? 1.0 : state().s.cg_alpha;
    return load_cell(kCellSolution, i) + alpha * load_cell(plain ? kCellPressureUp : kCellDirection, i);
}

void main() {
    load_bindings();
    uint l = pc.level;
    const uint mode = kMode;
    GridLevel level = load_level(l);
    ivec3 local = ivec3(gl_LocalInvocationID);
    bool up = mode == kSmoothUp || mode == kSmoothUpBeta;
    // Only the upward leg prolongs from the next level.
    GridLevel coarse = up ? load_level(l + 1u) : level;
    ivec3 origin = ivec3(gl_WorkGroupID) * kSide - (up ? ivec3(kSide / 2) : ivec3(0));
    ivec3 c = origin + local;
    bool mine = all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, level.dims));
    int i = mine ? int(level.cells) + cell_index(level.dims, c) : 0;
    uint open = grid_open_sides();
    bool start = mode == kSmoothStart;
    bool first = start || mode == kSmoothFirst || mode == kSmoothFirstPlain;

    // The cell's six couplings (cell_operator's faces): weight, and where the neighbour's value lives.
    float w[6];
    int nb_slot[6]; // tile slot, or -1 for an open side's φ = 0
    float diag = 0.0;
    if (mine) {
        for (uint a = 0u; a < 3u; ++a)
            for (uint s = 0u; s < 2u; ++s) {
                int nb;
                w[2u * a + s] = face_coupling(level, open, c, a, s, nb);
                diag += w[2u * a + s];
                nb_slot[2u * a + s] = nb >= 0 ? slot_of(local + (s == 0u ? -1 : 1) * axis_unit(a)) : -1;
            }
    }

    // The right-hand side the tile smooths against.
    float rhs = 0.0;
    if (first) {
        if (start && gl_LocalInvocationIndex == 0u) {
            group_b_max = 0u;
            group_fluid = 0u;
        }
        group_max_begin();
        if (mine) {
            bool plain = mode == kSmoothFirstPlain;
            float b = 0.0;
            if (start) {
                b = diag > 0.0 ? cell_divergence(c) : 0.0;
                store_cell(kCellTarget, i, b);
                atomicMax(group_b_max, floatBitsToUint(abs(b)));
                if (diag > 0.0) atomicAdd(group_fluid, 1u);
            }
            float x = iterate(c, plain);
            float lap = 0.0;
            for (uint a = 0u; a < 3u; ++a)
                for (uint s = 0u; s < 2u; ++s) {
                    float wf = w[2u * a + s];
                    if (wf == 0.0) continue;
                    ivec3 n = c + (s == 0u ? -1 : 1) * axis_unit(a);
                    lap += wf * ((nb_slot[2u * a + s] >= 0 ? iterate(n, plain) : 0.0) - x);
                }
            if (!start) b = load_cell(kCellTarget, i);
            rhs = diag > 0.0 ? b - lap : 0.0;
            store_cell(kCellSolutionB, i, x);
            store_cell(kCellOldResidual, i, start ? b : load_cell(kCellRhs, i));
            store_cell(kCellRhs, i, rhs);
            group_max_add(rhs);
        }
        uint bits;
        if (group_max_end(bits)) {
            StateRef st = state();
            if (bits > st.s.residual_scratch) atomicMax(st.s.residual_scratch, bits);
            if (start) {
                // Before last_group() below, so the convergence check sees every group's maximum of b.
                if (group_b_max > st.s.divergence_before) atomicMax(st.s.divergence_before, group_b_max);
                if (group_fluid > 0u) atomicAdd(st.s.fluid_cells, group_fluid);
                if (gl_WorkGroupID == uvec3(0)) st.s.recorded = sb().b.cycles_recorded;
            }
        }
        // The iterate just written is x_k; in absolute terms kCellSolutionB is buffer B on even iterations.
        if (!kThenCoarse && last_group() && gl_LocalInvocationIndex == 0u)
            convergence_check((pc.swap & 2u) != 0u ? 0u : 1u);
    } else if (mine && mode == kSmoothDown) {
        rhs = restrict_cell(load_level(l - 1u), c);
        store_cell(kCellRhs, i, rhs);
    } else if (mine) {
        rhs = load_cell(kCellRhs, i);
    }
    // A grid small enough for the coarse solve to hold level 0 is smoothed there, from zero: the first pass
    // gives it the iterate and the residual only.
    if (first && sb().b.coarse_level == 0u) return;

    // Load the tile and its halo: zero going down; going up, the downward values plus the correction.
    for (int e = int(gl_LocalInvocationIndex); e < kSpan * kSpan * kSpan; e += kSide * kSide * kSide) {
        ivec3 t = ivec3(e % kSpan, (e / kSpan) % kSpan, e / (kSpan * kSpan)) - ivec3(1);
        ivec3 cell = origin + t;
        float value = 0.0;
        if (up && all(greaterThanEqual(cell, ivec3(0))) && all(lessThan(cell, level.dims))) {
            int j = int(level.cells) + cell_index(level.dims, cell);
            value = load_cell(kCellPressure, j) + prolong_cell(level, coarse, cell, kCellPressureUp);
        }
        tile[e] = value;
    }
    barrier();

    int self = slot_of(local);
    uint colour = uint(c.x + c.y + c.z) & 1u;
    for (uint half_sweep = 0u, sweeps = 2u * sb().b.smoothing; half_sweep < sweeps; ++half_sweep) {
        if (mine && colour == (half_sweep & 1u) && diag > 0.0) {
            float phi = tile[self];
            float off = 0.0;
            for (uint f = 0u; f < 6u; ++f) {
                if (w[f] == 0.0) continue;
                off += w[f] * ((nb_slot[f] >= 0 ? tile[nb_slot[f]] : 0.0) - phi);
            }
            tile[self] = phi + (off - rhs) / diag;
        }
        barrier();
    }
    float z = mine && diag > 0.0 ? tile[self] : 0.0;
    if (mine) store_cell(up ? kCellPressureUp : kCellPressure, i, z);
#ifdef GUST_THEN_COARSE
    then_coarse(first);
    return;
#endif

    if (mode == kSmoothUp && l == 0u && gl_WorkGroupID == uvec3(0) && gl_LocalInvocationIndex == 0u) {
        // Plain multigrid: the next iterate adds this z whole.
        state().s.p_slot = 2u;
        state().s.cg_alpha = 1.0;
    }
    if (mode != kSmoothUpBeta) return;
    vec2 sums = mine ? z * vec2(rhs, load_cell(kCellOldResidual, i)) : vec2(0.0);
    vec2 total;
    if (sum_dispatch(sums, total) && gl_LocalInvocationIndex == 0u) {
        StateRef st = state();
        st.s.cg_beta = cg_beta(total.x, total.y, st.s.cg_rz);
        st.s.cg_rz = total.x;
    }
}
