#version 460
#extension GL_GOOGLE_include_directive : require
// Per four faces (one word of open_counts): the open voxel pairs between the air of the cells on both
// sides (beyond the domain: all open), and the solid's normal velocity from the moving fragments of
// both cells (or the sealed region a cell without air lies in), over the share of the face's closed pairs
// that touch no static solid (moving_share).
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

/// The cell's kCell* flags, none beyond the domain.
uint flags_of(ivec3 c) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? flags_at(cell_index(n, c)) : 0u;
}

ivec4 motion_of(ivec3 c, uint flags) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? solid_motion_of(cell_index(n, c), flags) : ivec4(0);
}

CellBits static_at(ivec3 c, uint flags) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? static_of(cell_index(n, c), flags) : bits_none();
}

CellBits air_at(ivec3 c, uint flags) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? air_of(cell_index(n, c), flags) : bits_all(hot.voxels_per_cell);
}

void main() {
    load_bindings();
    int t = thread_index();
    ivec3 n = hot.dims;
    int total = faces_total(n);
    if (uint(t) >= open_count_words(uint(total))) return;
    uint v = hot.voxels_per_cell;
    uint counts = 0u;
    // The face layers are loaded once, by the first face that compares voxel sets.
    CellBits faces[6];
    bool masks = false;
    for (int k = 0; k < 4 && 4 * t + k < total; ++k) {
        int i = 4 * t + k;
        uint axis;
        ivec3 f = face_from_index(n, i, axis);
        ivec3 lo = f - axis_unit(axis);
        uint flags_lo = flags_of(lo), flags_hi = flags_of(f);
        uint open = v * v;
        if (((flags_lo | flags_hi) & kCellNoAir) != 0u) {
            open = 0u;
        } else if (((flags_lo | flags_hi) & kCellCut) != 0u) {
            if (!masks) load_face_masks(faces);
            masks = true;
            open = face_open_count(air_at(lo, flags_lo), air_at(f, flags_hi), axis, v, faces);
        }
        counts |= open << (8 * k);
        ivec4 m = motion_of(lo, flags_lo) + motion_of(f, flags_hi);
        float share = 1.0;
        if (m.w > 0 && ((flags_lo | flags_hi) & kCellStatic) != 0u) {
            if (!masks) load_face_masks(faces);
            masks = true;
            share = moving_share(v * v - open, face_any_count(static_at(lo, flags_lo), static_at(f, flags_hi), axis, v, faces));
        }
        FloatsRef(hot.solid_velocity).v[i] = m.w > 0 ? share * float(m[axis]) / (kVelocityScale * float(m.w)) : 0.0;
    }
    WordsRef(hot.open_counts).v[t] = counts;
}
