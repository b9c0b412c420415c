#version 460
#extension GL_GOOGLE_include_directive : require
// Per face: open fraction from the fluid voxel sets on both sides (beyond the domain: all open), and
// the solid's normal velocity from the moving fragments of both cells.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

CellBits fluid_of(ivec3 c, uint v) {
    ivec3 n = sb().b.dims;
    if (!inside_cells(n, c)) return bits_all(v);
    int i = cell_index(n, c);
    if (WordsRef(sb().b.cell_flags).v[i] == 0u) return bits_all(v);
    CellBits b = bits_none();
    uint cw = sb().b.cell_words;
    for (uint k = 0u; k < cw; ++k) b.w[k] = WordsRef(sb().b.cell_fluid).v[uint(i) * cw + k];
    return b;
}

ivec4 motion_of(ivec3 c) {
    if (!inside_cells(sb().b.dims, c)) return ivec4(0);
    return IVec4Ref(sb().b.cell_motion).v[cell_index(sb().b.dims, c)];
}

void main() {
    int i = thread_index();
    ivec3 n = sb().b.dims;
    if (i >= faces_total(n)) return;
    uint axis;
    ivec3 f = face_from_index(n, i, axis);
    ivec3 lo = f - axis_unit(axis);
    uint v = sb().b.voxels_per_cell;
    bool cut = (inside_cells(n, lo) && WordsRef(sb().b.cell_flags).v[cell_index(n, lo)] != 0u) ||
               (inside_cells(n, f) && WordsRef(sb().b.cell_flags).v[cell_index(n, f)] != 0u);
    float open = 1.0;
    if (cut) {
        CellBits faces[6];
        load_face_masks(faces);
        open = face_open_fraction(fluid_of(lo, v), fluid_of(f, v), axis, v, faces);
    }
    FloatsRef(sb().b.weights).v[i] = open;
    ivec4 m = motion_of(lo) + motion_of(f);
    FloatsRef(sb().b.solid_velocity).v[i] = m.w > 0 ? float(m[axis]) / (kVelocityScale * float(m.w)) : 0.0;
}
