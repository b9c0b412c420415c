#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, between the passes: sizes the large pass's indirect dispatch on the GPU, one
// workgroup per queued tile, rows of kMaxGroupsX, so the CPU never waits for the queue's length.
#include "voxelize_common.glsl"

layout(local_size_x = 1) in;

void main() {
    uint queued = Counters(pc.counters).c.large_items;
    atomicMax(Counters(pc.counters).c.large_peak, queued);
    uint items = min(queued, pc.large_capacity);
    uint rows = (items + kMaxGroupsX - 1u) / kMaxGroupsX;
    Counters(pc.counters).c.large_dispatch = DispatchArgs(min(items, kMaxGroupsX), rows, 1u);
}
