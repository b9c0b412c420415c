// The wind solver's passes on the CPU, from the same per-cell kernels as the shaders
// (shaders/solver/solver_kernels.h). For tests, which compare it with the GPU; not a product path.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <gust/solver/wind_solver.hpp>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace gust {

/// A dense solid boundary for the CPU version, in voxels of cell_size / voxels_per_cell from the
/// grid's min corner.
struct CpuSolid {
    /// Occupancy of voxel (x, y, z), index x + X·(y + Y·z) over cells · voxels_per_cell voxels per axis:
    /// 0 free, kMoving for moving surfaces only, kStatic where a static surface is (moving ones too or not).
    std::vector<std::uint8_t> occupied;
    static constexpr std::uint8_t kMoving = 1, kStatic = 2;
    /// Moving surfaces: voxel and velocity (m/s) per fragment.
    std::vector<std::pair<glm::ivec3, glm::vec3>> fragments;
};

/// Same contract as WindSolver, on host arrays.
class CpuWind {
  public:
    static Result<std::unique_ptr<CpuWind>> create(const SolverDesc& desc);
    ~CpuWind();

    Status set_ambient(glm::vec3 velocity);
    Status set_emitters(std::span<const Emitter> emitters);
    Status scroll(glm::ivec3 cells);
    Result<WindStats> step(float dt, const CpuSolid* solid = nullptr);
    Status set_velocity(std::span<const float> faces);

    const std::vector<float>& velocity() const;
    const std::vector<float>& open_fraction() const;
    const std::vector<float>& solid_velocity() const;
    /// Pressure per cell, Pa (air density 1.2 kg/m^3).
    std::vector<float> pressure() const;
    const std::vector<float>& solid_fraction() const;

  private:
    CpuWind() = default;
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace gust
