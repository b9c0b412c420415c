#version 460
#extension GL_GOOGLE_include_directive : require
// Per face: one pass of extending the air's velocity into closed faces (extend_face, layer pc.iterations)
// from face field pc.parity into pc.level's field (kField* numbers).
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    store_face(pc.level, i, extend_face(pc.parity, axis, f, pc.iterations));
}
