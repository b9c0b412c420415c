#version 460
#extension GL_GOOGLE_include_directive : require
// Frame start (one thread): last frame's lists become this frame's inputs, counters reset, and the
// indirect dispatches over those lists are sized on the GPU.
#include "tree_common.glsl"

layout(local_size_x = 1) in;

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
}
