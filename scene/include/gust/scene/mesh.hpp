// The triangle mesh every module exchanges: positions and a triangle index list.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
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

} // namespace gust
