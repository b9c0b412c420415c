// Layouts shared by the sparse-tree shaders and voxelizer/src/sparse_tree.cpp (docs/architecture.md
// "Sparse tree").
//
// Nodes live in blocks of b^3 (all children of one parent). A node is (child, touched): `child` is the
// index of its child block (internal levels) or of its leaf mask block (last level), 0 when none;
// `touched` is the last frame a fragment reached it, kPinned for nodes on static geometry. Block 0
// holds the root (node 0). Leaf mask blocks hold the static words, then the dynamic words, then the
// frame in which the leaf was last listed for clearing.
#ifndef GUST_TREE_IO_H
#define GUST_TREE_IO_H

#include "../common.h"

GUST_NAMESPACE_BEGIN

GUST_CONST uint kTreeGroupSize = 64;
/// `touched` of nodes on static geometry: never coarsened.
GUST_CONST uint kPinned = 0xffffffffu;
/// frag_node value of a fragment whose path ended at a node the pool could not refine.
GUST_CONST uint kNoNode = 0xffffffffu;
/// Deepest tree (b = 2 at res 1024).
GUST_CONST uint kMaxLevels = 10;

/// Indirect dispatch arguments (VkDispatchIndirectCommand) plus the item count they cover.
struct TreeDispatch {
    uint x, y, z;
    uint items;
};

/// One block handed out or taken back, kept for coarsening: which node owns it, at which level.
struct BlockRecord {
    uint owner;
    uint level; ///< level of the owner (the last level owns mask blocks)
};

/// Counters and allocator state, one buffer for the whole tree.
struct TreeState {
    uint node_blocks_used;             ///< bump pointer of the node-block pool (block 0 is the root's)
    uint node_free_top;                ///< entries on the node-block free list
    uint mask_blocks_used;             ///< bump pointer of the mask-block pool (block 0 unused)
    uint mask_free_top;                ///< entries on the mask-block free list
    uint free_taken;                   ///< blocks the current tree_visit took (first from the free list)
    uint exhausted;                    ///< refinements the pool could not serve this frame
    uint refined;                      ///< blocks handed out this frame
    uint coarsened;                    ///< blocks taken back this frame
    uint records_prev;                 ///< entries in last frame's coarsening list
    uint records_next;                 ///< entries in this frame's coarsening list
    uint leaves_prev;                  ///< leaves whose dynamic words last frame set
    uint leaves_next;                  ///< leaves whose dynamic words this frame set
    uint static_voxels;                ///< voxels set in static words (since the last rebuild)
    uint dynamic_voxels;               ///< voxels set in dynamic words this frame and not in static ones
    uint groups_done;                  ///< workgroups of the current tree_visit done (its last one settles)
    uint blocks_per_level[kMaxLevels]; ///< live blocks whose owner is at each level
    TreeDispatch fragments_dispatch;   ///< over this frame's fragments
    TreeDispatch records_dispatch;     ///< over the previous frame's coarsening list
    TreeDispatch leaves_dispatch;      ///< over the previous frame's leaf list
};

/// Workgroups for `items` threads of kTreeGroupSize, in rows of at most 65,535 workgroups.
GUST_INLINE TreeDispatch dispatch_for(uint items) {
    uint groups = (items + kTreeGroupSize - 1u) / kTreeGroupSize;
    TreeDispatch d;
    d.x = min(groups, 65535u);
    d.y = (groups + 65534u) / 65535u;
    d.z = 1u;
    d.items = items;
    return d;
}

/// dispatch_for, but at least one workgroup: a pass whose last workgroup finishes the work of the pass
/// (tree_visit settles the pools) runs even over no items.
GUST_INLINE TreeDispatch dispatch_at_least_one(uint items) {
    TreeDispatch d = dispatch_for(items);
    d.x = max(d.x, 1u);
    d.y = max(d.y, 1u);
    return d;
}

/// Addresses and sizes of the tree's buffers, in a small buffer of its own (push constants are kept
/// to the guaranteed 128 bytes). The record and leaf lists alternate between frames: index
/// frame & 1 is written this frame, the other was written last frame.
struct TreeBindings {
    GUST_ADDRESS state;          ///< TreeState
    GUST_ADDRESS nodes;          ///< uvec2[node_capacity * b^3]
    GUST_ADDRESS masks;          ///< uint[mask_capacity * mask_stride]
    GUST_ADDRESS node_free;      ///< uint[node_capacity]
    GUST_ADDRESS mask_free;      ///< uint[mask_capacity]
    GUST_ADDRESS fragments;      ///< uint keys from the voxelizer
    GUST_ADDRESS fragment_count; ///< uint: the voxelizer's counter (clamped to fragment_capacity)
    GUST_ADDRESS frag_node;      ///< uint[fragment_capacity]: each fragment's node at the current level
    GUST_ADDRESS records[2];     ///< BlockRecord[list_capacity]: coarsening lists
    GUST_ADDRESS leaves[2];      ///< uint[list_capacity]: leaves whose dynamic words a frame set
    uint fragment_capacity;
    uint node_capacity;  ///< node blocks
    uint mask_capacity;  ///< mask blocks
    uint list_capacity;  ///< entries of each record and leaf list
    uint log2_branching; ///< 1, 2 or 3
    uint levels;         ///< tree depth: res = b^levels
    uint hysteresis;     ///< K: a block whose owner went more than K frames unreached is coarsened
    uint key_shift;      ///< fragment keys are at res << key_shift: each coordinate is shifted right by it
};

/// Push constants of every tree pass.
struct TreePush {
    GUST_ADDRESS bindings; ///< TreeBindings
    uint frame;            ///< current frame number (>= 1)
    uint level;            ///< level the pass works on (0 = root)
    uint pinned;           ///< 1 while inserting static fragments
    uint size_fragments;   ///< tree_begin: kSizeFragments when it also sizes the insertion's dispatches
};

/// TreePush::size_fragments of tree_begin: it also does tree_fragments' work for the bindings it gets and
/// visits their root, so that the insertion's next level runs beside the clearing (two stages fewer a frame).
GUST_CONST uint kSizeFragments = 1u;

/// Words of one leaf layer (static or dynamic) for branching factor 2^log2_branching.
GUST_INLINE uint mask_words(uint log2_branching) {
    return max(1u, (1u << (3u * log2_branching)) / 32u);
}
/// Words per mask block: static, dynamic, and the frame the leaf was last listed.
GUST_INLINE uint mask_stride(uint log2_branching) {
    return 2u * mask_words(log2_branching) + 1u;
}

/// Child slot of voxel `v` inside a node of level `level` (children at level + 1).
GUST_INLINE uint child_slot(uvec3 v, uint level, uint levels, uint log2_branching) {
    uint shift = (levels - 1u - level) * log2_branching;
    uint mask = (1u << log2_branching) - 1u;
    uvec3 c = (v >> shift) & mask;
    return c.x | (c.y << log2_branching) | (c.z << (2u * log2_branching));
}

/// Inverse of child_slot: the child's position inside its parent, in children per axis (each in
/// [0, 2^log2_branching)). Also a voxel's position inside its leaf brick from its mask bit.
GUST_INLINE uvec3 slot_offset(uint slot, uint log2_branching) {
    uint mask = (1u << log2_branching) - 1u;
    return uvec3(slot & mask, (slot >> log2_branching) & mask, slot >> (2u * log2_branching));
}

GUST_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(gust::shaderio::TreePush) == 24, "push constants must match the GLSL layout");
static_assert(sizeof(gust::shaderio::TreeBindings) == 12 * 8 + 8 * 4);
static_assert(sizeof(gust::shaderio::TreeState) == (15 + 10 + 12) * 4);
#endif

#endif
