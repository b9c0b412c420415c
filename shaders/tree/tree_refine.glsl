// A node's visit at level pc.level (its mark, and its child block for the first to reach it without one)
// and the pools' settling after a pass of them: tree_visit.comp per fragment, tree_begin.comp for the root
// of an insertion it sized.

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
