#version 460
#extension GL_GOOGLE_include_directive : require
// Per face, in place: subtracts the pressure gradient (none after a diverged solve); closed faces take the
// solid's velocity.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    store_face(kFieldVelocity, i, project_face(axis, f, state().s.diverged == 0u));
}
