#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell, the step's end over its final velocity: φ as the solve left it (load_phi) stored as the step's
// pressure solution (kCellPhi: the output and the next warm start), its residual b − Lφ and the divergence
// left (their maxima for the stats), the vorticity the next step's confinement reads, and, when
// SolverBindings::texels is set, the wind texture's texel (cell_output).
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

shared uint group_residual;

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    bool inside = i < n.x * n.y * n.z;
    group_max_begin();
    if (gl_LocalInvocationIndex == 0u) group_residual = 0u;
    barrier();
    if (inside) {
        ivec3 c = cell_from_index(n, i);
        float phi = load_phi(i);
        store_cell(kCellPhi, i, phi);
        GridLevel level = load_level(0u);
        uint open = grid_open_sides();
        float diag = 0.0, lap = 0.0;
        for (uint a = 0u; a < 3u; ++a)
            for (uint s = 0u; s < 2u; ++s) {
                int nb;
                float w = face_coupling(level, open, c, a, s, nb);
                if (w == 0.0) continue;
                diag += w;
                lap += w * ((nb >= 0 ? load_phi(nb) : 0.0) - phi);
            }
        if (diag > 0.0) {
            group_max_add(cell_divergence(c));
            atomicMax(group_residual, floatBitsToUint(abs(load_cell(kCellTarget, i) - lap)));
        }
        Vec4Ref(hot.vorticity).v[i] = cell_vorticity(c);
        if (sb().b.texels != 0ul) store_texel(i);
    }
    uint bits;
    if (group_max_end(bits)) {
        StateRef st = state();
        if (bits > st.s.divergence_after) atomicMax(st.s.divergence_after, bits);
        if (group_residual > st.s.residual) atomicMax(st.s.residual, group_residual);
    }
}
