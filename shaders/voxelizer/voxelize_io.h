// Push constants and constants shared by the voxelizer shaders and voxelizer/src/voxelizer.cpp.
#ifndef GUST_VOXELIZE_IO_H
#define GUST_VOXELIZE_IO_H

#include "../common.h"

GUST_NAMESPACE_BEGIN

/// Threads per workgroup of the compute paths.
GUST_CONST uint kVoxelizeGroupSize = 64;
/// Workgroups of the large-triangle pass; each loops over the large list (persistent threads), so the
/// CPU never needs the list's length.
GUST_CONST uint kLargeGroups = 256;
/// A triangle whose projected footprint has more columns than this goes to the large-triangle pass,
/// where a whole workgroup shares it instead of one thread walking it alone.
GUST_CONST uint kLargeTriangleColumns = 64;

/// Counters written by the voxelizer passes (one per call, zeroed before it).
struct VoxelizeCounters {
    uint fragments;       ///< fragments appended; may exceed the capacity, which means "redo larger"
    uint rejected;        ///< triangles with a non-finite vertex
    uint large_triangles; ///< triangles queued for the large-triangle pass (compute path)
    uint pad;
};

/// Push constants of every voxelizer pass (<= 128 bytes, the guaranteed minimum).
struct VoxelizePush {
    mat4 to_grid;             ///< model matrix followed by world -> grid space ((p - origin) / h)
    GUST_ADDRESS positions;   ///< float[3 * vertex_count]
    GUST_ADDRESS indices;     ///< uint[3 * triangle_count]
    GUST_ADDRESS fragments;   ///< uint[capacity] packed voxel keys (pack_voxel)
    GUST_ADDRESS counters;    ///< VoxelizeCounters
    GUST_ADDRESS large_list;  ///< uint[triangle_count] triangle ids for the large pass
    uint res;                 ///< voxels per axis
    uint capacity;            ///< fragment slots
    uint triangle_count;      ///< triangles in this draw or dispatch
    uint first_triangle;      ///< compute path: offset of this dispatch's first triangle
};

GUST_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(gust::shaderio::VoxelizePush) == 120, "push constants must match the GLSL layout");
static_assert(offsetof(gust::shaderio::VoxelizePush, positions) == 64);
static_assert(offsetof(gust::shaderio::VoxelizePush, res) == 104);
static_assert(sizeof(gust::shaderio::VoxelizeCounters) == 16);
#endif

#endif
