// The voxel grid of a scene's domain (DESIGN.md "Interfaces": voxels are cell_size / voxels_per_cell
// wide and indexed from the domain's min corner).
#pragma once

#include <gust/gpu/result.hpp>
#include <gust/scene/scene_file.hpp>
#include <gust/voxelizer/grid.hpp>
#include <string>

namespace gust {

/// The cubic voxel grid the tree covers: min corner at the domain's, voxel size cell_size /
/// voxels_per_cell, res the smallest power of the branching factor (at least 8) spanning the domain's
/// longest axis. Voxels beyond the domain's shorter axes exist in the tree but the wind ignores them.
inline Result<GridDesc> domain_grid(const DomainDesc& domain) {
    const std::uint32_t longest =
        std::max({domain.cells.x, domain.cells.y, domain.cells.z}) * domain.voxels_per_cell;
    std::uint32_t res = 1;
    while (res < longest || res < kMinRes) {
        res *= domain.branching;
        if (res > kMaxRes)
            return Result<GridDesc>::failure("the domain needs " + std::to_string(longest) +
                                             " voxels along its longest axis; with branching " +
                                             std::to_string(domain.branching) + " the tree would exceed " +
                                             std::to_string(kMaxRes) + " per axis");
    }
    GridDesc grid;
    grid.res = res;
    grid.voxel_size = domain.cell_size / float(domain.voxels_per_cell);
    grid.origin = domain.center - glm::vec3(domain.cells) * domain.cell_size * 0.5f;
    return grid;
}

} // namespace gust
