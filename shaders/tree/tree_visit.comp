#version 460
#extension GL_GOOGLE_include_directive : require
// Per fragment, level pc.level: below the root, first steps the fragment from its node one level up to
// the child that holds its voxel; then marks that node as reached this frame (or pinned, for static
// geometry), and the fragment that marks a node without a child block first gives it one (refine). The
// workgroup that finishes last settles the pools' counters. One dispatch a level where there were four
// (visit, plan, allocation, step down), each waiting for the one before to drain: on a GPU a small frame
// costs about its count of such stages (docs/architecture.md "Sparse tree", issue 41).
#include "tree_common.glsl"

layout(local_size_x = kTreeGroupSize) in;

/// The fragment's node at pc.level (kNoNode when its path ended above, at a node a pool could not
/// refine), kept in frag_node for the passes after.
uint step_down(uint i) {
    if (pc.level == 0u) return 0u;
    WordsRef frag_node = WordsRef(tb.frag_node);
    uint parent = pc.level == 1u ? 0u : frag_node.v[i];
    uint node = kNoNode;
    if (parent != kNoNode) {
        uint block = nodes().v[parent].x;
        uint slot = child_slot(fragment_voxel(i), pc.level - 1u, tb.levels, tb.log2_branching);
        if (block != 0u) node = block * children_per_node() + slot;
    }
    frag_node.v[i] = node;
    return node;
}

/// Gives `node` its child block (at the last level its leaf mask block): the free list's top first, then
/// the bump pointer; with neither left the request counts as exhausted and the node keeps no children.
/// The free list's length and the bump pointer's bound are settled once the pass is done, so during it the
/// free list's top stays where it was and each taker counts itself instead of popping.
void refine(uint node) {
    StateRef st = state();
    bool leaf = pc.level + 1u == tb.levels;
    uint free_top = leaf ? st.s.mask_free_top : st.s.node_free_top;
    uint taken = atomicAdd(st.s.free_taken, 1u);
    uint block;
    if (taken < free_top) {
        block = WordsRef(leaf ? tb.mask_free : tb.node_free).v[free_top - 1u - taken];
    } else {
        block = leaf ? atomicAdd(st.s.mask_blocks_used, 1u) : atomicAdd(st.s.node_blocks_used, 1u);
        if (block >= (leaf ? tb.mask_capacity : tb.node_capacity)) {
            atomicAdd(st.s.exhausted, 1u);
            return;
        }
    }
    if (leaf) {
        uint stride = mask_stride(tb.log2_branching);
        for (uint w = 0u; w < stride; ++w) masks().v[block * stride + w] = 0u;
    } else {
        uint count = children_per_node();
        for (uint c = 0u; c < count; ++c) nodes().v[block * count + c] = uvec2(0u);
    }
    nodes().v[node].x = block;
    atomicAdd(st.s.refined, 1u);
    atomicAdd(st.s.blocks_per_level[pc.level], 1u);
    // Blocks made for dynamic geometry are recorded so that coarsening can find them later.
    if (pc.pinned == 0u) {
        uint slot = atomicAdd(st.s.records_next, 1u);
        if (slot < tb.list_capacity) RecordsRef(tb.records[pc.frame & 1u]).v[slot] = BlockRecord(node, pc.level);
    }
}

void visit(uint node) {
    // Every fragment visits the root and the nodes near it: a plain read first skips the atomic once
    // the mark is there (marks only grow during a pass, so a stale read only costs an atomic).
    uint mark = pc.pinned != 0u ? kPinned : pc.frame;
    if (nodes().v[node].y >= mark) return;
    uint old = atomicMax(nodes().v[node].y, mark);
    bool first = pc.pinned != 0u ? old != kPinned : old < pc.frame;
    if (first && nodes().v[node].x == 0u) refine(node);
}

/// After every refine of the pass: the free list loses what was taken from it, the bump pointer stops at
/// the pool's capacity.
void settle() {
    CoherentStateRef st = CoherentStateRef(tb.state);
    uint taken = st.s.free_taken;
    st.s.free_taken = 0u;
    if (pc.level + 1u == tb.levels) {
        st.s.mask_free_top -= min(taken, st.s.mask_free_top);
        st.s.mask_blocks_used = min(st.s.mask_blocks_used, tb.mask_capacity);
    } else {
        st.s.node_free_top -= min(taken, st.s.node_free_top);
        st.s.node_blocks_used = min(st.s.node_blocks_used, tb.node_capacity);
    }
}

void main() {
    load_bindings();
    uint i = thread_index();
    if (i < state().s.fragments_dispatch.items) {
        uint node = step_down(i);
        if (node != kNoNode) visit(node);
    }
    if (last_group() && gl_LocalInvocationIndex == 0u) settle();
}
