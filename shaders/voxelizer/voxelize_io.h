// Push constants and constants shared by the voxelizer shaders and voxelizer/src/voxelizer.cpp.
#ifndef GUST_VOXELIZE_IO_H
#define GUST_VOXELIZE_IO_H

#include "../common.h"

GUST_NAMESPACE_BEGIN

/// Threads per workgroup of the compute paths.
GUST_CONST uint kVoxelizeGroupSize = 64;
/// A triangle whose projected footprint has more columns than this goes to the large-triangle pass,
/// where workgroups share it instead of one thread walking it alone.
GUST_CONST uint kLargeTriangleColumns = 64;
/// Columns of a large triangle's footprint per work item (one workgroup each): 64 per thread, which
/// also keeps every shader loop far below llvmpipe's limit of 65,535 iterations per loop.
GUST_CONST uint kTileColumns = 4096;
/// Workgroups per row of the indirect large-triangle dispatch (the guaranteed x limit).
GUST_CONST uint kMaxGroupsX = 65535;

/// VkDispatchIndirectCommand for the large-triangle pass, written on the GPU.
struct DispatchArgs {
    uint x, y, z;
};

/// Counters written by the voxelizer passes (one per call, zeroed before it). The buffer is also the
/// indirect-dispatch buffer of the large pass.
struct VoxelizeCounters {
    uint fragments;   ///< fragments appended; may exceed the capacity, which means "redo larger"
    uint rejected;    ///< triangles with a non-finite vertex
    uint large_items; ///< (instance, triangle, tile) items queued by the call; may exceed the capacity
    uint groups_done; ///< workgroups of the small-triangle pass done (its last one sizes the large pass)
    DispatchArgs large_dispatch; ///< workgroups of the large pass, written by voxelize_tri.comp's last group
    uint wrapped; ///< nonzero when a counter passed 2^32 - 1 (the call fails instead of wrapping silently)
};

/// One instance of a call, in a buffer (push constants hold its address).
struct VoxelizeInstance {
    mat4 to_grid;                ///< model matrix followed by world -> grid space ((p - origin) / h)
    mat4 model;                  ///< mesh -> world this frame
    mat4 prev_model;             ///< mesh -> world last frame
    GUST_ADDRESS positions;      ///< float[3 * vertex_count], this frame
    GUST_ADDRESS prev_positions; ///< float[3 * vertex_count], last frame (the same buffer for rigid meshes)
    GUST_ADDRESS indices;        ///< uint[3 * triangle_count]
    uint triangle_count;
    float inv_dt; ///< 1 / frame time in seconds; 0 when no velocities are wanted
};

/// Bytes of a VoxelizeInstance: the large pass finds an item's instance at that stride.
GUST_CONST uint kVoxelizeInstanceBytes = 224;

/// Push constants of every voxelizer pass (<= 128 bytes, the guaranteed minimum).
struct VoxelizePush {
    GUST_ADDRESS instance;  ///< VoxelizeInstance
    GUST_ADDRESS fragments; ///< uint[capacity] packed voxel keys (pack_voxel)
    GUST_ADDRESS
    velocities; ///< uvec2[capacity] surface velocity per fragment (half x, y, z; m/s, world); 0: none
    GUST_ADDRESS counters;   ///< VoxelizeCounters
    GUST_ADDRESS large_list; ///< uvec3[large_capacity] (instance, triangle, tile) items for the large pass
    uint res;                ///< voxels per axis
    uint capacity;           ///< fragment slots
    // The vectors start at multiples of 16 bytes: Vulkan 1.2's relaxed block layout, which a device without
    // scalarBlockLayout (Godot 4's) holds push constants to, lets no vector straddle a 16-byte boundary.
    uvec3 keep; ///< voxels kept per axis from the grid's origin (the wind domain); the rest dropped
    /// Nonzero: only the slabs a scroll uncovered are voxelized, the voxels v for which v + slab_shift
    /// lies outside [0, keep) on some axis (the rest are in the list shifted by voxelize_shift.comp).
    uint slabs;
    ivec3 slab_shift;    ///< the scroll in voxels: the old grid's voxel v + slab_shift is the new grid's v
    uint triangle_count; ///< triangles in this draw or dispatch
    uint first_triangle; ///< compute path: offset of this dispatch's first triangle
    uint large_capacity; ///< items the large list holds
    /// Compute path: the instance's index in the call's instance buffer, which the large queue's items
    /// carry (the large pass's `instance` is that buffer's start).
    uint instance_index;
    /// Compute path: workgroups of all the call's small-triangle dispatches together; the one that finishes
    /// last sizes the large pass.
    uint groups_total;
};

/// Threads per workgroup of voxelize_shift.comp.
GUST_CONST uint kShiftGroupSize = 64;
/// Kept fragments a thread of voxelize_shift.comp moves per block (one atomic for them).
GUST_CONST uint kShiftPerThread = 8;
/// The most workgroups of voxelize_shift.comp, which stride over a longer list.
GUST_CONST uint kShiftMaxGroups = 2048;

/// Push constants of voxelize_shift.comp, which moves a kept fragment list into a scrolled grid.
struct ShiftPush {
    GUST_ADDRESS source;       ///< uint[source_capacity] packed keys of the last pass, in the old grid
    GUST_ADDRESS source_count; ///< uint: fragments the last pass counted (may exceed source_capacity)
    GUST_ADDRESS fragments;    ///< uint[capacity]: the new list, appended to through counters
    GUST_ADDRESS counters;     ///< VoxelizeCounters of the new pass (zeroed before)
    ivec3 shift; ///< old key - shift = new key (at 32 bytes: no vector straddles 16, as in VoxelizePush)
    uint source_capacity;
    uvec3 keep; ///< the new grid's kept voxels per axis; keys outside are dropped
    uint capacity;
};

GUST_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(gust::shaderio::VoxelizePush) == 96, "push constants must match the GLSL layout");
static_assert(offsetof(gust::shaderio::VoxelizePush, slab_shift) == 64);
static_assert(sizeof(gust::shaderio::ShiftPush) == 64);
static_assert(offsetof(gust::shaderio::ShiftPush, shift) == 32);
static_assert(offsetof(gust::shaderio::ShiftPush, keep) == 48);
static_assert(offsetof(gust::shaderio::VoxelizePush, keep) == 48);
static_assert(offsetof(gust::shaderio::VoxelizePush, res) == 40);
static_assert(sizeof(gust::shaderio::VoxelizeInstance) == gust::shaderio::kVoxelizeInstanceBytes);
static_assert(offsetof(gust::shaderio::VoxelizeInstance, positions) == 192);
static_assert(sizeof(gust::shaderio::VoxelizeCounters) == 32);
static_assert(offsetof(gust::shaderio::VoxelizeCounters, large_dispatch) == 16);
static_assert(offsetof(gust::shaderio::VoxelizePush, large_capacity) == 84);
#endif

#endif
