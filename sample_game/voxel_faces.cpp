#include "voxel_faces.hpp"

#include <algorithm>
#include <array>

namespace sample {

void VoxelFaces::find(std::span<const gust::VoxelCoord> voxels, std::vector<VoxelFace>& out) {
    out.clear();
    if (voxels.empty()) return;
    // A bit per voxel of the bounding box grown by one on every side, so every neighbour has a bit: the
    // set is a thin shell over a large ground, so the box is far smaller than gust's whole grid.
    std::array<std::int64_t, 3> lo{voxels[0].i, voxels[0].j, voxels[0].k}, hi = lo;
    for (const gust::VoxelCoord& v : voxels) {
        const std::array<std::int64_t, 3> c{v.i, v.j, v.k};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], c[a]);
            hi[a] = std::max(hi[a], c[a]);
        }
    }
    const std::array<std::int64_t, 3> size{hi[0] - lo[0] + 3, hi[1] - lo[1] + 3, hi[2] - lo[2] + 3};
    auto index = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        return static_cast<std::size_t>(((k - lo[2] + 1) * size[1] + (j - lo[1] + 1)) * size[0] +
                                        (i - lo[0] + 1));
    };
    const std::size_t words = (static_cast<std::size_t>(size[0] * size[1] * size[2]) + 63) / 64;
    bits_.assign(words, 0);
    for (const gust::VoxelCoord& v : voxels) {
        const std::size_t b = index(v.i, v.j, v.k);
        bits_[b / 64] |= std::uint64_t(1) << (b % 64);
    }
    auto occupied = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        const std::size_t b = index(i, j, k);
        return (bits_[b / 64] >> (b % 64) & 1) != 0;
    };
    constexpr int kStep[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
    for (const gust::VoxelCoord& v : voxels) {
        for (std::uint32_t side = 0; side < 6; ++side)
            if (!occupied(std::int64_t(v.i) + kStep[side][0], std::int64_t(v.j) + kStep[side][1],
                          std::int64_t(v.k) + kStep[side][2]))
                out.push_back(pack_face(v.i, v.j, v.k, side));
    }
}

} // namespace sample
