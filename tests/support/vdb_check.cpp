#include "support/vdb_check.hpp"

#include <algorithm>
#include <cmath>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

namespace gust::test {

DistanceCheck check_against_distance_field(const TestMesh& mesh, const GridDesc& grid,
                                           std::span<const std::uint32_t> voxels) {
    openvdb::initialize();
    const double h = grid.voxel_size;
    auto transform = openvdb::math::Transform::createLinearTransform(h);
    transform->postTranslate(openvdb::Vec3d(grid.origin.x, grid.origin.y, grid.origin.z) + 0.5 * h);
    std::vector<openvdb::Vec3s> points;
    for (const glm::vec3& p : mesh.positions)
        points.emplace_back(p.x, p.y, p.z);
    std::vector<openvdb::Vec3I> triangles;
    for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
        triangles.emplace_back(mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]);
    const auto distance = openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(
        *transform, points, triangles, std::vector<openvdb::Vec4I>(), 1.0f);
    const auto accessor = distance->getConstAccessor();

    DistanceCheck out;
    for (std::uint32_t k = 0; k < grid.res; ++k)
        for (std::uint32_t j = 0; j < grid.res; ++j)
            for (std::uint32_t i = 0; i < grid.res; ++i) {
                const double d = accessor.getValue(openvdb::Coord(int(i), int(j), int(k))) / h;
                const bool occupied = std::binary_search(voxels.begin(), voxels.end(), pack_voxel(i, j, k));
                // 1e-4 voxel of slack for OpenVDB's single-precision distances.
                const bool near = d < 0.5 - 1e-4;
                const bool far = d > std::sqrt(3.0) / 2 + 1e-3;
                out.near_surface += near;
                const bool bad = (near && !occupied) || (occupied && far);
                out.uncovered += near && !occupied;
                out.too_far += occupied && far;
                if (bad && out.examples.size() < 5)
                    out.examples.push_back("voxel " + std::to_string(i) + "," + std::to_string(j) + "," +
                                           std::to_string(k) + (occupied ? " occupied" : " empty") +
                                           ", centre " + std::to_string(d) + " voxels from the surface");
            }
    return out;
}

} // namespace gust::test
