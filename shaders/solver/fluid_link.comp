#version 460
#extension GL_GOOGLE_include_directive : require
// The pressure equation's own connectivity, per wind cell; run only when the fill found a cell with two
// parts of outside air (fill_finish.comp). Such a cell's pressure stands for one of them, so cells that
// reach an open side only through its other part would form a pocket: a block of the pressure equation
// with no open side, singular, and inconsistent wherever its divergence does not sum to zero. Unites the
// cell with its +x, +y and +z neighbours across faces with open voxel pairs (solid_faces.comp's counts),
// and with the outside across the open faces of an open domain side; fluid_finish.comp seals the rest.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

/// Open voxel pairs of level-0 face `face`.
uint open_count_at(int face) {
    return open_count_in(WordsRef(hot.open_counts).v[face >> 2], uint(face));
}

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    uint cells = uint(n.x * n.y * n.z);
    if (uint(i) >= cells || (flags_at(i) & kCellNoAir) != 0u) return;
    ivec3 c = cell_from_index(n, i);
    uint node = fluid_node(uint(i), cells);
    for (uint a = 0u; a < 3u; ++a) {
        ivec3 high = c + axis_unit(a);
        if (c[a] == 0 && (hot.open_sides >> (2u * a) & 1u) != 0u && open_count_at(face_index(n, a, c)) != 0u)
            uf_unite(node, kOutsideNode);
        if (!inside_cells(n, high)) {
            if ((hot.open_sides >> (2u * a + 1u) & 1u) != 0u && open_count_at(face_index(n, a, high)) != 0u)
                uf_unite(node, kOutsideNode);
        } else if (open_count_at(face_index(n, a, high)) != 0u) {
            uf_unite(node, fluid_node(uint(cell_index(n, high)), cells));
        }
    }
}
