#version 460
#extension GL_GOOGLE_include_directive : require
// One thread: decides where this level's requests get their blocks (free list first, then the bump
// pointer, then nothing: counted as exhausted), so the allocation pass needs no contended pops.
#include "tree_common.glsl"

layout(local_size_x = 1) in;

void main() {
    load_bindings();
    StateRef st = state();
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
