// Buffers and helpers shared by the tree passes.
#include "tree_io.h"

layout(buffer_reference, scalar) buffer StateRef { TreeState s; };
layout(buffer_reference, scalar) readonly buffer BindingsRef { TreeBindings b; };
layout(buffer_reference, scalar) buffer NodesRef { uvec2 v[]; };
layout(buffer_reference, scalar) buffer WordsRef { uint v[]; };
layout(buffer_reference, scalar) buffer RecordsRef { BlockRecord v[]; };

layout(push_constant, scalar) uniform Push { TreePush pc; };

TreeBindings tb;

/// Loads the bindings; every pass calls it first.
void load_bindings() { tb = BindingsRef(pc.bindings).b; }

StateRef state() { return StateRef(tb.state); }
NodesRef nodes() { return NodesRef(tb.nodes); }
WordsRef masks() { return WordsRef(tb.masks); }

uint children_per_node() { return 1u << (3u * tb.log2_branching); }

/// Linear thread index over a 2D grid of workgroups made by dispatch_for().
uint thread_index() {
    return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kTreeGroupSize + gl_LocalInvocationID.x;
}

uvec3 fragment_voxel(uint i) {
    uint key = WordsRef(tb.fragments).v[i];
    return uvec3(key & 1023u, (key >> 10) & 1023u, (key >> 20) & 1023u) >> tb.key_shift;
}

uint fragment_count() { return min(WordsRef(tb.fragment_count).v[0], tb.fragment_capacity); }

// The "last workgroup" pattern (as the solver's reductions, solver_common.glsl): every group counts itself
// done with an atomic after a memory barrier, and the group that counts last sees the others' atomics and
// writes, read through a coherent reference.
layout(buffer_reference, scalar) coherent buffer CoherentStateRef { TreeState s; };

uint group_total() { return gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z; }

shared bool group_is_last;
/// Called by every thread of the dispatch: true in every thread of the group that finished last.
bool last_group() {
    memoryBarrierBuffer();
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        uint seen = atomicAdd(state().s.groups_done, 1u);
        group_is_last = seen + 1u == group_total();
        if (group_is_last) state().s.groups_done = 0u;
    }
    barrier();
    memoryBarrierBuffer();
    return group_is_last;
}
