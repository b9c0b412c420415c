#version 460
#extension GL_GOOGLE_include_directive : require
// pc.mode kScrollMove: per face, the field moved by pc.shift cells (new face f is old face f + shift) into
// kFieldTmp; faces with no old counterpart take the wind beyond the grid there (the ambient wind, or the
// next coarser cascade's). The first threads, one per cell, move φ the same way into kCellScratch (new
// cells 0), so that the next solve's warm start still lines up with the field.
// kScrollAmbientChange: per open face, the change of the ambient wind added in place (docs/solver.md,
// "Ambient wind"), and to the field kept for the finer cascades where there is one.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    if (pc.mode == kScrollAmbientChange) {
        if (i >= faces_total(n)) return;
        uint axis;
        ivec3 f = face_from_index(n, i, axis);
        if (!face_open(axis, f)) return;
        float change = sb().b.ambient_change[axis];
        store_face(kFieldVelocity, i, load_face(kFieldVelocity, i) + change);
        if (sb().b.previous != 0ul) FloatsRef(sb().b.previous).v[i] += change;
        return;
    }
    if (i < n.x * n.y * n.z) {
        ivec3 src = cell_from_index(n, i) + pc.shift;
        store_cell(kCellScratch, i, inside_cells(n, src) ? load_cell(kCellPhi, cell_index(n, src)) : 0.0);
    }
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    ivec3 src = f + pc.shift;
    ivec3 m = n + axis_unit(axis);
    bool inside = all(greaterThanEqual(src, ivec3(0))) && all(lessThan(src, m));
    // The grid's origin moves by the shift once this pass is done: the new face's world position.
    vec3 x = grid_origin() + (face_position(axis, f) + vec3(pc.shift)) * grid_h();
    store_face(kFieldTmp, i, inside ? load_face(kFieldVelocity, face_index(n, axis, src)) : beyond_component(axis, x));
}
