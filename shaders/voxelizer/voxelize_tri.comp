#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, pass 1: one thread per triangle walks its projected footprint column by column
// (Schwarz & Seidel 2010). Triangles with large footprints are queued tile by tile for
// voxelize_large.comp instead. Every compute instance of a call runs this pass back to back, into one
// queue; the workgroup that finishes last of all of them sizes the large pass's indirect dispatch on the
// GPU, so the CPU never waits for the queue's length and no pass of its own stands between the two.
#include "voxelize_common.glsl"

layout(local_size_x = kVoxelizeGroupSize) in;

void voxelize_triangle(uint t) {
    vec3 g0 = load_grid_vertex(t, 0u), g1 = load_grid_vertex(t, 1u), g2 = load_grid_vertex(t, 2u);
    if (!is_finite(g0) || !is_finite(g1) || !is_finite(g2)) {
        atomicAdd(Counters(pc.counters).c.rejected, 1u);
        return;
    }
    Setup s;
    if (!setup_triangle(g0, g1, g2, s)) return;
    ivec2 extent = s.col_hi - s.col_lo + 1;
    uint columns = uint(extent.x) * uint(extent.y);
    if (columns > kLargeTriangleColumns) {
        uint tiles = (columns + kTileColumns - 1u) / kTileColumns;
        uint slot = atomicAdd(Counters(pc.counters).c.large_items, tiles);
        if (slot > 0xffffffffu - tiles) atomicOr(Counters(pc.counters).c.wrapped, 1u);
        LargeList list = LargeList(pc.large_list);
        for (uint i = 0u; i < tiles && slot + i < pc.large_capacity; ++i) {
            list.v[3 * (slot + i)] = pc.instance_index;
            list.v[3 * (slot + i) + 1] = t;
            list.v[3 * (slot + i) + 2] = i;
        }
        return;
    }
    setup_velocities(t, s);
    for (int y = s.col_lo.y; y <= s.col_hi.y; ++y)
        for (int x = s.col_lo.x; x <= s.col_hi.x; ++x) voxelize_column(s, x, y);
    flush_voxels();
}

shared bool group_is_last;
/// Called by every thread: true in every thread of the workgroup that finished last among all the call's
/// dispatches of this pass (pc.groups_total); the others' queued items are then counted.
bool last_group() {
    memoryBarrierBuffer();
    barrier();
    if (gl_LocalInvocationIndex == 0u)
        group_is_last = atomicAdd(Counters(pc.counters).c.groups_done, 1u) + 1u == pc.groups_total;
    barrier();
    memoryBarrierBuffer();
    return group_is_last;
}

void main() {
    if (gl_GlobalInvocationID.x < pc.triangle_count) voxelize_triangle(pc.first_triangle + gl_GlobalInvocationID.x);
    if (!last_group() || gl_LocalInvocationIndex != 0u) return;
    // One workgroup per queued tile, in rows of kMaxGroupsX (an atomic read sees every group's items).
    uint items = min(atomicAdd(Counters(pc.counters).c.large_items, 0u), pc.large_capacity);
    uint rows = (items + kMaxGroupsX - 1u) / kMaxGroupsX;
    Counters(pc.counters).c.large_dispatch = DispatchArgs(min(items, kMaxGroupsX), rows, 1u);
}
