#version 460
#extension GL_GOOGLE_include_directive : require
// Per level-0 cell: the residual b − Lφ, whose maximum joins the convergence check (plain multigrid
// and Jacobi; restriction computes the V-cycle's residuals itself, restrict_cell).
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    group_max_begin();
    int i = thread_index();
    ivec3 n = grid_dims();
    if (i < n.x * n.y * n.z) group_max_add(residual_cell(0u, cell_from_index(n, i)));
    uint bits;
    if (group_max_end(bits) && bits > state().s.residual_scratch) atomicMax(state().s.residual_scratch, bits);
}
