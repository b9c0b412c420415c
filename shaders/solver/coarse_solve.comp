#version 460
#extension GL_GOOGLE_include_directive : require
// One workgroup solves every level from pc.level down to the coarsest in shared memory, with a V-cycle of
// its own (SolverBindings::smoothing red-black sweeps before and after each coarser level's correction,
// pc.iterations sweeps on the coarsest): levels of at most kCoarseCells cells (16^3) cost this one
// dispatch together, where a dispatch per sweep and level cost microseconds whatever its size. Below level
// 0 the first level's right-hand side is restricted here from the finer level's residual (the dispatch
// before this one smoothed it) into memory, where the solve reads it; its correction goes to
// kCellPressureUp for the finer level's upward pass. With pc.level 0 (a grid that small) and pc.mode kCoarseBeta it is the whole V-cycle
// of a conjugate-gradient iteration, and also turns the sums z·r and z·r_old into β.
#include "solver_io.h"

const uint kCoarseValues = kCoarseCells + kCoarseCells / 7u + 16u;
const uint kCoarseRhs = kCoarseCells / 7u + 16u;
shared float coarse_phi[kCoarseValues];
shared float coarse_rhs[kCoarseRhs];
uint coarse_base = 0u;
uint coarse_rhs_from = 0x7fffffffu;

// As wide as the device allows (constant 0, a power of two from 64 to 1024).
layout(local_size_x_id = 0) in;
#define GUST_COARSE_SHARED 1
#include "solver_common.glsl"

uint cells_of(GridLevel level) { return uint(level.dims.x * level.dims.y * level.dims.z); }

/// Red-black Gauss–Seidel sweeps of level l. A half-sweep visits only its own colour's cells, every second
/// one along x from the first of that colour in each row: a loop over every cell that skipped the other
/// colour left half of each group of invocations idle, on a GPU's lanes as on a CPU's vectors.
void smooth_level(uint l, uint sweeps) {
    GridLevel level = load_level(l);
    ivec3 n = level.dims;
    int row_slots = (n.x + 1) / 2;
    uint slots = uint(row_slots * n.y * n.z);
    for (uint half_sweep = 0u; half_sweep < 2u * sweeps; ++half_sweep) {
        for (uint j = gl_LocalInvocationIndex; j < slots; j += gl_WorkGroupSize.x) {
            int row = int(j) / row_slots;
            ivec3 c = ivec3(0, row % n.y, row / n.y);
            c.x = 2 * (int(j) - row * row_slots) + ((c.y + c.z + int(half_sweep)) & 1);
            if (c.x < n.x)
                coarse_phi[level.cells - coarse_base + cell_index(n, c)] = relax_cell(level, c, kCellPressure);
        }
        barrier();
    }
}

void main() {
    load_bindings();
    uint top = pc.level;
    uint levels = sb().b.levels;
    uint smoothing = sb().b.smoothing;
    GridLevel first = load_level(top);
    coarse_base = first.cells;
    if (top + 1u < levels) coarse_rhs_from = load_level(top + 1u).cells - coarse_base;
    GridLevel last = load_level(levels - 1u);
    uint total = last.cells + cells_of(last) - coarse_base;
    for (uint e = gl_LocalInvocationIndex; e < total; e += gl_WorkGroupSize.x) coarse_phi[e] = 0.0;
    if (top > 0u) {
        GridLevel fine = load_level(top - 1u);
        for (uint i = gl_LocalInvocationIndex; i < cells_of(first); i += gl_WorkGroupSize.x)
            store_cell(kCellRhs, int(first.cells + i), restrict_cell(fine, cell_from_index(first.dims, int(i))));
        // The sweeps read those right-hand sides back from memory in other invocations of this workgroup.
        memoryBarrierBuffer();
    }
    barrier();

    for (uint l = top; l + 1u < levels; ++l) {
        smooth_level(l, smoothing);
        GridLevel fine = load_level(l), coarse = load_level(l + 1u);
        for (uint i = gl_LocalInvocationIndex; i < cells_of(coarse); i += gl_WorkGroupSize.x)
            coarse_rhs[coarse.cells - coarse_base - coarse_rhs_from + i] =
                restrict_cell(fine, cell_from_index(coarse.dims, int(i)));
        barrier();
    }
    smooth_level(levels - 1u, pc.iterations);
    for (uint l = levels - 1u; l-- > top;) {
        GridLevel level = load_level(l), coarse = load_level(l + 1u);
        for (uint i = gl_LocalInvocationIndex; i < cells_of(level); i += gl_WorkGroupSize.x)
            coarse_phi[level.cells - coarse_base + i] +=
                prolong_cell(level, coarse, cell_from_index(level.dims, int(i)), kCellPressure);
        barrier();
        smooth_level(l, smoothing);
    }

    if (top == 0u && pc.mode == kCoarseCorrection && gl_LocalInvocationIndex == 0u) {
        // Plain multigrid on a grid this small: the next iterate adds this z whole (as smooth.comp's
        // upward pass says on larger grids).
        state().s.p_slot = 2u;
        state().s.cg_alpha = 1.0;
    }
    vec2 sums = vec2(0.0);
    for (uint i = gl_LocalInvocationIndex; i < cells_of(first); i += gl_WorkGroupSize.x) {
        float z = coarse_phi[i];
        store_cell(kCellPressureUp, int(first.cells + i), z);
        if (pc.mode == kCoarseBeta) sums += z * vec2(load_cell(kCellRhs, int(i)), load_cell(kCellOldResidual, int(i)));
    }
    if (pc.mode != kCoarseBeta) return;
    vec2 total_sums = group_sum(sums);
    if (gl_LocalInvocationIndex == 0u) {
        StateRef st = state();
        st.s.cg_beta = cg_beta(total_sums.x, total_sums.y, st.s.cg_rz);
        st.s.cg_rz = total_sums.x;
    }
}
