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
#include "tree_refine.glsl"

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

void main() {
    load_bindings();
    uint i = thread_index();
    if (i < state().s.fragments_dispatch.items) {
        uint node = step_down(i);
        if (node != kNoNode) visit(node);
    }
    if (last_group() && gl_LocalInvocationIndex == 0u) settle();
}
