// The voxel grid and the mesh input every voxelizer path shares.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>

namespace gust {

/// A cube of `res`^3 voxels. Voxel (i,j,k) is the closed box [origin + (i,j,k) h, origin + (i+1,j+1,k+1) h].
struct GridDesc {
    glm::vec3 origin{0.0f};  ///< world-space min corner, metres
    float voxel_size = 1.0f; ///< h, metres, > 0
    std::uint32_t res = 64;  ///< voxels per axis, 8..1024
    /// Voxels kept per axis from the origin (a wind domain inside the power-of-b grid): surface beyond
    /// them is not voxelized; 0 keeps all `res`.
    glm::uvec3 keep{0};
};

/// Largest and smallest resolution any voxelizer path accepts.
inline constexpr std::uint32_t kMinRes = 8;
inline constexpr std::uint32_t kMaxRes = 1024;

/// A voxel coordinate packed 10:10:10 bits (i in the low bits). Valid for res <= 1024.
inline constexpr std::uint32_t pack_voxel(std::uint32_t i, std::uint32_t j, std::uint32_t k) {
    return i | (j << 10) | (k << 20);
}
/// Inverse of pack_voxel.
inline constexpr glm::uvec3 unpack_voxel(std::uint32_t key) {
    return {key & 1023u, (key >> 10) & 1023u, (key >> 20) & 1023u};
}

/// A borrowed, strided triangle mesh (meshoptimizer style). Nothing is copied until a call needs it.
struct MeshView {
    const float* positions = nullptr; ///< x,y,z floats of vertex 0; vertex v starts at byte v*stride
    std::size_t vertex_count = 0;
    std::size_t position_stride = 12;       ///< bytes between consecutive vertices, >= 12
    const std::uint32_t* indices = nullptr; ///< three per triangle, each < vertex_count
    std::size_t index_count = 0;            ///< multiple of 3
    glm::vec3 position(std::size_t v) const {
        const auto* p = reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(positions) +
                                                       v * position_stride);
        return {p[0], p[1], p[2]};
    }
};

/// One placement of a mesh: world = model * p.
struct InstanceDesc {
    MeshView mesh;
    glm::mat4 model{1.0f};
};

} // namespace gust
