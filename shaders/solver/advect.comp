#version 460
#extension GL_GOOGLE_include_directive : require
// Per face. pc.parity 0: semi-Lagrangian, velocity -> tmp. 1: MacCormack's backward pass, tmp -> back.
// 2: MacCormack's clamped correction, in place in tmp.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    if (pc.parity == 0u) store_face(kFieldTmp, i, advect_face(kFieldVelocity, axis, f, pc.dt));
    else if (pc.parity == 1u) store_face(kFieldBack, i, advect_face(kFieldTmp, axis, f, -pc.dt));
    else store_face(kFieldTmp, i, maccormack_face(axis, f, pc.dt));
}
