// OpenVDB output in the layout docs/design.md fixes: a BoolGrid "occupancy" whose index (i,j,k) maps to
// the voxel centre origin + (i + 0.5) h, and for simulated frames the wind grids "solid", "velocity"
// and "pressure" whose index (i,j,k) maps to the wind cell's centre; each coarser cascade k adds its own
// "solid_cascadeK", "velocity_cascadeK" and "pressure_cascadeK", each with its own transform.
#pragma once

#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <gust/gpu/result.hpp>
#include <gust/voxelizer/grid.hpp>
#include <span>

namespace gust::vdb {

/// One frame's wind, cell-centred, index x + X·(y + Y·z).
struct WindGrids {
    glm::uvec3 cells{0};
    float cell_size = 1.0f;
    glm::vec3 origin{0.0f};              ///< world position of the grid's min corner, m
    std::span<const float> solid;        ///< solid fraction per cell, 0..1
    std::span<const glm::vec3> velocity; ///< m/s, world space
    std::span<const float> pressure;     ///< Pa
};

/// The smallest voxel or cell size the files hold: OpenVDB's linear transforms need the cube of their
/// scale to be at least 3e-15 (openvdb::math::ScaleMap), so 1.45e-5, with a margin.
inline constexpr double kSmallestVoxelSize = 1.5e-5;

/// Fails with the reason unless `size` (a voxel or cell edge) is at least kSmallestVoxelSize.
Status check_voxel_size(double size);

/// Writes the packed voxel keys (any order, duplicates allowed) as grid "occupancy" to `path`.
Status write_occupancy_vdb(const std::filesystem::path& path, std::span<const std::uint32_t> voxels,
                           const GridDesc& grid);

/// Writes "occupancy" and the wind grids "solid" (FloatGrid, cells with solid voxels active),
/// "velocity" (Vec3SGrid) and "pressure" (FloatGrid), every cell active in the last two, of `cascades`
/// (at least one, the finest first; the coarser ones' names end in "_cascadeK").
Status write_frame_vdb(const std::filesystem::path& path, std::span<const std::uint32_t> voxels,
                       const GridDesc& grid, std::span<const WindGrids> cascades);

} // namespace gust::vdb
