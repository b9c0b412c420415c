#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, pass 2: a workgroup per large triangle, its threads striding over the columns, so a
// triangle spanning the grid does not serialise on one thread. Workgroups loop over the queue.
#include "voxelize_common.glsl"

layout(local_size_x = kVoxelizeGroupSize) in;

void main() {
    uint queued = Counters(pc.counters).c.large_triangles;
    for (uint i = gl_WorkGroupID.x; i < queued; i += gl_NumWorkGroups.x) {
        uint t = LargeList(pc.large_list).v[i];
        Setup s;
        setup_triangle(load_grid_vertex(t, 0u), load_grid_vertex(t, 1u), load_grid_vertex(t, 2u), s);
        ivec2 extent = s.col_hi - s.col_lo + 1;
        uint columns = uint(extent.x) * uint(extent.y);
        for (uint c = gl_LocalInvocationID.x; c < columns; c += gl_WorkGroupSize.x)
            voxelize_column(s, s.col_lo.x + int(c % uint(extent.x)), s.col_lo.y + int(c / uint(extent.x)));
    }
}
