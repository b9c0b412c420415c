// Set-up shared by the GPU solver and its CPU version: the multigrid hierarchy, face layers, emitters.
#pragma once

#include "solver/solver_cells.h"
#include "solver/solver_math.h"

#include <gust/solver/wind_solver.hpp>
#include <span>
#include <vector>

namespace gust::detail {

/// Levels from the wind grid down to at most 4 cells per axis; an axis already at one cell stays.
std::pmr::vector<shaderio::GridLevel>
build_levels(glm::uvec3 cells, float cell_size,
             std::pmr::memory_resource* memory = std::pmr::get_default_resource());
/// The six face layers of a cell of v^3 voxels (−x,+x,−y,+y,−z,+z), kCellWords words each.
void face_masks(std::uint32_t v, std::uint32_t* out);
std::uint32_t cell_words(std::uint32_t v);
shaderio::GpuEmitter to_gpu(const Emitter& e);
/// Writes `emitters` into `out` (at least as many), omni emitters first and each group in its order;
/// returns how many are omni (the kernels' omni_count).
std::uint32_t omni_first(std::span<const Emitter> emitters, std::span<shaderio::GpuEmitter> out);
/// Share of an emitter's gap closed in dt seconds.
float emitter_rate(float dt, float response);
/// Whether a warm step of `desc` sums the warm start's b·q in MacCormack's correction (kAdvectCorrectScale)
/// rather than in a start pass (docs/solver.md, "The solve's start"): PassLayout::FewerStages, MacCormack,
/// no viscosity (which changes the faces after advection), a multigrid solve.
inline bool scale_in_advection(const SolverDesc& desc) {
    return desc.warm_start && desc.layout == PassLayout::FewerStages &&
           desc.advection == Advection::MacCormack && desc.viscosity <= 0.0f &&
           desc.pressure != PressureSolver::Jacobi;
}
/// Jacobi iterations between convergence checks.
inline constexpr std::uint32_t kJacobiBlock = 8;
/// Red-black sweeps of the coarsest solve.
inline constexpr std::uint32_t kCoarseSweeps = shaderio::kCoarseSweeps;

/// V-cycles the steps after one with `last` record: half as many again as it ran (at least 8 more),
/// or twice what it recorded when it used them all without converging; never above `max_cycles`.
std::uint32_t cycles_to_record(const WindStats& last, std::uint32_t max_cycles);
/// Jacobi iterations of implicit viscosity.
inline constexpr std::uint32_t kViscosityIterations = 4;
/// Air density for reporting pressure, kg/m^3.
inline constexpr float kAirDensity = 1.2f;
Status validate_dt(float dt);
/// Face velocities of a uniform flow over a grid of `cells`.
std::pmr::vector<float> uniform_faces(glm::ivec3 cells, glm::vec3 velocity,
                                      std::pmr::memory_resource* memory = std::pmr::get_default_resource());
/// An ambient wind: finite and below 10,000 m/s.
Status validate_ambient(glm::vec3 velocity);

} // namespace gust::detail
