#version 460
#extension GL_GOOGLE_include_directive : require
// The outside-air fill's end, per wind cell: a part is air when its set holds node 0 (it reaches an open
// domain side), else sealed. The cell's air is its first part that is air (kCellSecondPart when that is
// part 1); a cell with none is kCellNoAir, solid for the wind. Writes the solid fraction (1 − air share),
// and adds to each sealed region the solid its parts touch (add_contacts), so that a region moves with the
// solid enclosing it (enclosing_motion): the air sealed inside a moving crate with the crate, the inside of
// a static building not at all. A cell whose two parts both reach the outside turns on solid_faces.comp's link_fluid and
// fluid_finish.comp (SolverState::fluid_dispatch), whose nodes start here.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

shared uint group_sealed;
shared bool group_ambiguous;

/// Adds what sealed part k of cell i touches to its region (root): the solid voxels in its cell and across
/// its faces, the moving ones with their cell's mean fragment velocity, weighted in quarters of all it
/// touches, and 4 to the region's border (enclosing_motion).
void add_contacts(int i, uint flags, uint k, uint root, CellBits faces[6]) {
    uint v = hot.voxels_per_cell;
    ivec3 n = hot.dims;
    ivec3 c = cell_from_index(n, i);
    CellBits part = part_of(i, flags, k);
    uvec2 touch[7];
    ivec3 mean[7];
    uint total = 0u;
    for (uint side = 0u; side < 7u; ++side) {
        touch[side] = uvec2(0u);
        mean[side] = ivec3(0);
        ivec3 at = side == 6u ? c : c + ((side & 1u) != 0u ? 1 : -1) * axis_unit(side / 2u);
        if (!inside_cells(n, at)) continue;
        int j = cell_index(n, at);
        uint fj = side == 6u ? flags : flags_at(j);
        if ((fj & kCellCut) == 0u) continue;
        touch[side] = part_contact(part, solid_of(j, fj), static_of(j, fj), side, v, faces);
        total += touch[side].x;
        if ((fj & kCellMoving) == 0u) {
            touch[side].y = touch[side].x; // a solid without moving fragments is still
        } else {
            ivec4 m = IVec4Ref(hot.cell_motion).v[j];
            mean[side] = m.xyz / m.w;
        }
    }
    if (total == 0u) return;
    ivec4 sum = ivec4(0);
    for (uint side = 0u; side < 7u; ++side) {
        int quarters = int((4u * (touch[side].x - touch[side].y) + total / 2u) / total);
        sum += ivec4(mean[side] * quarters, quarters);
    }
    IVec4Ref region = IVec4Ref(hot.region_motion);
    atomicAdd(region.v[2u * root].x, sum.x);
    atomicAdd(region.v[2u * root].y, sum.y);
    atomicAdd(region.v[2u * root].z, sum.z);
    atomicAdd(region.v[2u * root].w, sum.w);
    atomicAdd(region.v[2u * root + 1u].x, 4);
    uint root_cell = (root - 1u) / kCellParts, root_part = (root - 1u) % kCellParts;
    atomicOr(WordsRef(hot.cell_flags).v[root_cell], kCellRegion << root_part);
}

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
        // Vectors, not uint[2]: glslang gives a local array the type of a buffer's uint[2], whose ArrayStride
        // a Function variable must not carry (SPIR-V validation rejects it).
        uvec2 counts;
        uvec2 roots;
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
        FloatsRef(hot.cell_solid).v[i] = solid_fraction_of(air, v, sb().b.voxel_share);
        bool sealed[kCellParts];
        for (uint k = 0u; k < kCellParts; ++k)
            sealed[k] = counts[k] != 0u && roots[k] != kOutsideNode;
        if (sealed[0] || sealed[1]) {
            CellBits faces[6];
            load_face_masks(faces);
            for (uint k = 0u; k < kCellParts; ++k)
                if (sealed[k]) add_contacts(i, flags, k, roots[k], faces);
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
