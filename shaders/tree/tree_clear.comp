#version 460
#extension GL_GOOGLE_include_directive : require
// Clears the dynamic occupancy of the leaves last frame's dynamic fragments set, so cost follows the
// dynamic geometry instead of the whole tree.
#include "tree_common.glsl"

layout(local_size_x = kTreeGroupSize) in;

void main() {
    load_bindings();
    uint i = thread_index();
    if (i >= state().s.leaves_prev) return;
    uint leaf = WordsRef(tb.leaves[(pc.frame + 1u) & 1u]).v[i];
    uint block = nodes().v[leaf].x;
    if (block == 0u) return;
    uint words = mask_words(tb.log2_branching);
    uint base = block * mask_stride(tb.log2_branching) + words;
    for (uint w = 0u; w < words; ++w) masks().v[base + w] = 0u;
}
