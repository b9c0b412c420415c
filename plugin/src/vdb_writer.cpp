#include "vdb_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <openvdb/io/Archive.h>
#include <openvdb/openvdb.h>
#include <sstream>
#include <string>

namespace gust::vdb {

namespace {

/// Index (i,j,k) -> origin + (i + 0.5) · size.
openvdb::math::Transform::Ptr centred_transform(glm::vec3 origin, float size) {
    auto transform = openvdb::math::Transform::createLinearTransform(double(size));
    const glm::dvec3 centre0 = glm::dvec3(origin) + 0.5 * double(size);
    transform->postTranslate(openvdb::Vec3d(centre0.x, centre0.y, centre0.z));
    return transform;
}

openvdb::BoolGrid::Ptr occupancy_grid(std::span<const std::uint32_t> voxels, const GridDesc& grid) {
    auto occupancy = openvdb::BoolGrid::create(false);
    occupancy->setName("occupancy");
    occupancy->setGridClass(openvdb::GRID_UNKNOWN);
    occupancy->setTransform(centred_transform(grid.origin, grid.voxel_size));
    auto accessor = occupancy->getAccessor();
    for (std::uint32_t key : voxels) {
        const glm::uvec3 v = unpack_voxel(key);
        accessor.setValueOn(openvdb::Coord(int(v.x), int(v.y), int(v.z)), true);
    }
    return occupancy;
}

/// One cascade's wind grids, their names ending in `suffix`, appended to `out`.
void wind_grids(const WindGrids& wind, const std::string& suffix, openvdb::GridPtrVec& out) {
    const auto transform = centred_transform(wind.origin, wind.cell_size);
    auto solid = openvdb::FloatGrid::create(0.0f);
    solid->setName("solid" + suffix);
    auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    velocity->setName("velocity" + suffix);
    velocity->setVectorType(openvdb::VEC_INVARIANT);
    auto pressure = openvdb::FloatGrid::create(0.0f);
    pressure->setName("pressure" + suffix);
    for (openvdb::GridBase* g :
         {static_cast<openvdb::GridBase*>(solid.get()), static_cast<openvdb::GridBase*>(velocity.get()),
          static_cast<openvdb::GridBase*>(pressure.get())})
        g->setTransform(transform->copy());
    auto s = solid->getAccessor();
    auto v = velocity->getAccessor();
    auto p = pressure->getAccessor();
    std::size_t i = 0;
    for (std::uint32_t z = 0; z < wind.cells.z; ++z)
        for (std::uint32_t y = 0; y < wind.cells.y; ++y)
            for (std::uint32_t x = 0; x < wind.cells.x; ++x, ++i) {
                const openvdb::Coord c{int(x), int(y), int(z)};
                if (wind.solid[i] > 0.0f) s.setValueOn(c, wind.solid[i]);
                v.setValueOn(c, openvdb::Vec3s(wind.velocity[i].x, wind.velocity[i].y, wind.velocity[i].z));
                p.setValueOn(c, wind.pressure[i]);
            }
    out.insert(out.end(), {solid, velocity, pressure});
}

/// The grids of a simulated frame: occupancy, then each cascade's wind.
openvdb::GridPtrVec frame_grids(std::span<const std::uint32_t> voxels, const GridDesc& grid,
                                std::span<const WindGrids> cascades) {
    openvdb::GridPtrVec grids{occupancy_grid(voxels, grid)};
    for (std::size_t k = 0; k < cascades.size(); ++k)
        wind_grids(cascades[k], k == 0 ? std::string() : "_cascade" + std::to_string(k), grids);
    return grids;
}

/// io::File's own write ignores the stream's state, so a full disk gave a truncated file and success.
/// This writes the same seekable layout (Archive::write, as File::write does) through a stream that
/// throws on any failed write or close.
class CheckedFile : public openvdb::io::Archive {
  public:
    void write_to(const std::filesystem::path& path, const openvdb::GridPtrVec& grids) const {
        std::ofstream os;
        os.exceptions(std::ios::failbit | std::ios::badbit);
        os.open(path, std::ios::out | std::ios::binary | std::ios::trunc);
        Archive::write(os, grids, /*seekable=*/true);
        os.close();
    }
};

/// Writes `grids` to `path`, turning what OpenVDB or the stream throws (while the grids are made or
/// written) into a failure naming the file. A regular file left half-written is removed: a reader
/// must not take it for a result.
template <class MakeGrids>
Status write_grids(const std::filesystem::path& path, double voxel_size, MakeGrids make_grids) {
    if (Status s = check_voxel_size(voxel_size); !s)
        return Status::failure(path.string() + ": " + s.message());
    std::string reason;
    errno = 0;
    try {
        openvdb::initialize();
        CheckedFile().write_to(path, make_grids());
        return {};
    } catch (const std::ios_base::failure&) {
        reason = errno != 0 ? std::strerror(errno) : "the write failed";
    } catch (const std::exception& e) {
        reason = e.what();
    }
    std::error_code ec;
    if (std::filesystem::is_regular_file(path, ec)) std::filesystem::remove(path, ec);
    return Status::failure(path.string() + ": cannot write OpenVDB file: " + reason);
}

} // namespace

Status check_voxel_size(double size) {
    if (size >= kSmallestVoxelSize) return {};
    std::ostringstream text;
    text << "voxel size " << size << " is below " << kSmallestVoxelSize
         << ", the smallest an OpenVDB transform holds";
    return Status::failure(text.str());
}

Status write_occupancy_vdb(const std::filesystem::path& path, std::span<const std::uint32_t> voxels,
                           const GridDesc& grid) {
    return write_grids(path, grid.voxel_size,
                       [&] { return openvdb::GridPtrVec{occupancy_grid(voxels, grid)}; });
}

Status write_frame_vdb(const std::filesystem::path& path, std::span<const std::uint32_t> voxels,
                       const GridDesc& grid, std::span<const WindGrids> cascades) {
    if (cascades.empty()) return Status::failure(path.string() + ": no wind grids to write");
    for (const WindGrids& wind : cascades) {
        const std::size_t cells = std::size_t(wind.cells.x) * wind.cells.y * wind.cells.z;
        if (wind.solid.size() != cells || wind.velocity.size() != cells || wind.pressure.size() != cells)
            return Status::failure(path.string() + ": wind grids do not match the domain's cells");
    }
    // The finest cascade has the smallest cells.
    return write_grids(path, std::min<double>(grid.voxel_size, cascades.front().cell_size),
                       [&] { return frame_grids(voxels, grid, cascades); });
}

} // namespace gust::vdb
