#version 460
#extension GL_GOOGLE_include_directive : require
// Per face: one Jacobi iteration of implicit viscosity (α = pc.param) from face field pc.mode into face
// field diffuse_target(pc.mode).
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
    store_face(diffuse_target(pc.mode), i, diffuse_face(pc.mode, axis, f, pc.param));
}
