#version 460
#extension GL_GOOGLE_include_directive : require
// Per face of multigrid level pc.level (> 0): the mean weight of the finer faces it covers.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    GridLevel level = load_level(pc.level);
    if (i >= faces_total(level.dims)) return;
    uint axis;
    ivec3 f = face_from_index(level.dims, i, axis);
    FloatsRef(sb().b.weights).v[int(level.faces - sb().b.level0_faces) + i] = coarse_weight(pc.level, axis, f);
}
