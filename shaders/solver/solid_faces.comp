#version 460
#extension GL_GOOGLE_include_directive : require
// Per four faces (one word of open_counts): the open voxel pairs from the fluid voxel sets on both
// sides (beyond the domain: all open), and the solid's normal velocity from the moving fragments of
// both cells.
#include "solver_common.glsl"

layout(local_size_x = kSolverGroupSize) in;

/// The cell's kCellCut / kCellMoving flags, none beyond the domain.
uint flags_of(ivec3 c) {
    ivec3 n = sb().b.dims;
    return inside_cells(n, c) ? WordsRef(sb().b.cell_flags).v[cell_index(n, c)] : 0u;
}

CellBits fluid_of(ivec3 c, uint flags, uint v) {
    if ((flags & kCellCut) == 0u) return bits_all(v);
    CellBits b = bits_none();
    uint cw = sb().b.cell_words;
    int i = cell_index(sb().b.dims, c);
    for (uint k = 0u; k < cw; ++k) b.w[k] = WordsRef(sb().b.cell_fluid).v[uint(i) * cw + k];
    return b;
}

ivec4 motion_of(ivec3 c, uint flags) {
    if ((flags & kCellMoving) == 0u) return ivec4(0);
    return IVec4Ref(sb().b.cell_motion).v[cell_index(sb().b.dims, c)];
}

void main() {
    int t = thread_index();
    ivec3 n = sb().b.dims;
    int total = faces_total(n);
    if (uint(t) >= open_count_words(uint(total))) return;
    uint v = sb().b.voxels_per_cell;
    uint counts = 0u;
    for (int k = 0; k < 4 && 4 * t + k < total; ++k) {
        int i = 4 * t + k;
        uint axis;
        ivec3 f = face_from_index(n, i, axis);
        ivec3 lo = f - axis_unit(axis);
        uint flags_lo = flags_of(lo), flags_hi = flags_of(f);
        uint open = v * v;
        if (((flags_lo | flags_hi) & kCellCut) != 0u) {
            CellBits faces[6];
            load_face_masks(faces);
            open = face_open_count(fluid_of(lo, flags_lo, v), fluid_of(f, flags_hi, v), axis, v, faces);
        }
        counts |= open << (8 * k);
        ivec4 m = motion_of(lo, flags_lo) + motion_of(f, flags_hi);
        FloatsRef(sb().b.solid_velocity).v[i] = m.w > 0 ? float(m[axis]) / (kVelocityScale * float(m.w)) : 0.0;
    }
    WordsRef(sb().b.open_counts).v[t] = counts;
}
