#version 460
#extension GL_GOOGLE_include_directive : require
// Per face: the second pass of extending the air's velocity into closed faces (extend_face, layer 2), from
// the velocity into kFieldTmp.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    store_face(kFieldTmp, i, extend_face(kFieldVelocity, axis, f, 2u));
}
