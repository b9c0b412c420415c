#version 460
#extension GL_GOOGLE_include_directive : require
// Per fragment at the last level: sets its voxel's bit in the leaf's static or dynamic words, and
// lists each leaf with dynamic bits once per frame so the next frame can clear them.
#include "tree_common.glsl"

layout(local_size_x = kTreeGroupSize) in;

void main() {
    load_bindings();
    uint i = thread_index();
    if (i >= state().s.fragments_dispatch.items) return;
    uint node = tb.levels == 1u ? 0u : WordsRef(tb.frag_node).v[i];
    if (node == kNoNode) return;
    uint block = nodes().v[node].x;
    if (block == 0u) return;
    uint bit = child_slot(fragment_voxel(i), tb.levels - 1u, tb.levels, tb.log2_branching);
    uint words = mask_words(tb.log2_branching);
    uint base = block * mask_stride(tb.log2_branching);
    uint layer = pc.pinned != 0u ? 0u : words;
    uint flag = 1u << (bit % 32u);
    // Many fragments share a voxel: a plain read first skips the atomic once the bit is set (bits and
    // the frame stamp only grow during a pass, so a stale read only costs an atomic).
    uint word = base + layer + bit / 32u;
    bool newly = (masks().v[word] & flag) == 0u && (atomicOr(masks().v[word], flag) & flag) == 0u;
    if (pc.pinned != 0u) {
        if (newly) atomicAdd(state().s.static_voxels, 1u);
        return;
    }
    if (newly && (masks().v[base + bit / 32u] & flag) == 0u) atomicAdd(state().s.dynamic_voxels, 1u);
    if (masks().v[base + 2u * words] == pc.frame) return;
    if (atomicExchange(masks().v[base + 2u * words], pc.frame) == pc.frame) return;
    uint slot = atomicAdd(state().s.leaves_next, 1u);
    if (slot < tb.list_capacity) WordsRef(tb.leaves[pc.frame & 1u]).v[slot] = node;
}
