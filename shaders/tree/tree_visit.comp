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
