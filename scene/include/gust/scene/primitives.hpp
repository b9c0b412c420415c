// Generated meshes for tests and samples.
#pragma once

#include "gust/scene/mesh.hpp"

#include <glm/glm.hpp>

namespace gust {

/// The closed axis-aligned box [min, max] (same units as the arguments) as 8 vertices and 12 triangles,
/// wound counter-clockwise seen from outside. Named "box".
Mesh make_box_mesh(glm::vec3 min, glm::vec3 max);

} // namespace gust
