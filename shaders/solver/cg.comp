#version 460
#extension GL_GOOGLE_include_directive : require
// Per level-0 cell, the rest of a conjugate-gradient iteration after its V-cycle: the new search direction
// p_k = z + β p_{k-1} (into the other direction buffer), the sum of p_k · L p_k (each neighbour's p_k
// computed here from its z and p_{k-1}), and in the workgroup that finishes last α = (r·z)/(p·Lp). The next
// iteration's first pass (smooth.comp) then moves the iterate along p_k.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

float direction(int i, float beta) { return load_cell(kCellPressureUp, i) + beta * load_cell(kCellDirection, i); }

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    bool inside = i < n.x * n.y * n.z;
    float beta = state().s.cg_beta;
    float sum = 0.0;
    if (inside) {
        ivec3 c = cell_from_index(n, i);
        float p = direction(i, beta);
        store_cell(kCellDirectionB, i, p);
        GridLevel level = load_level(0u);
        uint open = grid_open_sides();
        float lap = 0.0;
        for (uint a = 0u; a < 3u; ++a)
            for (uint s = 0u; s < 2u; ++s) {
                int nb;
                float w = face_coupling(level, open, c, a, s, nb);
                if (w != 0.0) lap += w * ((nb >= 0 ? direction(nb, beta) : 0.0) - p);
            }
        sum = p * lap;
    }
    vec2 total;
    if (sum_dispatch(vec2(sum, 0.0), total) && gl_LocalInvocationIndex == 0u) {
        StateRef st = state();
        st.s.cg_alpha = cg_alpha(st.s.cg_rz, total.x);
        // The direction just written is p_k; in absolute terms kCellDirectionB is buffer B on even iterations.
        st.s.p_slot = (pc.swap & 2u) != 0u ? 0u : 1u;
    }
}
