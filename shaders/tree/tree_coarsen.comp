#version 460
#extension GL_GOOGLE_include_directive : require
// Per block recorded last frame: when its owner went more than K frames unreached, the block goes
// back to its free list and the owner loses it; otherwise it stays recorded. Reaching a node marks
// its whole path, so a stale owner's descendants are stale too and are freed by their own records.
#include "tree_common.glsl"

layout(local_size_x = kTreeGroupSize) in;

void main() {
    load_bindings();
    StateRef st = state();
    uint i = thread_index();
    if (i >= st.s.records_prev) return;
    BlockRecord r = RecordsRef(tb.records[(pc.frame + 1u) & 1u]).v[i];
    uvec2 owner = nodes().v[r.owner];
    bool stale = owner.y != kPinned && pc.frame - owner.y > tb.hysteresis;
    if (!stale) {
        uint slot = atomicAdd(st.s.records_next, 1u);
        if (slot < tb.list_capacity) RecordsRef(tb.records[pc.frame & 1u]).v[slot] = r;
        return;
    }
    if (owner.x == 0u) return;
    nodes().v[r.owner].x = 0u;
    if (r.level + 1u == tb.levels) {
        uint top = atomicAdd(st.s.mask_free_top, 1u);
        WordsRef(tb.mask_free).v[top] = owner.x;
    } else {
        uint top = atomicAdd(st.s.node_free_top, 1u);
        WordsRef(tb.node_free).v[top] = owner.x;
    }
    atomicAdd(st.s.coarsened, 1u);
    atomicAdd(st.s.blocks_per_level[r.level], uint(-1));
}
