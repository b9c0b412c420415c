#version 460
#extension GL_GOOGLE_include_directive : require
// Per face, the velocity's next field into kFieldTmp. Mode (kMode) kAdvectSemiLagrangian: semi-Lagrangian
// advection, then the emitters (closing pc.param of the gap), the ambient wind on the domain's faces and
// vorticity confinement (forced_face), all in this one pass. MacCormack in two passes: kAdvectForward the
// forward pass (kFieldScratch, and the range it blended into kFieldLow and kFieldHigh), kAdvectCorrect the
// backward pass, the clamped correction and the same forces into kFieldTmp (maccormack_face: a face's
// backward value serves only its own correction, so it needs no pass of its own). kAdvectForces: no
// advection, the forces alone.
// The mode is the pipeline's specialization constant 0 (pc.mode holds it too), so a compiler keeps only
// that mode's code: a CPU device executes every branch, taken or not. Constant 1 (kNested) does the same for
// the cascades' code.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
layout(constant_id = 0) const uint kMode = 0u;
// Whether the solver has a coarser or finer cascade (SolverPush::nest may then be set): without one, the
// compiler drops the cascades' code, whose inlined reads otherwise cost a grid on its own half again.
layout(constant_id = 1) const bool kNested = true;
#define GUST_NESTED_CONSTANT
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    float epsilon = sb().b.vorticity_strength;
    if (kMode == kAdvectSemiLagrangian)
        store_face(
            kFieldTmp, i,
            forced_face(advect_face(kFieldVelocity, axis, f, pc.dt), axis, f, pc.param, pc.dt, epsilon));
    else if (kMode == kAdvectForward) {
        vec2 range;
        store_face(kFieldScratch, i, advect_face_range(axis, f, pc.dt, range));
        store_face(kFieldLow, i, range.x);
        store_face(kFieldHigh, i, range.y);
    } else if (kMode == kAdvectForces)
        store_face(kFieldTmp, i,
                   forced_face(load_face(kFieldVelocity, i), axis, f, pc.param, pc.dt, epsilon));
    else
        store_face(kFieldTmp, i, forced_face(maccormack_face(axis, f, pc.dt), axis, f, pc.param, pc.dt, epsilon));
}
