#version 460
#extension GL_GOOGLE_include_directive : require
// The outside-air fill's end, per wind cell: a part is air when its set holds node 0 (it reaches an open
// domain side), else sealed. The cell's air is its first part that is air (kCellSecondPart when that is
// part 1); a cell with none is kCellNoAir, solid for the wind. Writes the solid fraction (1 − air share),
// and adds a moving cell's mean fragment velocity to each sealed region it borders, weighted by the share
// of the solid its part touches that is not static (region_weight), so the air sealed inside a moving
// solid moves with it and the air inside a static one stays still (solid_motion_of). A cell whose two parts both reach the outside
// turns on fluid_link.comp and fluid_finish.comp (SolverState::fluid_dispatch), whose nodes start here.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

shared uint group_sealed;
shared bool group_ambiguous;

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    uint cells = uint(n.x * n.y * n.z);
    if (gl_LocalInvocationIndex == 0u) {
        group_sealed = 0u;
        group_ambiguous = false;
    }
    barrier();
    if (uint(i) < cells) {
        uint fluid = fluid_node(uint(i), cells);
        LabelsRef(hot.labels).v[fluid] = fluid;
        uint v = hot.voxels_per_cell;
        uint flags = flags_at(i);
        uint counts[2];
        uint roots[2];
        bool cut = (flags & kCellCut) != 0u;
        for (uint k = 0u; k < kCellParts; ++k) {
            counts[k] = cut ? bits_count(part_of(i, flags, k)) : (k == 0u ? v * v * v : 0u);
            uint node = part_node(uint(i), k);
            roots[k] = counts[k] != 0u ? uf_find(node) : node;
            // Later passes read a label only to find a sealed part's region (solid_motion_of).
            if (roots[k] != kOutsideNode && roots[k] != node) atomicMin(LabelsRef(hot.labels).v[node], roots[k]);
        }
        uint add = 0u, air = 0u;
        if (counts[0] != 0u && roots[0] == kOutsideNode && counts[1] != 0u && roots[1] == kOutsideNode)
            group_ambiguous = true;
        if (counts[0] != 0u && roots[0] == kOutsideNode) {
            air = counts[0];
        } else if (counts[1] != 0u && roots[1] == kOutsideNode) {
            air = counts[1];
            add = kCellSecondPart;
        } else {
            add = kCellNoAir;
            if (counts[0] != 0u) atomicAdd(group_sealed, 1u);
        }
        FloatsRef(hot.cell_solid).v[i] = 1.0 - float(air) / float(v * v * v);
        if ((flags & kCellMoving) != 0u) {
            ivec4 m = IVec4Ref(hot.cell_motion).v[i];
            ivec3 mean = m.xyz / m.w;
            CellBits faces[6];
            load_face_masks(faces);
            CellBits solid = bits_and_not(bits_and_not(bits_all(v), part_of(i, flags, 0u)), part_of(i, flags, 1u));
            CellBits still = static_of(i, flags);
            for (uint k = 0u; k < kCellParts; ++k) {
                if (counts[k] == 0u || roots[k] == kOutsideNode) continue;
                int weight = int(region_weight(part_of(i, flags, k), solid, still, v, faces));
                if (weight == 0) continue;
                IVec4Ref region = IVec4Ref(hot.region_motion);
                atomicAdd(region.v[roots[k]].x, mean.x * weight);
                atomicAdd(region.v[roots[k]].y, mean.y * weight);
                atomicAdd(region.v[roots[k]].z, mean.z * weight);
                atomicAdd(region.v[roots[k]].w, weight);
                uint root_cell = (roots[k] - 1u) / kCellParts, root_part = (roots[k] - 1u) % kCellParts;
                atomicOr(WordsRef(hot.cell_flags).v[root_cell], kCellRegion << root_part);
            }
        }
        if (add != 0u) atomicOr(WordsRef(hot.cell_flags).v[i], add);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u && group_sealed > 0u) atomicAdd(state().s.sealed_cells, group_sealed);
    if (gl_LocalInvocationIndex == 0u && group_ambiguous) {
        uint groups = (cells + kSolverGroupSize - 1u) / kSolverGroupSize;
        state().s.fluid_dispatch = LevelDispatch(min(groups, 65535u), (groups + 65534u) / 65535u, 1u);
    }
}
