#version 460
#extension GL_GOOGLE_include_directive : require
// Per wind cell: gathers the cell's voxels from the sparse tree's leaves and splits its free voxels into
// parts (cell_parts in solver_cells.h); starts the outside-air fill (each part its own union-find set) and
// clears what the last step summed here. Only cells whose voxels may have changed are gathered again: with
// pc.mode kSolidChanged (the static solids as at the last step) a cell that held no moving voxels then and
// whose leaf bricks hold none now keeps its parts and static voxels; kSolidAll redoes every cell. Thread 0
// also sizes the moving-fragment pass. Every cell also makes its vorticity-confinement force for advection.
#include "../tree/tree_io.h"
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

// The tree's bindings, loaded once per invocation (as load_bindings does for the others).
uint64_t tree_nodes, tree_masks;
uint tree_levels, tree_log2, leaf_words, leaf_stride;
ivec3 voxel_offset;
void load_tree_bindings() {
    tree_nodes = sb().b.tree_nodes;
    tree_masks = sb().b.tree_masks;
    tree_levels = sb().b.tree_levels;
    tree_log2 = sb().b.tree_log2_branching;
    leaf_words = sb().b.mask_words;
    leaf_stride = sb().b.mask_stride;
    voxel_offset = sb().b.voxel_offset;
}

uint b_log2() { return tree_log2; }

/// Node of `level` holding tree voxel v, or kNone when the path stops earlier.
const uint kNone = 0xffffffffu;
uint node_at(ivec3 v, uint level) {
    uint levels = tree_levels;
    uint children = 1u << (3u * b_log2());
    uint node = 0u;
    for (uint l = 0u; l < level; ++l) {
        uint block = NodesRef(tree_nodes).v[node].x;
        if (block == 0u) return kNone;
        node = block * children + child_slot(uvec3(v), l, levels, b_log2());
    }
    return node;
}

bool in_tree(ivec3 v) {
    int res = 1 << int(tree_levels * b_log2());
    return all(greaterThanEqual(v, ivec3(0))) && all(lessThan(v, ivec3(res)));
}

/// Whether a leaf brick holding any of voxels lo .. lo + v - 1 has a voxel of a moving surface this step
/// (anywhere in the brick: a cell redone for nothing costs only time).
bool bricks_dynamic(ivec3 lo, uint v) {
    int shift = int(b_log2());
    ivec3 first = lo >> shift, last = (lo + int(v - 1u)) >> shift;
    for (int z = first.z; z <= last.z; ++z)
        for (int y = first.y; y <= last.y; ++y)
            for (int x = first.x; x <= last.x; ++x) {
                ivec3 corner = ivec3(x, y, z) << shift;
                if (!in_tree(corner)) continue;
                uint node = node_at(corner, tree_levels - 1u);
                uint block = node == kNone ? 0u : NodesRef(tree_nodes).v[node].x;
                if (block == 0u) continue;
                for (uint w = 0u; w < leaf_words; ++w)
                    if (WordsRef(tree_masks).v[block * leaf_stride + leaf_words + w] != 0u) return true;
            }
    return false;
}

void main() {
    load_bindings();
    load_tree_bindings();
    int i = thread_index();
    ivec3 n = hot.dims;
    if (i >= n.x * n.y * n.z) return;
    ivec3 c = cell_from_index(n, i);
    // Each cell's confinement force and speed for this step's advect.comp (cell_confinement), here where
    // every cell is visited before it, so that advection reads two values a face instead of 26.
    float epsilon = sb().b.vorticity_strength;
    if (epsilon != 0.0) Vec4Ref(hot.confinement).v[i] = cell_confinement(c, epsilon);
    uint v = hot.voxels_per_cell;
    uint levels = tree_levels;
    WordsRef flags = WordsRef(hot.cell_flags);
    // The last step's moving fragments and region sums kept here (kCellMoving, kCellRegion): clear them,
    // so only the cells that held some are written, not the whole arrays.
    uint old = flags.v[i];
    if ((old & kCellMoving) != 0u) IVec4Ref(hot.cell_motion).v[i] = ivec4(0);
    LabelsRef labels = LabelsRef(hot.labels);
    for (uint k = 0u; k < kCellParts; ++k) {
        uint node = part_node(uint(i), k);
        if ((old & (kCellRegion << k)) != 0u) {
            IVec4Ref(hot.region_motion).v[2u * node] = ivec4(0);
            IVec4Ref(hot.region_motion).v[2u * node + 1u] = ivec4(0);
        }
        labels.v[node] = node;
    }
    if (i == 0) {
        labels.v[kOutsideNode] = kOutsideNode;
        // Sizes solid_motion's dispatch from the voxelizer's fragment count (read by one thread).
        uint count = sb().b.fragments == 0ul ? 0u : min(WordsRef(sb().b.fragment_count).v[0], sb().b.fragment_capacity);
        uint groups = (count + kSolverGroupSize - 1u) / kSolverGroupSize;
        state().s.fragments_dispatch = LevelDispatch(min(groups, 65535u), (groups + 65534u) / 65535u, 1u);
        state().s.fragments = count;
    }
    flags.v[i] = 0u;
    if (levels == 0u) return;
    ivec3 lo = voxel_offset + c * int(v);
    // Cheap exit: the shallowest level whose nodes are at least a cell wide; the cell lies in at most
    // two such nodes along each axis (one where its first and last voxels share a node), and when none
    // exists the cell is empty. Only the corners in distinct nodes are looked up.
    uint coarse = levels - 1u;
    while (coarse > 0u && (1u << ((levels - coarse) * b_log2())) < v) --coarse;
    int node_shift = int((levels - coarse) * b_log2());
    ivec3 hi = lo + int(v - 1u);
    ivec3 spans = ivec3(notEqual(lo >> node_shift, hi >> node_shift));
    bool any_node = false;
    for (int k = 0; k < 8 && !any_node; ++k) {
        ivec3 side = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        if (any(greaterThan(side, spans))) continue;
        ivec3 corner = lo + side * int(v - 1u);
        uint node = in_tree(corner) ? node_at(corner, coarse) : kNone;
        any_node = node != kNone && NodesRef(tree_nodes).v[node].x != 0u;
    }
    if (!any_node) return;
    if (pc.mode == kSolidChanged && (old & kCellDynamic) == 0u && !bricks_dynamic(lo, v)) {
        // Nothing here changed since the last step: its parts and static voxels stay as that step left them.
        if ((old & kCellCut) != 0u) {
            uint kept = old & (kCellCut | kCellStatic);
            if ((old & kCellNoAir) == 0u)
                for (uint k = 0u; k < kCellParts; ++k)
                    if (part_crossed(part_of(i, old, k), air_of(i, old))) kept |= kCellCrossed << k;
            flags.v[i] = kept;
            atomicAdd(state().s.cut_cells, 1u);
        }
        return;
    }

    CellBits occupied = bits_none(), held = bits_none();
    bool dynamic = false;
    ivec3 cached_brick = ivec3(-1);
    uint block = 0u;
    for (uint z = 0u; z < v; ++z)
        for (uint y = 0u; y < v; ++y)
            for (uint x = 0u; x < v; ++x) {
                ivec3 voxel = lo + ivec3(x, y, z);
                if (!in_tree(voxel)) continue;
                ivec3 brick = voxel >> int(b_log2());
                if (brick != cached_brick) {
                    cached_brick = brick;
                    uint node = node_at(voxel, levels - 1u);
                    block = node == kNone ? 0u : NodesRef(tree_nodes).v[node].x;
                }
                if (block == 0u) continue;
                uint bit = child_slot(uvec3(voxel), levels - 1u, levels, b_log2());
                uint base = block * leaf_stride + bit / 32u;
                uint static_word = WordsRef(tree_masks).v[base];
                uint dynamic_word = WordsRef(tree_masks).v[base + leaf_words];
                uint word = static_word | dynamic_word;
                uint j = x + v * (y + v * z);
                if ((dynamic_word >> (bit % 32u) & 1u) != 0u) dynamic = true;
                if ((word >> (bit % 32u) & 1u) != 0u) occupied.w[j / 32u] |= 1u << (j % 32u);
                if ((static_word >> (bit % 32u) & 1u) != 0u) held.w[j / 32u] |= 1u << (j % 32u);
            }
    if (bits_count(occupied) == 0u) return;
    CellBits faces[6];
    load_face_masks(faces);
    CellBits parts[2];
    cell_parts(occupied, v, faces, parts[0], parts[1]);
    uint cut = dynamic ? kCellCut | kCellDynamic : kCellCut;
    // Against the last step's air, before its parts are overwritten (a cell without air then has none to
    // cross from).
    if ((old & kCellNoAir) == 0u) {
        CellBits before = air_of(i, old);
        for (uint k = 0u; k < kCellParts; ++k)
            if (part_crossed(parts[k], before)) cut |= kCellCrossed << k;
    }
    uint cw = hot.cell_words;
    for (uint k = 0u; k < kCellParts; ++k)
        for (uint w = 0u; w < cw; ++w) WordsRef(hot.cell_parts).v[(kCellParts * uint(i) + k) * cw + w] = parts[k].w[w];
    if (bits_count(held) != 0u) {
        for (uint w = 0u; w < cw; ++w) WordsRef(hot.cell_static).v[uint(i) * cw + w] = held.w[w];
        cut |= kCellStatic;
    }
    flags.v[i] = cut;
    atomicAdd(state().s.cut_cells, 1u);
}
