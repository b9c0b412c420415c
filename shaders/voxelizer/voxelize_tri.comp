#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, pass 1: one thread per triangle walks its projected footprint column by column
// (Schwarz & Seidel 2010). Triangles with large footprints are queued tile by tile for
// voxelize_large.comp instead.
#include "voxelize_common.glsl"

layout(local_size_x = kVoxelizeGroupSize) in;

void main() {
    if (gl_GlobalInvocationID.x >= pc.triangle_count) return;
    uint t = pc.first_triangle + gl_GlobalInvocationID.x;
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
        for (uint i = 0u; i < tiles && slot + i < pc.large_capacity; ++i)
            LargeList(pc.large_list).v[slot + i] = uvec2(t, i);
        return;
    }
    setup_velocities(t, s);
    for (int y = s.col_lo.y; y <= s.col_hi.y; ++y)
        for (int x = s.col_lo.x; x <= s.col_hi.x; ++x) voxelize_column(s, x, y);
    flush_voxels();
}
