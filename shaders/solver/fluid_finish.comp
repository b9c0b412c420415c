#version 460
#extension GL_GOOGLE_include_directive : require
// The end of solid_faces.comp's link_fluid, per wind cell: a cell with air whose node is apart from the outside is a
// pocket of the pressure equation. It becomes kCellNoAir, solid for the wind (its solid fraction 1, the
// open pairs of its faces 0), and counts as sealed. Its air is a few voxels cut off from the cells'
// chosen parts, so sealing it loses no flow.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

shared uint group_sealed;

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    uint cells = uint(n.x * n.y * n.z);
    if (gl_LocalInvocationIndex == 0u) group_sealed = 0u;
    barrier();
    if (uint(i) < cells && (flags_at(i) & kCellNoAir) == 0u &&
        uf_find(fluid_node(uint(i), cells)) != kOutsideNode) {
        atomicOr(WordsRef(hot.cell_flags).v[i], kCellNoAir);
        FloatsRef(hot.cell_solid).v[i] = 1.0;
        ivec3 c = cell_from_index(n, i);
        for (uint a = 0u; a < 3u; ++a) {
            for (int side = 0; side < 2; ++side) {
                int face = face_index(n, a, c + side * axis_unit(a));
                atomicAnd(WordsRef(hot.open_counts).v[face >> 2], ~(0xffu << (8u * uint(face & 3))));
            }
        }
        atomicAdd(group_sealed, 1u);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && group_sealed > 0u) atomicAdd(state().s.sealed_cells, group_sealed);
}
