// Solids for solver tests: meshes voxelized into a sparse tree over the wind grid, handed to the GPU
// solver as a SolidSource and to the CPU version as the same voxels and fragments.
#pragma once

#include "support/mesh_gen.hpp"

#include <gust/solver/cpu_wind.hpp>
#include <gust/solver/wind_solver.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <memory>
#include <optional>
#include <vector>

namespace gust::test {

/// A mesh placed in the world; moving bodies carry last frame's matrix too.
struct Body {
    TestMesh mesh;
    glm::mat4 model{1.0f};
    std::optional<glm::mat4> prev_model; ///< set: the body moves (dynamic)
};

class SolidWorld {
  public:
    /// A tree over the wind grid of `desc` (voxels of cell_size / voxels_per_cell from its min corner).
    SolidWorld(gpu::Context& ctx, const SolverDesc& desc, std::uint32_t branching = 4);
    /// Voxelizes the bodies (static ones once per call) and updates the tree; dt for velocities.
    void update(const std::vector<Body>& bodies, float dt);
    SolidSource source() const;
    CpuSolid cpu() const;
    GridDesc grid() const { return grid_; }

  private:
    gpu::Context& ctx_;
    SolverDesc desc_;
    GridDesc grid_;
    std::unique_ptr<VoxelWorld> world_;
    std::vector<GpuMesh> meshes_;
};

} // namespace gust::test
