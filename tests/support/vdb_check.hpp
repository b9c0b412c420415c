// The OpenVDB cross-check of a conservative surface voxelization (issue 2): occupied voxels against the
// unsigned distance from each voxel centre to the mesh, computed independently by OpenVDB.
#pragma once

#include "support/mesh_gen.hpp"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace gust::test {

/// What the distance field says about a voxel set.
struct DistanceCheck {
    std::size_t near_surface = 0; ///< voxel centres closer than 0.5 h to the surface
    std::size_t uncovered = 0;    ///< of those, voxels that are not occupied (must be 0)
    std::size_t too_far =
        0; ///< occupied voxels whose centre is farther than sqrt(3)/2 h + 1e-3 h (must be 0)
    std::vector<std::string> examples; ///< the first few offending voxels, for the failure message
};

/// Runs openvdb::tools::meshToUnsignedDistanceField (band 1) on `mesh` over `grid` and checks
/// `voxels` (sorted, unique packed keys) against it.
DistanceCheck check_against_distance_field(const TestMesh& mesh, const GridDesc& grid,
                                           std::span<const std::uint32_t> voxels);

} // namespace gust::test
