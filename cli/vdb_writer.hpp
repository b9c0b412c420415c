// OpenVDB output in the layout DESIGN.md fixes: a BoolGrid "occupancy" whose index (i,j,k) maps to
// the voxel centre origin + (i + 0.5) h.
#pragma once

#include <cstdint>
#include <filesystem>
#include <gust/gpu/result.hpp>
#include <gust/voxelizer/grid.hpp>
#include <span>

namespace gust::cli {

/// Writes the packed voxel keys (any order, duplicates allowed) as grid "occupancy" to `path`.
Status write_occupancy_vdb(const std::filesystem::path& path, std::span<const std::uint32_t> voxels,
                           const GridDesc& grid);

} // namespace gust::cli
