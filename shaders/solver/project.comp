#version 460
#extension GL_GOOGLE_include_directive : require
// Per face, into kFieldTmp: the pressure gradient subtracted (φ as the solve left it, load_phi; none after a
// diverged solve), closed faces the solid's velocity, and both passes of the air's extension into closed
// faces (project_extended_face), which computes its neighbours' projected and first-pass values where it
// needs them.
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
    store_face(kFieldTmp, i, project_extended_face(axis, f, state().s.diverged == 0u));
}
