// The coarse solve (coarse_solve.comp, and the last workgroup of the smoothing before it: smooth.comp built
// with GUST_THEN_COARSE): every level from `top` down to the coarsest in shared memory (coarse_shared.glsl),
// by the workgroup's invocations whatever its shape.

uint cells_of(GridLevel level) { return uint(level.dims.x * level.dims.y * level.dims.z); }

uint coarse_width() { return gl_WorkGroupSize.x * gl_WorkGroupSize.y * gl_WorkGroupSize.z; }

/// Red-black Gauss–Seidel sweeps of level l. A half-sweep visits only its own colour's cells, every second
/// one along x from the first of that colour in each row: a loop over every cell that skipped the other
/// colour left half of each group of invocations idle, on a GPU's lanes as on a CPU's vectors.
void smooth_level(uint l, uint sweeps) {
    GridLevel level = load_level(l);
    ivec3 n = level.dims;
    int row_slots = (n.x + 1) / 2;
    uint slots = uint(row_slots * n.y * n.z);
    for (uint half_sweep = 0u; half_sweep < 2u * sweeps; ++half_sweep) {
        for (uint j = gl_LocalInvocationIndex; j < slots; j += coarse_width()) {
            int row = int(j) / row_slots;
            ivec3 c = ivec3(0, row % n.y, row / n.y);
            c.x = 2 * (int(j) - row * row_slots) + ((c.y + c.z + int(half_sweep)) & 1);
            if (c.x < n.x)
                coarse_phi[level.cells - coarse_base + cell_index(n, c)] = relax_cell(level, c, kCellPressure);
        }
        barrier();
    }
}

/// One workgroup solves every level from `top` down to the coarsest with a V-cycle of its own
/// (SolverBindings::smoothing red-black sweeps before and after each coarser level's correction, `sweeps` on
/// the coarsest). Below level 0 the first level's right-hand side is restricted here from the finer level's
/// residual (smoothed before this runs) into memory, where the solve reads it; its correction goes to
/// kCellPressureUp for the finer level's upward pass. With `top` 0 (a grid that small) and `mode`
/// kCoarseBeta it is the whole V-cycle of a conjugate-gradient iteration, and also turns the sums z·r and
/// z·r_old into β.
void coarse_solve(uint top, uint sweeps, uint mode) {
    uint levels = sb().b.levels;
    uint smoothing = sb().b.smoothing;
    uint width = coarse_width();
    GridLevel first = load_level(top);
    coarse_base = first.cells;
    if (top + 1u < levels) coarse_rhs_from = load_level(top + 1u).cells - coarse_base;
    GridLevel last = load_level(levels - 1u);
    uint total = last.cells + cells_of(last) - coarse_base;
    for (uint e = gl_LocalInvocationIndex; e < total; e += width) coarse_phi[e] = 0.0;
    if (top > 0u) {
        GridLevel fine = load_level(top - 1u);
        for (uint i = gl_LocalInvocationIndex; i < cells_of(first); i += width)
            store_cell(kCellRhs, int(first.cells + i), restrict_cell(fine, cell_from_index(first.dims, int(i))));
        // The sweeps read those right-hand sides back from memory in other invocations of this workgroup.
        memoryBarrierBuffer();
    }
    barrier();

    for (uint l = top; l + 1u < levels; ++l) {
        smooth_level(l, smoothing);
        GridLevel fine = load_level(l), coarse = load_level(l + 1u);
        for (uint i = gl_LocalInvocationIndex; i < cells_of(coarse); i += width)
            coarse_rhs[coarse.cells - coarse_base - coarse_rhs_from + i] =
                restrict_cell(fine, cell_from_index(coarse.dims, int(i)));
        barrier();
    }
    smooth_level(levels - 1u, sweeps);
    for (uint l = levels - 1u; l-- > top;) {
        GridLevel level = load_level(l), coarse = load_level(l + 1u);
        for (uint i = gl_LocalInvocationIndex; i < cells_of(level); i += width)
            coarse_phi[level.cells - coarse_base + i] +=
                prolong_cell(level, coarse, cell_from_index(level.dims, int(i)), kCellPressure);
        barrier();
        smooth_level(l, smoothing);
    }

    if (top == 0u && mode == kCoarseCorrection && gl_LocalInvocationIndex == 0u) {
        // Plain multigrid on a grid this small: the next iterate adds this z whole (as smooth.comp's
        // upward pass says on larger grids).
        state().s.p_slot = 2u;
        state().s.cg_alpha = 1.0;
    }
    vec2 sums = vec2(0.0);
    for (uint i = gl_LocalInvocationIndex; i < cells_of(first); i += width) {
        float z = coarse_phi[i];
        store_cell(kCellPressureUp, int(first.cells + i), z);
        if (mode == kCoarseBeta) sums += z * vec2(load_cell(kCellRhs, int(i)), load_cell(kCellOldResidual, int(i)));
    }
    if (mode != kCoarseBeta) return;
    vec2 total_sums = group_sum(sums);
    if (gl_LocalInvocationIndex == 0u) {
        StateRef st = state();
        st.s.cg_beta = cg_beta(total_sums.x, total_sums.y, st.s.cg_rz);
        st.s.cg_rz = total_sums.x;
    }
}
