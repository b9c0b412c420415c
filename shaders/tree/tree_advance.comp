#version 460
#extension GL_GOOGLE_include_directive : require
// Per fragment: steps from its node at pc.level to the child at pc.level + 1 that contains its voxel.
#include "tree_common.glsl"

layout(local_size_x = kTreeGroupSize) in;

void main() {
    load_bindings();
    uint i = thread_index();
    if (i >= state().s.fragments_dispatch.items) return;
    WordsRef frag_node = WordsRef(tb.frag_node);
    uint node = pc.level == 0u ? 0u : frag_node.v[i];
    if (node == kNoNode) {
        frag_node.v[i] = kNoNode;
        return;
    }
    uint block = nodes().v[node].x;
    uint slot = child_slot(fragment_voxel(i), pc.level, tb.levels, tb.log2_branching);
    frag_node.v[i] = block == 0u ? kNoNode : block * children_per_node() + slot;
}
