#version 460
#extension GL_GOOGLE_include_directive : require
// Per face: velocity plus vorticity confinement (strength pc.param) -> tmp.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    store_face(kFieldTmp, i, confine_face(axis, f, pc.dt, pc.param));
}
