// The CPU reference voxelizer: exact (double precision) conservative surface voxelization, used by tests
// and as a fallback checker for the GPU paths. It is not a product path: it favours being obviously right
// over being fast.
#pragma once

#include "gust/voxelizer/grid.hpp"

#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

namespace gust {

/// True when the closed triangle `tri` meets the closed box [box_min, box_max] (any space, box_min <=
/// box_max). Separating-axis test in double: touching counts as overlap; zero-area triangles work too.
bool triangle_box_overlap(const glm::dvec3 tri[3], const glm::dvec3& box_min, const glm::dvec3& box_max);

/// Result of voxelize_reference; owns its arrays.
struct CpuVoxelization {
    std::vector<std::uint32_t> voxels; ///< occupied voxels as pack_voxel keys, sorted ascending, unique
    std::uint64_t triangles = 0;       ///< triangles read (index_count / 3 summed over instances)
    std::uint64_t rejected = 0;        ///< triangles dropped for a non-finite vertex or an out-of-range index
};

/// Conservative surface voxelization of `instances` on `grid` in double precision: voxel (i,j,k) is
/// occupied when its box [ijk - box_grow, ijk + 1 + box_grow] (voxel units) meets a triangle. Zero-area
/// triangles are skipped, triangles outside the grid clipped. Runs on all hardware threads; blocking.
CpuVoxelization voxelize_reference(std::span<const InstanceDesc> instances, const GridDesc& grid,
                                   double box_grow = 0.0);

/// Set difference between a candidate voxelization and the reference, as pack_voxel keys (owning).
struct VoxelDiff {
    std::vector<std::uint32_t> missing; ///< in the reference, not in the candidate; sorted
    std::vector<std::uint32_t> extra;   ///< in the candidate, not in the reference; sorted
};

/// Splits the symmetric difference of two sorted, unique key arrays into missing and extra voxels.
VoxelDiff diff_voxels(std::span<const std::uint32_t> candidate_sorted_unique,
                      std::span<const std::uint32_t> reference_sorted_unique);

/// The differences that rounding cannot explain, sorted: a missing voxel is excused when its box shrunk
/// by `tolerance_voxels` meets no triangle, an extra one when its box grown by it meets some triangle
/// (zero-area ones included, since voxelizers may keep or skip them). Extra voxels outside the grid are
/// never excused. Triangles are those of `instances` on `grid`, as voxelize_reference reads them.
std::vector<std::uint32_t> unexplained_differences(const VoxelDiff& diff,
                                                   std::span<const InstanceDesc> instances,
                                                   const GridDesc& grid, double tolerance_voxels = 1e-3);

} // namespace gust
