#include "vdb_writer.hpp"

#include <openvdb/openvdb.h>

namespace gust::cli {

Status write_occupancy_vdb(const std::filesystem::path& path, std::span<const std::uint32_t> voxels,
                           const GridDesc& grid) {
    try {
        openvdb::initialize();
        auto occupancy = openvdb::BoolGrid::create(false);
        occupancy->setName("occupancy");
        occupancy->setGridClass(openvdb::GRID_UNKNOWN);
        auto transform = openvdb::math::Transform::createLinearTransform(double(grid.voxel_size));
        const glm::dvec3 centre0 = glm::dvec3(grid.origin) + 0.5 * double(grid.voxel_size);
        transform->postTranslate(openvdb::Vec3d(centre0.x, centre0.y, centre0.z));
        occupancy->setTransform(transform);
        auto accessor = occupancy->getAccessor();
        for (std::uint32_t key : voxels) {
            const glm::uvec3 v = unpack_voxel(key);
            accessor.setValueOn(openvdb::Coord(int(v.x), int(v.y), int(v.z)), true);
        }
        openvdb::io::File file(path.string());
        file.write({occupancy});
        file.close();
    } catch (const std::exception& e) {
        return Status::failure(path.string() + ": cannot write OpenVDB file: " + e.what());
    }
    return {};
}

} // namespace gust::cli
