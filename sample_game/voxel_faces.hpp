// The W view's geometry: the sides of gust's voxels that face empty space, found on the CPU.
#pragma once

#include "sample/sample_io.h"

#include <cstdint>
#include <gust/gust.hpp>
#include <span>
#include <vector>

namespace sample {

/// Voxel (i, j, k)'s side, packed as the voxel shader reads it (shaders/sample/sample_io.h).
using VoxelFace = gust::shaderio::VoxelFace;

/// Finds the faces of a voxel set: keeps the occupancy of the set's bounding box as bits between calls.
class VoxelFaces {
  public:
    /// Replaces `out` with every side of a voxel in `voxels` whose neighbour across it is not in the set.
    /// Each voxel is listed once, as System::debug_voxels lists them; indices are below 65536.
    void find(std::span<const gust::VoxelCoord> voxels, std::vector<VoxelFace>& out);

  private:
    std::vector<std::uint64_t> bits_;
};

/// Side `side` (0: -x, 1: +x, 2: -y, 3: +y, 4: -z, 5: +z) of voxel (i, j, k), packed.
inline VoxelFace pack_face(std::uint32_t i, std::uint32_t j, std::uint32_t k, std::uint32_t side) {
    return {i | j << 16, k | side << 16};
}

} // namespace sample
