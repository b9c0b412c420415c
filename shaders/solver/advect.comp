#version 460
#extension GL_GOOGLE_include_directive : require
// Per face, the velocity's next field into kFieldTmp. Mode (kMode) kAdvectSemiLagrangian: semi-Lagrangian
// advection, then the emitters (closing pc.param of the gap), the ambient wind on the domain's faces and
// vorticity confinement (forced_face), all in this one pass. MacCormack in two passes: kAdvectForward the
// forward pass (kFieldScratch, and the range it blended into kFieldLow and kFieldHigh), kAdvectCorrect the
// backward pass, the clamped correction and the same forces into kFieldTmp (maccormack_face: a face's
// backward value serves only its own correction, so it needs no pass of its own). kAdvectForces: no
// advection, the forces alone.
// kAdvectCorrectScale: kAdvectCorrect that also sums the warm start's b·q over the faces it writes (start.comp's
// kStartQ left q and q·q), and the workgroup that finishes last makes the scale. Only this mode's pipeline
// holds the sum's barriers: in a pass this large they cost a CPU device a tenth of the pass, even untaken.
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

/// Face i's share of b·q, where b is the divergence the face's final value u gives the cells beside it: the
/// flux leaves the cell below and enters the one above, so Σ_cells b·q = Σ_faces flux·(q_below − q_above)/h
/// (q = 0 beyond the grid, and in cells without open faces, whose b is 0).
float warm_face_product(int i, uint axis, ivec3 f, float u) {
    ivec3 n = grid_dims();
    ivec3 below = f - axis_unit(axis);
    float q_below = inside_cells(n, below) ? load_cell(kCellScratch, cell_index(n, below)) : 0.0;
    float q_above = inside_cells(n, f) ? load_cell(kCellScratch, cell_index(n, f)) : 0.0;
    return face_flux_of(i, u) * (q_below - q_above) / grid_h();
}

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    if (kMode == kAdvectCorrectScale) {
        // Every thread reaches the sum's barriers.
        float product = 0.0;
        if (i < faces_total(n)) {
            uint axis;
            ivec3 f = face_from_index(n, i, axis);
            float u = forced_face(maccormack_face(axis, f, pc.dt), axis, f, pc.param, pc.dt,
                                  sb().b.vorticity_strength);
            store_face(kFieldTmp, i, u);
            product = warm_face_product(i, axis, f, u);
        }
        vec2 total;
        if (sum_dispatch(vec2(product, 0.0), total) && gl_LocalInvocationIndex == 0u)
            state().s.warm_scale = warm_scale(total.x, state().s.warm_qq);
        return;
    }
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
