#version 460
#extension GL_GOOGLE_include_directive : require
// Per face: emitters (closing pc.param of the gap each) and the ambient wind on the domain's faces,
// from face field pc.parity (advection's output, or the velocity itself without advection) into the velocity.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    store_face(kFieldVelocity, i, force_face(pc.parity, axis, f, pc.param));
}
