#version 460
#extension GL_GOOGLE_include_directive : require
// Per cell: curl of the velocity and its length, for confinement.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i >= n.x * n.y * n.z) return;
    Vec4Ref(sb().b.vorticity).v[i] = cell_vorticity(cell_from_index(n, i));
}
