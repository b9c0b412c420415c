#version 460
#extension GL_GOOGLE_include_directive : require
// Frame start (one thread): last frame's lists become this frame's inputs, counters reset, and the
// indirect dispatches over those lists are sized on the GPU; with pc.size_fragments kSizeFragments also
// the insertion's per-fragment dispatches (tree_fragments.comp), for a frame that inserts only its dynamic
// fragments, and the root's visit that tree_visit's first level would make for each of them (the same
// mark and refinement however many make it), so the insertion's dispatches start at level 1.
#include "tree_common.glsl"

layout(local_size_x = 1) in;
#include "tree_refine.glsl"

void main() {
    load_bindings();
    StateRef st = state();
    st.s.records_prev = min(st.s.records_next, tb.list_capacity);
    st.s.records_next = 0u;
    st.s.leaves_prev = min(st.s.leaves_next, tb.list_capacity);
    st.s.leaves_next = 0u;
    st.s.exhausted = 0u;
    st.s.refined = 0u;
    st.s.coarsened = 0u;
    st.s.dynamic_voxels = 0u;
    st.s.records_dispatch = dispatch_for(st.s.records_prev);
    st.s.leaves_dispatch = dispatch_for(st.s.leaves_prev);
    if (pc.size_fragments != kSizeFragments) return;
    uint count = fragment_count();
    st.s.fragments_dispatch = dispatch_at_least_one(count);
    if (count > 0u) visit(0u);
    settle();
}
