// What the benches that drive a gust::System share: a scene mesh handed to System::create_mesh.
#pragma once

#include <cstdint>
#include <gust/gust.hpp>
#include <gust/scene/mesh.hpp>

namespace gust::bench {

/// A rigid MeshDesc borrowing `mesh`'s arrays (valid while it lives unchanged).
inline gust::MeshDesc desc_of(const gust::Mesh& mesh) {
    gust::MeshDesc d;
    d.positions = &mesh.positions[0].x;
    d.vertex_count = std::uint32_t(mesh.positions.size());
    d.indices = mesh.indices.data();
    d.index_count = std::uint32_t(mesh.indices.size());
    return d;
}

} // namespace gust::bench
