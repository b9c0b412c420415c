#version 460
#extension GL_GOOGLE_include_directive : require
// Per served request: takes the planned block, clears it and links it to its owner. Blocks made for
// dynamic geometry are recorded so that coarsening can find them later.
#include "tree_common.glsl"

layout(local_size_x = kTreeGroupSize) in;

void main() {
    load_bindings();
    StateRef st = state();
    uint j = thread_index();
    if (j >= st.s.requests_dispatch.items) return;
    bool leaf = pc.level + 1u == tb.levels;
    uint take = st.s.take_free;
    uint block;
    if (j < take) {
        uint top = leaf ? st.s.mask_free_top : st.s.node_free_top;
        block = WordsRef(leaf ? tb.mask_free : tb.node_free).v[top + j];
    } else {
        block = st.s.bump_first + (j - take);
    }
    if (leaf) {
        uint stride = mask_stride(tb.log2_branching);
        for (uint w = 0u; w < stride; ++w) masks().v[block * stride + w] = 0u;
    } else {
        uint count = children_per_node();
        for (uint c = 0u; c < count; ++c) nodes().v[block * count + c] = uvec2(0u);
    }
    uint owner = WordsRef(tb.request_list).v[j];
    nodes().v[owner].x = block;
    atomicAdd(st.s.refined, 1u);
    atomicAdd(st.s.blocks_per_level[pc.level], 1u);
    if (pc.pinned == 0u) {
        uint slot = atomicAdd(st.s.records_next, 1u);
        if (slot < tb.list_capacity) RecordsRef(tb.records[pc.frame & 1u]).v[slot] = BlockRecord(owner, pc.level);
    }
}
