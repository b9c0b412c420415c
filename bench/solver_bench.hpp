// What the parts of gust_bench_solver share: the scene's constants, the command line's options, the rows
// each measurement fills, and the report that turns them into the results block (solver_report.cpp).
#pragma once

#include "bench_common.hpp"

#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <gust/gpu/context.hpp>
#include <gust/gpu/profiler.hpp>
#include <gust/gust.hpp>
#include <gust/solver/wind_solver.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace gust::bench::solver {

using PassMs = gust::gpu::Timings;

/// Frame time of every step, seconds.
constexpr float kDt = 1.0f / 30.0f;
/// Wind cell size, metres, at every grid size: a larger grid covers more ground, as a game's would.
constexpr float kCellSize = 1.0f;
/// The ambient wind of every run, m/s.
constexpr glm::vec3 kAmbient{4.0f, 0.0f, 0.0f};
/// Velocity of the moving box, m/s.
constexpr glm::vec3 kBoxVelocity{0.0f, 0.0f, 3.0f};
/// Untimed frames before the timed ones of the frame tables.
constexpr int kWarmupSteps = 2;
/// A solver of the time-to-tolerance table.
struct Contender {
    const char* name;
    gust::PressureSolver pressure;
    const char* unit; ///< of WindStats::cycles: "V-cycles" (MGPCG: one per iteration) or "iterations"
    /// Cap of the search step: far more than the tolerance should take, so the tolerance stops it.
    std::uint32_t cap;
};
/// The solvers of the time-to-tolerance table, the default first: the ratios are to it. MGPCG and
/// multigrid get 100 V-cycles (SolverDesc's default is 32), Jacobi 200,000 iterations.
constexpr Contender kContenders[] = {{"MGPCG", gust::PressureSolver::MultigridPCG, "V-cycles", 100},
                                     {"multigrid", gust::PressureSolver::Multigrid, "V-cycles", 100},
                                     {"Jacobi", gust::PressureSolver::Jacobi, "iterations", 200000}};
/// Tolerances of the time-to-tolerance table; 1e-5 is SolverDesc's default.
constexpr float kTolerances[] = {1e-4f, 1e-5f};
/// Each copy of the bandwidth measurement, bytes (read once and written once).
constexpr VkDeviceSize kCopyBytes = 256ull << 20;

/// What the command line asked for.
struct Options {
    std::vector<std::string> sizes = {"32x16x32", "64", "128"};
    int repeat = 3;
    double budget_s = 30.0;
    /// Largest grid of the time-to-tolerance table: Jacobi's iterations grow with the square of the
    /// grid's width and each costs the cells, so a 128^3 solve would take hours on lavapipe.
    std::uint64_t solve_max_cells = 64ull * 64 * 64;
    /// Frame-time and frame-budget tables: the relative tolerance the solve stops at
    /// (WindSettings::tolerance).
    float tolerance = gust::SolverDesc{}.tolerance;
    /// Frame-time table: V-cycles per frame at most (WindSettings::max_cycles).
    std::uint32_t max_cycles = gust::SolverDesc{}.max_cycles;
    /// Every table: SolverDesc::advection (--advection semi_lagrangian or maccormack, the scene format's
    /// names).
    gust::Advection advection = gust::SolverDesc{}.advection;
    /// Frame-budget table: V-cycles per step (0: no such table).
    std::uint32_t frame_cycles = 2;
    std::string write;
    std::string device;
};

/// Median of `values` (mean of the middle two for an even count), the statistic every column reports.
double median(std::vector<double> values);

/// Median of `field(item)` over `items`.
template <class T, class F> double median_of(const std::vector<T>& items, F field) {
    std::vector<double> values;
    for (const T& item : items)
        values.push_back(double(field(item)));
    return median(values);
}

/// "32x16x32", or "64^3" for a cube.
std::string size_name(glm::uvec3 cells);

/// Cells of a grid, the size the time-to-tolerance table is limited by.
std::uint64_t cell_count(glm::uvec3 cells);

/// Seconds with three significant digits, for the time-to-tolerance columns.
std::string fmt_s(double s);

/// A residual or tolerance in scientific notation.
std::string fmt_sci(double x);

/// Milliseconds of the pass `name`, or a negative number when the step did not time it.
double pass_ms(const PassMs& passes, std::string_view name);

/// GPU milliseconds of all passes of a step.
double summed(const PassMs& passes);

/// One timed frame.
struct StepSample {
    double wall_ms = 0.0; ///< around System::step()
    gust::FrameStats stats;
};

/// The frame tables' row of one grid.
struct StepRow {
    glm::uvec3 cells{0};
    std::uint32_t levels = 0;
    std::uint64_t static_fragments = 0; ///< FrameStats::fragments of the static boxes alone
    /// FrameStats::fragments less the static boxes': the sliding box's, which solid_motion reads.
    double moving_fragments(const StepSample& s) const {
        return double(s.stats.fragments - static_fragments);
    }
    std::vector<StepSample> steps;
    /// The frame-budget table's rows: one more frame after the timed ones, each dispatch timed apart
    /// (System::set_dispatch_timing), in recording order.
    gust::FrameStats::Timings timeline;
    std::string error;
    /// Medians over the timed frames: GPU ms of the wind's pass `name` (FrameStats::ms "wind_<name>"), of
    /// the voxelizer's and the tree's passes, of all passes, wall ms, V-cycles.
    double pass(const std::string& name) const {
        return median_of(steps, [&](const StepSample& s) { return pass_ms(s.stats.ms, "wind_" + name); });
    }
    double world() const {
        return median_of(steps, [](const StepSample& s) {
            double sum = 0.0;
            for (const auto& [name, ms] : s.stats.ms)
                sum += name.starts_with("wind_") ? 0.0 : ms;
            return sum;
        });
    }
    double total() const {
        return median_of(steps, [](const StepSample& s) { return summed(s.stats.ms); });
    }
    double wall() const {
        return median_of(steps, [](const StepSample& s) { return s.wall_ms; });
    }
    double cycles() const {
        return median_of(steps, [](const StepSample& s) { return s.stats.cycles; });
    }
};

/// One step of one solver from the uniform ambient wind.
struct Solve {
    double wall_s = 0.0; ///< around WindSolver::step()
    gust::WindStats stats;
};

/// One solver's row of the time-to-tolerance table.
struct SolveSide {
    const Contender* solver = nullptr;
    Solve search;             ///< the first step, at the solver's cap
    std::vector<Solve> timed; ///< at a cap of what the search needed; none when it did not converge
    std::string error;
    bool converged() const { return error.empty() && search.stats.converged; }
    /// max |residual| / max |divergence before| at the search step's last check.
    double residual_ratio() const {
        const gust::WindStats& s = search.stats;
        return s.divergence_before > 0.0 ? s.residual / s.divergence_before : 0.0;
    }
    /// Medians over the timed steps: wall seconds, GPU ms of the pressure pass.
    double wall_s() const {
        return median_of(timed, [](const Solve& s) { return s.wall_s; });
    }
    double pressure_ms() const {
        return median_of(timed, [](const Solve& s) { return pass_ms(s.stats.ms, "pressure"); });
    }
};

/// One grid and tolerance of the time-to-tolerance table: a side per kContenders entry, in its order.
struct SolveRow {
    glm::uvec3 cells{0};
    float tolerance = 0.0f;
    std::array<SolveSide, std::size(kContenders)> sides;
};

/// Device bandwidth, bytes per second, two ways: a kCopyBytes vkCmdCopyBuffer, and the same bytes copied by
/// a compute shader (shaders/bench/copy.comp); each timed by the GPU's timestamps, read once and written
/// once (so 2 x kCopyBytes move), the median of `repeat` after one warm-up.
struct Bandwidth {
    double copy = 0.0;    ///< vkCmdCopyBuffer
    double compute = 0.0; ///< the compute shader: the floor the passes are held against
};

/// Decimal gigabytes per second.
std::string fmt_gbs(double bytes_per_s);

/// The Markdown body of the results block: heading, command, machine, the four sections and notes.
std::string render(const std::vector<StepRow>& steps, const std::vector<SolveRow>& solves,
                   const std::vector<StepRow>& budget_rows, const gust::SolverDesc& desc,
                   const Bandwidth& bandwidth, const Options& options, const gust::gpu::DeviceInfo& device,
                   const RunInfo& run);

} // namespace gust::bench::solver
