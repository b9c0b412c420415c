#version 460
#extension GL_GOOGLE_include_directive : require
// Per fragment, level pc.level: marks the fragment's node as reached this frame (or pinned, for
// static geometry) and queues nodes without a child block for allocation, once each.
#include "tree_common.glsl"

layout(local_size_x = kTreeGroupSize) in;

void main() {
    load_bindings();
    uint i = thread_index();
    if (i >= state().s.fragments_dispatch.items) return;
    uint node = pc.level == 0u ? 0u : WordsRef(tb.frag_node).v[i];
    if (node == kNoNode) return;
    uint old = atomicMax(nodes().v[node].y, pc.pinned != 0u ? kPinned : pc.frame);
    bool first = pc.pinned != 0u ? old != kPinned : old < pc.frame;
    if (!first || nodes().v[node].x != 0u) return;
    uint slot = atomicAdd(state().s.requests, 1u);
    if (slot < tb.fragment_capacity) WordsRef(tb.request_list).v[slot] = node;
}
