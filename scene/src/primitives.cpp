#include "gust/scene/primitives.hpp"

namespace gust {

Mesh make_box_mesh(glm::vec3 min, glm::vec3 max) {
    Mesh mesh;
    mesh.name = "box";
    // Vertex v has bit 0 = x, bit 1 = y, bit 2 = z taken from max.
    for (int v = 0; v < 8; ++v) {
        mesh.positions.emplace_back((v & 1) ? max.x : min.x, (v & 2) ? max.y : min.y,
                                    (v & 4) ? max.z : min.z);
    }
    mesh.indices = {
        0, 4, 6, 0, 6, 2, // -x
        1, 3, 7, 1, 7, 5, // +x
        0, 1, 5, 0, 5, 4, // -y
        2, 6, 7, 2, 7, 3, // +y
        0, 2, 3, 0, 3, 1, // -z
        4, 5, 7, 4, 7, 6, // +z
    };
    return mesh;
}

} // namespace gust
