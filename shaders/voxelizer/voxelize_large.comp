#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, pass 2: a workgroup per (instance, triangle, tile) item of every compute instance of the
// call, its threads striding over the tile's columns, so a triangle spanning the grid is spread over many
// workgroups. pc.instance is the start of the call's instances.
#include "voxelize_common.glsl"

layout(local_size_x = kVoxelizeGroupSize) in;

void main() {
    uint item = gl_WorkGroupID.y * kMaxGroupsX + gl_WorkGroupID.x;
    if (item >= min(Counters(pc.counters).c.large_items, pc.large_capacity)) return;
    LargeList list = LargeList(pc.large_list);
    const uvec3 queued = uvec3(list.v[3 * item], list.v[3 * item + 1], list.v[3 * item + 2]);
    item_instance = pc.instance + uint64_t(queued.x) * uint64_t(kVoxelizeInstanceBytes);
    uint t = queued.y;
    Setup s;
    setup_triangle(load_grid_vertex(t, 0u), load_grid_vertex(t, 1u), load_grid_vertex(t, 2u), s);
    setup_velocities(t, s);
    ivec2 extent = s.col_hi - s.col_lo + 1;
    uint columns = uint(extent.x) * uint(extent.y);
    uint first = queued.z * kTileColumns;
    uint last = min(columns, first + kTileColumns);
    for (uint c = first + gl_LocalInvocationID.x; c < last; c += gl_WorkGroupSize.x)
        voxelize_column(s, s.col_lo.x + int(c % uint(extent.x)), s.col_lo.y + int(c / uint(extent.x)));
    flush_voxels();
}
