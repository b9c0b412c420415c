#version 460
#extension GL_GOOGLE_include_directive : require
// Slab pass, first dispatch: moves the last pass's fragment list into the scrolled grid. One thread per
// kept fragment subtracts the scroll from its key and appends it to the new list, unless it fell out of
// the grid; the voxelize passes then append the uncovered slabs behind it through the same counter.

#include "voxelize_io.h"

layout(local_size_x = kShiftGroupSize) in;

layout(buffer_reference, scalar) readonly buffer Keys { uint v[]; };
layout(buffer_reference, scalar) writeonly buffer Out { uint v[]; };
layout(buffer_reference, scalar) readonly buffer Count { uint v; };
layout(buffer_reference, scalar) buffer Counters { VoxelizeCounters c; };

layout(push_constant, scalar) uniform Push { ShiftPush pc; };

shared uint group_count;
shared uint group_slot;

void main() {
    uint counted = Count(pc.source_count).v;
    uint index = (gl_WorkGroupID.y * kMaxGroupsX + gl_WorkGroupID.x) * kShiftGroupSize + gl_LocalInvocationID.x;
    // A last pass cut short leaves this list short too: count past the capacity, so the host redoes it.
    if (index == 0u && counted > pc.source_capacity)
        atomicAdd(Counters(pc.counters).c.fragments, min(pc.capacity, 0xfffffffeu) + 1u);
    if (gl_LocalInvocationID.x == 0u) group_count = 0u;
    barrier();
    bool kept = false;
    uint key = 0u;
    uint local = 0u;
    if (index < min(counted, pc.source_capacity)) {
        uint old = Keys(pc.source).v[index];
        ivec3 v = ivec3(old & 1023u, (old >> 10) & 1023u, old >> 20) - pc.shift;
        kept = all(greaterThanEqual(v, ivec3(0))) && all(lessThan(v, ivec3(pc.keep)));
        key = uint(v.x) | (uint(v.y) << 10) | (uint(v.z) << 20);
        if (kept) local = atomicAdd(group_count, 1u);
    }
    barrier();
    // One atomic on the list's counter per workgroup.
    if (gl_LocalInvocationID.x == 0u && group_count > 0u)
        group_slot = atomicAdd(Counters(pc.counters).c.fragments, group_count);
    barrier();
    if (!kept) return;
    uint slot = group_slot + local;
    if (slot < pc.capacity) Out(pc.fragments).v[slot] = key;
}
