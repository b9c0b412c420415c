#version 460
#extension GL_GOOGLE_include_directive : require
// The outside-air fill, per wind cell: unites each of its parts with the parts of its +x, +y and +z
// neighbours that share an open voxel pair across the face, and with the outside (node 0) where it
// touches an open domain side. Parts left apart from node 0 are sealed (fill_finish.comp). Cells without
// solid voxels are one whole part and need no voxel sets: most cells take that path.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    if (i >= n.x * n.y * n.z) return;
    ivec3 c = cell_from_index(n, i);
    uint v = hot.voxels_per_cell;
    uint flags = flags_at(i);
    bool cut = (flags & kCellCut) != 0u;
    uint open = hot.open_sides;
    CellBits faces[6];
    CellBits parts[2];
    if (cut) {
        load_face_masks(faces);
        parts[0] = part_of(i, flags, 0u);
        parts[1] = part_of(i, flags, 1u);
    }
    for (uint s = 0u; s < 6u; ++s) {
        uint a = s / 2u;
        bool at_side = (s & 1u) == 0u ? c[a] == 0 : c[a] == n[a] - 1;
        if (!at_side || (open >> s & 1u) == 0u) continue;
        if (!cut) {
            uf_unite(part_node(uint(i), 0u), kOutsideNode);
            continue;
        }
        for (uint k = 0u; k < kCellParts; ++k)
            if (bits_touch(parts[k], faces, s)) uf_unite(part_node(uint(i), k), kOutsideNode);
    }
    for (uint a = 0u; a < 3u; ++a) {
        ivec3 nb = c + axis_unit(a);
        if (!inside_cells(n, nb)) continue;
        int j = cell_index(n, nb);
        uint nb_flags = flags_at(j);
        // Two cells without solid voxels meet over a whole open face: one union, no voxel sets.
        if (!cut && (nb_flags & kCellCut) == 0u) {
            uf_unite(part_node(uint(i), 0u), part_node(uint(j), 0u));
            continue;
        }
        if (!cut) {
            load_face_masks(faces);
            parts[0] = bits_all(v);
            parts[1] = bits_none();
            cut = true;
        }
        for (uint k = 0u; k < kCellParts; ++k) {
            if (bits_count(parts[k]) == 0u) continue;
            for (uint m = 0u; m < kCellParts; ++m) {
                CellBits other = part_of(j, nb_flags, m);
                if (face_open_count(parts[k], other, a, v, faces) != 0u)
                    uf_unite(part_node(uint(i), k), part_node(uint(j), m));
            }
        }
    }
}
