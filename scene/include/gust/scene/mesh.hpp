// The triangle mesh every module exchanges: positions and a triangle index list.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <gust/voxelizer/grid.hpp>
#include <string>
#include <vector>

namespace gust {

/// An indexed triangle list in the mesh's own space (units as in the source file).
/// `indices.size()` is a multiple of 3; every index is < `positions.size()` once validated.
struct Mesh {
    std::string name;                   ///< file name (or generator name) for messages
    std::vector<glm::vec3> positions;   ///< vertex positions
    std::vector<std::uint32_t> indices; ///< three per triangle
    std::size_t triangle_count() const { return indices.size() / 3; }
};

/// A view borrowing `mesh`'s arrays (valid while the mesh lives unchanged), for the voxelizer.
inline MeshView view_of(const Mesh& mesh) {
    MeshView view;
    view.positions = reinterpret_cast<const float*>(mesh.positions.data());
    view.vertex_count = mesh.positions.size();
    view.indices = mesh.indices.data();
    view.index_count = mesh.indices.size();
    return view;
}

} // namespace gust
