#version 460
#extension GL_GOOGLE_include_directive : require
// Per fragment, level pc.level: below the root, first steps the fragment from its node one level up to
// the child that holds its voxel; then marks that node as reached this frame (or pinned, for static
// geometry) and queues nodes without a child block for allocation, once each. The workgroup that finishes
// last then plans the level's allocation in one thread, so the allocation pass needs no contended pops.
// One dispatch a level where there were three (visit, plan, and the step down after the allocation):
// each waits for the one before to drain, and on a GPU a small frame costs its count of such stages
// (docs/architecture.md "Sparse tree", issue 41).
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

void visit(uint node) {
    // Every fragment visits the root and the nodes near it: a plain read first skips the atomic once
    // the mark is there (marks only grow during a pass, so a stale read only costs an atomic).
    uint mark = pc.pinned != 0u ? kPinned : pc.frame;
    if (nodes().v[node].y >= mark) return;
    uint old = atomicMax(nodes().v[node].y, mark);
    bool first = pc.pinned != 0u ? old != kPinned : old < pc.frame;
    if (!first || nodes().v[node].x != 0u) return;
    uint slot = atomicAdd(state().s.requests, 1u);
    if (slot < tb.fragment_capacity) WordsRef(tb.request_list).v[slot] = node;
}

/// Where this level's requests get their blocks: the free list first, then the bump pointer, then nothing
/// (counted as exhausted); sizes the allocation pass.
void plan() {
    CoherentStateRef st = CoherentStateRef(tb.state);
    uint n = min(st.s.requests, tb.fragment_capacity);
    st.s.requests = 0u;
    bool leaf = pc.level + 1u == tb.levels;
    uint free_top = leaf ? st.s.mask_free_top : st.s.node_free_top;
    uint used = leaf ? st.s.mask_blocks_used : st.s.node_blocks_used;
    uint capacity = leaf ? tb.mask_capacity : tb.node_capacity;
    uint take = min(n, free_top);
    uint bumped = min(n - take, capacity - used);
    if (leaf) {
        st.s.mask_free_top = free_top - take;
        st.s.mask_blocks_used = used + bumped;
    } else {
        st.s.node_free_top = free_top - take;
        st.s.node_blocks_used = used + bumped;
    }
    st.s.take_free = take;
    st.s.bump_first = used;
    st.s.exhausted += n - take - bumped;
    st.s.requests_dispatch = dispatch_for(take + bumped);
}

void main() {
    load_bindings();
    uint i = thread_index();
    if (i < state().s.fragments_dispatch.items) {
        uint node = step_down(i);
        if (node != kNoNode) visit(node);
    }
    if (last_group() && gl_LocalInvocationIndex == 0u) plan();
}
