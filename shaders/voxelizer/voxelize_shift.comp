#version 460
#extension GL_GOOGLE_include_directive : require
// Slab pass, first dispatch: moves the last pass's fragment list into the scrolled grid. Each key, less
// the scroll, is appended to the new list unless it fell out of the grid's kept extent; the voxelize
// passes then append the uncovered slabs behind it through the same counter.

#include "voxelize_io.h"

layout(local_size_x = kShiftGroupSize) in;

layout(buffer_reference, scalar) readonly buffer Keys { uint v[]; };
layout(buffer_reference, scalar) writeonly buffer Out { uint v[]; };
layout(buffer_reference, scalar) readonly buffer Count { uint v; };
layout(buffer_reference, scalar) buffer Counters { VoxelizeCounters c; };

layout(push_constant, scalar) uniform Push { ShiftPush pc; };

void main() {
    uint counted = Count(pc.source_count).v;
    // A last pass cut short leaves this list short too: count past the capacity, so the host redoes it.
    if (gl_GlobalInvocationID.x == 0u && counted > pc.source_capacity)
        atomicAdd(Counters(pc.counters).c.fragments, min(pc.capacity, 0xfffffffeu) + 1u);
    // The host cannot know the count of a recorded pass, so the workgroups stride over whatever it is:
    // each takes blocks of kShiftPerThread entries a thread, read side by side across the workgroup.
    uint total = min(counted, pc.source_capacity);
    const uint block = kShiftGroupSize * kShiftPerThread;
    for (uint first = gl_WorkGroupID.x * block; first < total; first += gl_NumWorkGroups.x * block) {
        uint keys[kShiftPerThread];
        uint kept = 0u;
        for (uint i = 0u; i < kShiftPerThread; ++i) {
            uint index = first + i * kShiftGroupSize + gl_LocalInvocationID.x;
            if (index >= total) break;
            uint old = Keys(pc.source).v[index];
            ivec3 v = ivec3(old & 1023u, (old >> 10) & 1023u, old >> 20) - pc.shift;
            if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, ivec3(pc.keep)))) continue;
            keys[kept++] = uint(v.x) | (uint(v.y) << 10) | (uint(v.z) << 20);
        }
        if (kept == 0u) continue;
        // One atomic a thread and block, as the voxelize passes batch theirs.
        uint slot = atomicAdd(Counters(pc.counters).c.fragments, kept);
        for (uint i = 0u; i < kept && slot + i < pc.capacity; ++i) Out(pc.fragments).v[slot + i] = keys[i];
    }
}
