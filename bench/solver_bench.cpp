// Measures the wind solver (docs/design.md "Wind solver"): GPU time per pass of one step at God of War's
// 32x16x32 grid and larger ones, the three pressure solvers (multigrid-preconditioned conjugate gradients,
// plain multigrid and the Jacobi baseline) to the same tolerance, and the bytes each pass moves against the
// device's copy bandwidth.
#include "bench_common.hpp"
#include "gust_shaders/copy_comp.h"
#include "solver_setup.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <glm/gtc/matrix_transform.hpp>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/context.hpp>
#include <gust/gpu/profiler.hpp>
#include <gust/gust.hpp>
#include <gust/solver/wind_solver.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <iostream>
#include <map>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace {

using gust::bench::block_name;
using gust::bench::Clock;
using gust::bench::command_line;
using gust::bench::cpu_model;
using gust::bench::failed_cell;
using gust::bench::fmt_ms;
using gust::bench::fmt_ratio;
using gust::bench::grouped;
using gust::bench::heading_device;
using gust::bench::load_average;
using gust::bench::ms_since;
using gust::bench::RunInfo;
using gust::bench::usable_cores;
using gust::bench::utc_now;
using PassMs = gust::gpu::Timings;

/// Names this tool in its error and Vulkan messages.
constexpr const char* kTool = "gust_bench_solver";
/// Names this bench's block in the results file (`<!-- bench:solver:begin -->`).
constexpr const char* kBlock = "solver";

/// Prints a fatal error under this tool's name and gives the exit status.
int fail(const std::string& message) {
    return gust::bench::fail(kTool, message);
}

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
/// Push constants of shaders/bench/copy.comp.
struct CopyPush {
    std::uint64_t source;
    std::uint64_t target;
    std::uint32_t count; ///< vec4s
};

/// What the command line asked for.
struct Options {
    std::vector<std::string> sizes = {"32x16x32", "64", "128"};
    int repeat = 3;
    double budget_s = 30.0;
    /// Largest grid of the time-to-tolerance table: Jacobi's iterations grow with the square of the
    /// grid's width and each costs the cells, so a 128^3 solve would take hours on lavapipe.
    std::uint64_t solve_max_cells = 64ull * 64 * 64;
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
double median(std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const std::size_t mid = values.size() / 2;
    return values.size() % 2 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

/// Median of `field(item)` over `items`.
template <class T, class F> double median_of(const std::vector<T>& items, F field) {
    std::vector<double> values;
    for (const T& item : items)
        values.push_back(double(field(item)));
    return median(values);
}

/// Parses "N" (a cube) or "XxYxZ".
gust::Result<glm::uvec3> parse_size(const std::string& text) {
    glm::uvec3 cells(0);
    char tail = 0;
    if (std::sscanf(text.c_str(), "%ux%ux%u%c", &cells.x, &cells.y, &cells.z, &tail) == 3) return cells;
    if (std::sscanf(text.c_str(), "%u%c", &cells.x, &tail) == 1) return glm::uvec3(cells.x);
    return gust::Result<glm::uvec3>::failure("--sizes: \"" + text + "\" is neither N nor XxYxZ");
}

/// "32x16x32", or "64^3" for a cube.
std::string size_name(glm::uvec3 cells) {
    if (cells.x == cells.y && cells.y == cells.z) return std::to_string(cells.x) + "^3";
    return std::to_string(cells.x) + "x" + std::to_string(cells.y) + "x" + std::to_string(cells.z);
}

/// Cells of a grid, the size the time-to-tolerance table is limited by.
std::uint64_t cell_count(glm::uvec3 cells) {
    return std::uint64_t(cells.x) * cells.y * cells.z;
}

/// Seconds with three significant digits, for the time-to-tolerance columns.
std::string fmt_s(double s) {
    char text[32];
    std::snprintf(text, sizeof(text), s < 1.0 ? "%.3f" : s < 10.0 ? "%.2f" : "%.1f", s);
    return text;
}

/// A residual or tolerance in scientific notation.
std::string fmt_sci(double x) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.1e", x);
    return text;
}

/// Milliseconds of the pass `name`, or a negative number when the step did not time it.
double pass_ms(const PassMs& passes, std::string_view name) {
    for (const auto& [pass, ms] : passes)
        if (pass == name) return ms;
    return -1.0;
}

/// GPU milliseconds of all passes of a step.
double summed(const PassMs& passes) {
    double total = 0.0;
    for (const auto& pass : passes)
        total += pass.second;
    return total;
}

/// The unit cube [0, 1]^3 as 8 corners and 12 triangles; every box of the scene is an instance of it.
struct UnitBox {
    std::array<glm::vec3, 8> positions;
    std::array<std::uint32_t, 36> indices;

    UnitBox() {
        for (std::uint32_t i = 0; i < 8; ++i)
            positions[i] = glm::vec3(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
        const std::uint32_t quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                           {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
        std::size_t n = 0;
        for (const auto& q : quads)
            for (std::uint32_t corner : {q[0], q[1], q[2], q[0], q[2], q[3]})
                indices[n++] = corner;
    }

    gust::MeshView view() const {
        gust::MeshView v;
        v.positions = &positions[0].x;
        v.vertex_count = positions.size();
        v.position_stride = sizeof(glm::vec3);
        v.indices = indices.data();
        v.index_count = indices.size();
        return v;
    }
};

/// Model matrix of the unit box stretched to span lo..hi.
glm::mat4 box_model(glm::vec3 lo, glm::vec3 hi) {
    return glm::scale(glm::translate(glm::mat4(1.0f), lo), hi - lo);
}

/// A box of the scene: x and z in fractions of the domain's extent, y in metres from its floor.
struct Placed {
    glm::vec2 lo_xz, hi_xz;
    float lo_y, hi_y; ///< metres, or fractions of the height where `top_fraction` says so
    bool top_fraction;
};

/// Where the scene's solids and source lie on one grid: a ground slab whose top cuts the lowest cells,
/// three buildings standing in it, a box sliding along +z over the ground, an omni emitter among them,
/// and the ambient wind along +x. Footprints and heights are fractions of the domain, so every size holds
/// the same scene at its own resolution; the ground's top is at the same height in metres, so it cuts its
/// cells alike.
class Layout {
  public:
    explicit Layout(const gust::SolverDesc& desc)
        : origin_(desc.origin), extent_(glm::vec3(desc.cells) * desc.cell_size) {}

    /// Model matrices of the unit box for the static boxes, the ground first.
    std::vector<glm::mat4> statics() const {
        std::vector<glm::mat4> out;
        for (const Placed& p : kStatic)
            out.push_back(model(p));
        return out;
    }

    /// The sliding box's model matrix at step `index`.
    glm::mat4 moving(std::int64_t index) const {
        return glm::translate(glm::mat4(1.0f), float(index) * kDt * kBoxVelocity) * model(kMoving);
    }

    /// The omni emitter, pushing air outwards among the buildings.
    gust::Emitter emitter() const {
        gust::Emitter e;
        e.type = gust::EmitterType::Omni;
        e.position = origin_ + extent_ * kEmitterAt;
        e.radius = kEmitterRadius * std::min({extent_.x, extent_.y, extent_.z});
        e.strength = kEmitterStrength;
        return e;
    }

    glm::vec3 centre() const { return origin_ + 0.5f * extent_; }

    /// What the scene holds, for the results text.
    static std::string describe() {
        std::ostringstream out;
        const auto box = [&](const Placed& p) {
            out << "x " << p.lo_xz.x << "-" << p.hi_xz.x << ", z " << p.lo_xz.y << "-" << p.hi_xz.y
                << " of the extent, y from " << p.lo_y << " m to " << p.hi_y
                << (p.top_fraction ? " of the height" : " m");
        };
        out << "a ground slab (past every side) with its top at y = " << kStatic[0].hi_y
            << " m, inside the lowest cells; buildings at ";
        for (std::size_t i = 1; i < std::size(kStatic); ++i) {
            if (i > 1) out << (i + 1 == std::size(kStatic) ? " and " : "; ");
            box(kStatic[i]);
        }
        out << ", standing in the ground; a box at ";
        box(kMoving);
        out << ", sliding along +z at " << kBoxVelocity.z << " m/s; an omni emitter (" << kEmitterStrength
            << " m/s, radius " << kEmitterRadius << " of the shortest side, falloff 1) at (" << kEmitterAt.x
            << ", " << kEmitterAt.y << ", " << kEmitterAt.z << ") of the extent";
        return out.str();
    }

  private:
    glm::mat4 model(const Placed& p) const {
        const float hi_y = p.top_fraction ? p.hi_y * extent_.y : p.hi_y;
        const glm::vec3 lo(p.lo_xz.x * extent_.x, p.lo_y, p.lo_xz.y * extent_.z);
        const glm::vec3 hi(p.hi_xz.x * extent_.x, hi_y, p.hi_xz.y * extent_.z);
        return box_model(origin_ + lo, origin_ + hi);
    }

    /// The ground first, reaching past the sides and the floor so that it has no edges inside; the
    /// buildings reach below the floor too.
    static constexpr Placed kStatic[] = {{{-0.1f, -0.1f}, {1.1f, 1.1f}, -1.0f, 0.3f, false},
                                         {{0.2f, 0.25f}, {0.3f, 0.4f}, -1.0f, 0.5f, true},
                                         {{0.5f, 0.6f}, {0.62f, 0.72f}, -1.0f, 0.7f, true},
                                         {{0.7f, 0.2f}, {0.78f, 0.45f}, -1.0f, 0.35f, true}};
    static constexpr Placed kMoving{{0.42f, 0.12f}, {0.48f, 0.18f}, 0.5f, 0.2f, true};
    static constexpr glm::vec3 kEmitterAt{0.35f, 0.3f, 0.5f};
    static constexpr float kEmitterRadius = 0.15f;
    static constexpr float kEmitterStrength = 6.0f;

    glm::vec3 origin_;
    glm::vec3 extent_;
};

/// The scene for the wind solver alone (the time-to-tolerance table): a b = 4 VoxelWorld over the wind
/// grid with the static boxes set; the moving box is placed by advance().
class Scene {
  public:
    static gust::Result<std::unique_ptr<Scene>> create(gust::gpu::Context& ctx,
                                                       const gust::SolverDesc& desc) {
        std::unique_ptr<Scene> scene(new Scene(desc));
        auto grid = gust::voxel_grid(desc, 4);
        if (!grid) return grid.status();
        gust::WorldDesc world;
        world.grid = *grid;
        world.tree.branching = 4;
        world.method = gust::VoxelizeMethod::Compute;
        auto created = gust::VoxelWorld::create(ctx, world);
        if (!created) return created.status();
        scene->world_ = std::move(*created);
        auto box = scene->world_->upload(UnitBox().view());
        if (!box) return gust::Status::failure("box upload failed: " + box.message());
        scene->box_ = std::make_unique<gust::GpuMesh>(std::move(*box));
        std::vector<gust::GpuInstance> statics;
        for (const glm::mat4& model : scene->layout_.statics())
            statics.push_back({scene->box_.get(), model, std::nullopt});
        scene->world_->set_static(std::move(statics));
        return scene;
    }

    /// Moves the box to step `index` and voxelizes the frame (static set once, box with velocities).
    gust::Status advance(std::int64_t index) {
        const gust::GpuInstance moving{box_.get(), layout_.moving(index), layout_.moving(index - 1)};
        auto frame = world_->step(std::span(&moving, 1), kDt);
        return frame ? gust::Status{} : frame.status();
    }

    /// The solid boundary as the solver takes it: the tree and the moving box's fragments. Taken after
    /// advance(), since a step may reallocate the fragment list.
    gust::SolidSource source() const { return gust::solid_source(*world_); }

    const Layout& layout() const { return layout_; }

  private:
    explicit Scene(const gust::SolverDesc& desc) : layout_(desc) {}

    Layout layout_;
    std::unique_ptr<gust::VoxelWorld> world_;
    std::unique_ptr<gust::GpuMesh> box_;
};

/// gust's matrix type from GLM's (both column-major).
gust::Mat4 to_mat4(const glm::mat4& m) {
    gust::Mat4 out;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            out.m[4 * c + r] = m[c][r];
    return out;
}

/// The Status of a public API call's Outcome, its message prefixed with what was being done.
gust::Status checked(const gust::Outcome& outcome, const char* what) {
    return outcome ? gust::Status{} : gust::Status::failure(std::string(what) + ": " + outcome.message());
}

/// The frame tables' scene through the public API, as a game drives gust: a gust::System on its own
/// device whose wind domain is the grid of `desc`, the unit box as one mesh, the static boxes as
/// instances, the sliding box as a moving instance, the ambient wind and the emitter. advance() moves the
/// box and runs one whole frame (voxelizer, tree, wind, texture) with System::step.
class FrameScene {
  public:
    static gust::Result<std::unique_ptr<FrameScene>> create(const gust::SolverDesc& desc,
                                                            const Options& options,
                                                            std::uint32_t cycles_per_step,
                                                            bool moving = true) {
        std::unique_ptr<FrameScene> scene(new FrameScene(desc));
        gust::SystemDesc system;
        system.device = options.device.empty() ? nullptr : options.device.c_str();
        system.voxelize = gust::VoxelizePath::Compute;
        for (int a = 0; a < 3; ++a)
            system.domain.cells[a] = desc.cells[a];
        system.domain.cell_size = desc.cell_size;
        system.domain.voxels_per_cell = desc.voxels_per_cell;
        system.domain.branching = 4;
        const glm::vec3 centre = scene->layout_.centre();
        system.domain.focus = {centre.x, centre.y, centre.z};
        system.wind.tolerance = desc.tolerance;
        system.wind.max_cycles = desc.max_cycles;
        system.wind.cycles_per_step = cycles_per_step;
        system.wind.vorticity = desc.vorticity;
        system.wind.advection = desc.advection == gust::Advection::MacCormack
                                    ? gust::WindAdvection::MacCormack
                                    : gust::WindAdvection::SemiLagrangian;
        if (gust::Status s = checked(gust::System::create(system, scene->system_), "System::create"); !s)
            return s;
        gust::System& sys = *scene->system_;
        const UnitBox box;
        gust::MeshDesc mesh;
        mesh.positions = &box.positions[0].x;
        mesh.vertex_count = std::uint32_t(box.positions.size());
        mesh.indices = box.indices.data();
        mesh.index_count = std::uint32_t(box.indices.size());
        gust::MeshId mesh_id = 0;
        if (gust::Status s = checked(sys.create_mesh(mesh, mesh_id), "create_mesh"); !s) return s;
        for (const glm::mat4& model : scene->layout_.statics()) {
            gust::InstanceId id = 0;
            if (gust::Status s =
                    checked(sys.create_instance(mesh_id, to_mat4(model), false, id), "create_instance");
                !s)
                return s;
        }
        if (moving)
            if (gust::Status s =
                    checked(sys.create_moving_instance(mesh_id, to_mat4(scene->layout_.moving(0)),
                                                       to_mat4(scene->layout_.moving(-1)), scene->moving_),
                            "create_moving_instance");
                !s)
                return s;
        if (gust::Status s = checked(sys.set_ambient({kAmbient.x, kAmbient.y, kAmbient.z}), "set_ambient");
            !s)
            return s;
        const gust::Emitter e = scene->layout_.emitter();
        gust::WindEmitter emitter;
        emitter.type = gust::WindEmitterType::Omni;
        emitter.position = {e.position.x, e.position.y, e.position.z};
        emitter.radius = e.radius;
        emitter.strength = e.strength;
        emitter.falloff = e.falloff;
        if (gust::Status s = checked(sys.set_emitters(std::span(&emitter, 1)), "set_emitters"); !s) return s;
        return scene;
    }

    /// Moves the box to step `index` (created at step 0) and runs the frame; the wall time around step().
    gust::Result<double> advance(std::int64_t index) {
        if (index > 0 && moving_ != 0)
            if (gust::Status s =
                    checked(system_->set_transform(moving_, to_mat4(layout_.moving(index))), "set_transform");
                !s)
                return s;
        const auto start = Clock::now();
        const gust::Outcome stepped = system_->step(kDt);
        const double wall_ms = ms_since(start);
        if (gust::Status s = checked(stepped, "step"); !s) return s;
        return wall_ms;
    }

    const gust::FrameStats& stats() const { return system_->stats(); }

  private:
    explicit FrameScene(const gust::SolverDesc& desc) : layout_(desc) {}

    Layout layout_;
    std::unique_ptr<gust::System> system_;
    gust::InstanceId moving_ = 0;
};

/// Face velocities of the uniform ambient wind: the non-random start of every timed solve.
std::vector<float> ambient_field(glm::uvec3 cells) {
    const glm::ivec3 n(cells);
    std::vector<float> faces(std::size_t(gust::shaderio::faces_total(n)));
    for (int i = 0; i < int(faces.size()); ++i) {
        std::uint32_t axis;
        gust::shaderio::face_from_index(n, i, axis);
        faces[std::size_t(i)] = kAmbient[int(axis)];
    }
    return faces;
}

/// A solver of `desc` with the scene's ambient wind and emitter.
gust::Result<std::unique_ptr<gust::WindSolver>>
make_solver(gust::gpu::Context& ctx, const gust::SolverDesc& desc, const Scene& scene) {
    auto solver = gust::WindSolver::create(ctx, desc);
    if (!solver) return solver;
    if (gust::Status s = (*solver)->set_ambient(kAmbient); !s) return s;
    const gust::Emitter emitter = scene.layout().emitter();
    if (gust::Status s = (*solver)->set_emitters(std::span(&emitter, 1)); !s) return s;
    return solver;
}

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

/// Runs the scene's frames from rest, moving the box every frame: kWarmupSteps untimed, then up to
/// `repeat` timed, fewer once the timed ones pass `budget_s`.
gust::Status bench_frames(FrameScene& scene, int repeat, double budget_s, StepRow& row) {
    double spent_ms = 0.0;
    for (int i = 0; i < kWarmupSteps + repeat; ++i) {
        if (!row.steps.empty() && spent_ms > budget_s * 1000.0) break;
        auto wall = scene.advance(i);
        if (!wall) return wall.status();
        StepSample sample;
        sample.wall_ms = *wall;
        sample.stats = scene.stats();
        std::cerr << "  frame " << i << (i < kWarmupSteps ? " (untimed)" : "") << ": " << sample.stats.cycles
                  << " V-cycles" << (sample.stats.converged ? "" : " (not converged)") << ", "
                  << fmt_ms(sample.wall_ms) << " ms wall" << std::endl;
        if (i < kWarmupSteps) continue;
        spent_ms += sample.wall_ms;
        row.steps.push_back(std::move(sample));
    }
    return {};
}

/// The frame table's row of `desc`'s grid at `cycles_per_step` (WindSettings): the static boxes' fragments
/// from a System holding them alone, then bench_frames on the whole scene.
gust::Status run_frames(const gust::SolverDesc& desc, const Options& options, std::uint32_t cycles_per_step,
                        StepRow& row) {
    row.cells = desc.cells;
    row.levels = std::uint32_t(gust::detail::build_levels(desc.cells, desc.cell_size).size());
    {
        auto statics = FrameScene::create(desc, options, cycles_per_step, false);
        if (!statics) return statics.status();
        if (auto wall = (*statics)->advance(0); !wall) return wall.status();
        row.static_fragments = (*statics)->stats().fragments;
    }
    auto frames = FrameScene::create(desc, options, cycles_per_step);
    if (!frames) return frames.status();
    return bench_frames(**frames, options.repeat, options.budget_s, row);
}

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

/// One step from `start`, timed around step().
gust::Result<Solve> solve_once(gust::WindSolver& solver, const gust::SolidSource& solid,
                               const std::vector<float>& start) {
    if (gust::Status s = solver.set_velocity(start); !s) return s;
    Solve out;
    const auto begin = Clock::now();
    auto stats = solver.step(kDt, &solid);
    out.wall_s = ms_since(begin) / 1000.0;
    if (!stats) return stats.status();
    out.stats = std::move(*stats);
    return out;
}

/// `desc` with its solver's cap (V-cycles or iterations) set to `cap`.
gust::SolverDesc capped(gust::SolverDesc desc, std::uint32_t cap) {
    (desc.pressure == gust::PressureSolver::Jacobi ? desc.max_iterations : desc.max_cycles) = cap;
    return desc;
}

/// The kContenders on the scene as it stands (the box no longer moves), from the same start each time.
/// Each first runs once at its cap to find how many cycles or iterations the tolerance takes; then, side
/// by side in rounds, a solver capped at that count is timed up to `repeat` times, fewer once its timed
/// steps pass `budget_s`.
SolveRow bench_solve(gust::gpu::Context& ctx, const Scene& scene, glm::uvec3 cells, float tolerance,
                     int repeat, double budget_s) {
    SolveRow row;
    row.cells = cells;
    row.tolerance = tolerance;
    const gust::SolidSource solid = scene.source();
    const std::vector<float> start = ambient_field(cells);
    // Each side's solver capped at its search step's count (null when it is not timed).
    std::array<std::unique_ptr<gust::WindSolver>, std::size(kContenders)> timed;
    for (std::size_t i = 0; i < std::size(kContenders); ++i) {
        SolveSide& side = row.sides[i];
        side.solver = &kContenders[i];
        gust::SolverDesc desc;
        desc.cells = cells;
        desc.cell_size = kCellSize;
        desc.tolerance = tolerance;
        desc.pressure = side.solver->pressure;
        auto search = make_solver(ctx, capped(desc, side.solver->cap), scene);
        if (!search) {
            side.error = search.message();
            continue;
        }
        auto solve = solve_once(**search, solid, start);
        if (!solve) {
            side.error = solve.message();
            continue;
        }
        side.search = std::move(*solve);
        if (!side.search.stats.converged) continue;
        auto solver = make_solver(ctx, capped(desc, std::max(side.search.stats.cycles, 1u)), scene);
        if (solver)
            timed[i] = std::move(*solver);
        else
            side.error = solver.message();
    }
    for (int round = 0; round < repeat; ++round)
        for (std::size_t i = 0; i < std::size(kContenders); ++i) {
            SolveSide& side = row.sides[i];
            double spent_s = 0.0;
            for (const Solve& s : side.timed)
                spent_s += s.wall_s;
            if (!timed[i] || !side.error.empty() || (round > 0 && spent_s > budget_s)) continue;
            auto solve = solve_once(*timed[i], solid, start);
            if (solve)
                side.timed.push_back(std::move(*solve));
            else
                side.error = solve.message();
        }
    return row;
}

/// Device bandwidth, bytes per second, two ways: a kCopyBytes vkCmdCopyBuffer, and the same bytes copied by
/// a compute shader (shaders/bench/copy.comp); each timed by the GPU's timestamps, read once and written
/// once (so 2 x kCopyBytes move), the median of `repeat` after one warm-up.
struct Bandwidth {
    double copy = 0.0;    ///< vkCmdCopyBuffer
    double compute = 0.0; ///< the compute shader: the floor the passes are held against
};

gust::Result<Bandwidth> copy_bandwidth(gust::gpu::Context& ctx, int repeat) {
    auto from =
        gust::gpu::Buffer::create(ctx, kCopyBytes, gust::gpu::MemoryUse::Device, 0, "bench copy source");
    if (!from) return from.status();
    auto to =
        gust::gpu::Buffer::create(ctx, kCopyBytes, gust::gpu::MemoryUse::Device, 0, "bench copy target");
    if (!to) return to.status();
    auto profiler = gust::gpu::Profiler::create(ctx, 2);
    if (!profiler) return profiler.status();
    auto shader = gust::gpu::Pipeline::compute(ctx, "gust bench copy", copy_comp, sizeof(CopyPush));
    if (!shader) return shader.status();
    const CopyPush push{from->address(), to->address(), std::uint32_t(kCopyBytes / 16)};
    // Enough workgroups of 256 to fill a large GPU; each loops over the rest.
    const std::uint32_t groups = std::min<std::uint32_t>(push.count / 256, 65535u);
    std::vector<double> copy_ms, compute_ms;
    for (int i = -1; i < repeat; ++i) {
        gust::Status s = ctx.submit_and_wait([&](VkCommandBuffer cmd) {
            if (i < 0) {
                ctx.vk().vkCmdFillBuffer(cmd, from->handle(), 0, VK_WHOLE_SIZE, 0x3f800000u);
                gust::gpu::barrier(ctx, cmd);
            }
            profiler->reset(cmd);
            profiler->begin(cmd, "copy");
            const VkBufferCopy region{0, 0, kCopyBytes};
            ctx.vk().vkCmdCopyBuffer(cmd, from->handle(), to->handle(), 1, &region);
            profiler->end(cmd);
            gust::gpu::barrier(ctx, cmd);
            profiler->begin(cmd, "compute");
            shader->bind(cmd, &push, sizeof(push));
            shader->dispatch(cmd, groups, 1, 1);
            profiler->end(cmd);
        });
        if (!s) return s;
        const PassMs passes = profiler->read();
        if (passes.size() != 2) return gust::Status::failure("the copies returned no timestamps");
        if (i >= 0) {
            copy_ms.push_back(passes[0].second);
            compute_ms.push_back(passes[1].second);
        }
    }
    const double bytes = 2.0 * double(kCopyBytes);
    return Bandwidth{bytes / (median(copy_ms) / 1000.0), bytes / (median(compute_ms) / 1000.0)};
}

// ---- Bytes per pass ------------------------------------------------------------------------------------
//
// Counting rule, from the kernels in shaders/solver/*.comp and solver_kernels.h, for an interior face or
// cell (all neighbours inside the grid, every face open), 4 bytes per float or word:
//   accessed: every load and store a thread issues, as if no cache existed (an advected face's velocity
//             at its centre, its velocity sample at the midpoint and its field sample are 9 + 3 x 8 + 8
//             loads);
//   unique:   every array element a dispatch touches, once (a perfect cache: a neighbour read by six
//             threads counts once); this is what a kernel must move at the least, so unique bytes over
//             the copy bandwidth is the floor.
// Uniform parameters (bindings, level table, emitters) and one-thread or one-workgroup passes (check,
// fragment_args, cg_scalars) are not counted; the tree's pools count once (pool_bytes) in both; each moving
// fragment's four atomics count as reads and writes of 4 bytes.

/// Bytes one pass moves, counted both ways.
struct Traffic {
    double accessed = 0.0;
    double unique = 0.0;
    std::uint64_t dispatches = 0;
    /// Adds `n` dispatches moving `accessed_bytes` and `unique_bytes` in all.
    void add(double accessed_bytes, double unique_bytes, std::uint64_t n = 1) {
        accessed += accessed_bytes;
        unique += unique_bytes;
        dispatches += n;
    }
};

/// What the byte counts depend on: the grid hierarchy and what one step found.
struct Workload {
    std::pmr::vector<gust::shaderio::GridLevel> levels;
    gust::Advection advection = gust::Advection::SemiLagrangian;
    std::uint32_t smoothing = 0;  ///< SolverDesc::smoothing
    std::uint32_t cell_words = 0; ///< words of a cell's voxel set
    double cycles = 0.0;          ///< V-cycles per step (median)
    bool warm_start = false;      ///< the solve starts from the last step's pressure
    double cut_cells = 0.0;       ///< cells holding solid voxels
    double fragments = 0.0;       ///< moving fragments
    double tree_bytes = 0.0;      ///< live bytes of the tree's pools
    double faces(std::size_t l) const { return double(gust::shaderio::faces_total(levels[l].dims)); }
    /// Bytes of one face's weight at level l: level 0 keeps a byte per face (open_counts), coarser levels
    /// a float. Accessed bytes count each weight load as the 4-byte word it is.
    static double weight(std::size_t l) { return l == 0 ? 1.0 : 4.0; }
    double cells(std::size_t l) const {
        const glm::ivec3 d = levels[l].dims;
        return double(d.x) * d.y * d.z;
    }
};

/// The "solid" pass: solid_cells (the cells' voxels from the tree, split into parts) and solid_motion.
Traffic solid_traffic(const Workload& w) {
    Traffic t;
    const double C = w.cells(0), parts = 4.0 * 2 * w.cut_cells * w.cell_words;
    // solid_cells: the last flags read, the flags and two labels stored per cell, the parts (and static
    // voxels, at most as many words) of a cut cell, the tree once. Clearing the last step's moving cells'
    // motion is left out (at most one per fragment).
    t.add(16 * C + 1.5 * parts + w.tree_bytes, 16 * C + 1.5 * parts + w.tree_bytes);
    // ... and each cell's confinement force and speed: seven vorticities, six faces, one vec4 stored.
    t.add(C * (7 * 16 + 6 * 4 + 16), 32 * C + 4 * w.faces(0), 0);
    // solid_motion: key and half-float velocity, four 4-byte atomics, per fragment.
    t.add(44 * w.fragments, 44 * w.fragments);
    return t;
}

/// The "fill" pass: the outside-air fill's union-find, linking each cell's parts to its three upper
/// neighbours' and finding each part's root (fill_link, fill_finish).
Traffic fill_traffic(const Workload& w) {
    Traffic t;
    const double C = w.cells(0), parts = 4.0 * 2 * w.cut_cells * w.cell_words;
    // fill_link: the flags of the cell and three neighbours, the parts of cut cells and their neighbours,
    // the labels of each union (about two finds of two loads each), per cell.
    t.add(C * (4 * 4 + 3 * 2 * 8) + 4 * parts, 12 * C + parts);
    // fill_finish: flags, parts of cut cells, a find per part, the label and the solid fraction stored.
    t.add(C * (4 + 2 * 8 + 2 * 4 + 4) + parts, 16 * C + parts);
    return t;
}

/// The "faces" pass: solid_faces, fluid_link and fluid_finish, then coarse_weights per coarser level.
Traffic faces_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0), air = 4.0 * w.cut_cells * w.cell_words;
    // solid_faces: two flags, the open count (a byte) and solid velocity stored; a face of a cut cell (six
    // per cut cell) also reads both cells' air. The motion sums of moving cells are left out (at most
    // 6 x 16 B per fragment).
    t.add(13 * F + 6 * 2 * air, 4 * C + 5 * F + air);
    // fluid_link and fluid_finish run in this scene: the ground slab, which the domain's sides cut, holds
    // outside air below the air above it in the lowest cells. fluid_link: per cell the flags, six open
    // counts (a word each) and about three unions (two finds of two loads each); fluid_finish: the flags and
    // a find per cell.
    t.add(C * (4 + 6 * 4 + 3 * 2 * 8), 8 * C + F);
    t.add(C * (4 + 2 * 4), 8 * C);
    // coarse_weights: the fine faces a coarse face covers (each read by one coarse face) and the store.
    for (std::size_t l = 1; l < w.levels.size(); ++l) {
        double accessed = 0.0, unique = 0.0;
        for (std::uint32_t axis = 0; axis < 3; ++axis) {
            glm::ivec3 span = w.levels[l - 1].factor;
            span[int(axis)] = 1;
            const double count = gust::shaderio::face_count(w.levels[l].dims, axis),
                         span_faces = span.x * span.y * span.z;
            accessed += count * (4 * span_faces + 4);
            unique += count * (Workload::weight(l - 1) * span_faces + 4);
        }
        t.add(accessed, unique);
    }
    return t;
}

/// The "advect" pass: semi-Lagrangian, or MacCormack's forward (which keeps the range it blended),
/// backward and clamped correction; the pass that writes the velocity (the only one, or MacCormack's last)
/// also adds the emitters, the ambient domain faces and vorticity confinement from the last step's
/// vorticity (the two cells' forces, made by solid_cells).
Traffic advect_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0);
    // Each trace reads the velocity at the face (its own value and four of each other component) and
    // samples it at the midpoint (3 components x 8 loads); a sample of a field is 8 loads.
    const double trace = (9 + 3 * 8) * 4, confine = 2 * 16;
    if (w.advection != gust::Advection::MacCormack) {
        t.add(F * (trace + 8 * 4 + confine + 4), 8 * F + 16 * C); // velocity -> tmp
        return t;
    }
    t.add(F * (trace + 8 * 4 + 3 * 4), 16 * F);        // velocity -> tmp, low and high
    t.add(F * (trace + 8 * 4 + 4), 12 * F);            // tmp -> back, tracing with the velocity
    t.add(F * (5 * 4 + confine + 4), 24 * F + 16 * C); // tmp, velocity, back, low, high -> tmp
    return t;
}

/// `half_sweeps` red-black half-sweeps at level l in `dispatches` dispatches: each touches half the cells,
/// which read six weights, six neighbours (of the other colour) and their right-hand side, and store.
void add_relax(Traffic& t, const Workload& w, std::size_t l, std::uint32_t half_sweeps,
               std::uint64_t dispatches) {
    const double n = half_sweeps;
    t.add(n * w.cells(l) / 2 * (12 * 4 + 4 + 4), n * (w.weight(l) * w.faces(l) + 6 * w.cells(l)), dispatches);
}

/// The "pressure" pass with the default MGPCG: divergence, then per iteration one V-cycle (smoothing and
/// restriction (which computes the residual) down, the coarsest solve, prolongation and smoothing up) and
/// conjugate gradients' five level-0 passes (cg.comp), and at the end the copy of x into φ.
Traffic pressure_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0), W = w.weight(0) * F;
    // divergence: the operator (12 loads), six face fluxes (3 loads each); r, b, x, p and r_old stored.
    t.add(C * (12 * 4 + 6 * 3 * 4 + 5 * 4), W + 8 * F + 24 * C);
    // warm start: q = Lφ (the operator, φ) with the sums b·q and q·q, q stored.
    if (w.warm_start) t.add(C * (12 * 4 + 4 + 4 + 4), W + 12 * C);
    // start: b (and, warm, φ and q) read; x0, r0 and φ = 0 stored.
    const double start_loads = w.warm_start ? 3 : 1;
    t.add(C * (start_loads + 3) * 4, (start_loads + 3) * 4 * C);
    const std::size_t last = w.levels.size() - 1;
    Traffic cycle;
    for (std::size_t l = 0; l < last; ++l) {
        add_relax(cycle, w, l, 2 * 2 * w.smoothing, 2 * 2 * w.smoothing);
        const glm::ivec3 k = w.levels[l].factor;
        const double parents = std::uint32_t(1) << ((k.x == 2) + (k.y == 2) + (k.z == 2));
        // restrict: a coarse cell computes its children's residuals (operator, b and φ each), two stores.
        cycle.add(w.cells(l) * (12 * 4 + 4 + 4) + 8 * w.cells(l + 1),
                  w.weight(l) * w.faces(l) + 8 * w.cells(l) + 8 * w.cells(l + 1));
        cycle.add(w.cells(l) * (4 + parents * 4 + 4), 8 * w.cells(l) + 4 * w.cells(l + 1)); // prolong
    }
    add_relax(cycle, w, last, 2 * gust::detail::kCoarseSweeps, 1);
    cycle.add(C * 3 * 4, 12 * C);                    // z·r and z·r_old
    cycle.add(C * 3 * 4, 12 * C);                    // p = z + βp
    cycle.add(C * (4 + 12 * 4 + 4), W + 4 * C);      // p·Lp
    cycle.add(C * 6 * 4, 24 * C);                    // x += αp, r_old = r, z = 0
    cycle.add(C * (4 + 12 * 4 + 4 + 4), W + 12 * C); // r = b − Lx and its maximum
    t.add(w.cycles * cycle.accessed, w.cycles * cycle.unique,
          std::uint64_t(w.cycles * double(cycle.dispatches) + 0.5));
    t.add(8 * C, 8 * C); // vkCmdCopyBuffer x -> φ
    return t;
}

/// The "project" pass: the gradient subtracted per face, the air's velocity extended into closed faces
/// in two passes, then the divergence measured again.
Traffic project_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0), W = w.weight(0) * F;
    t.add(F * 20, W + 8 * F + 4 * C);
    // extend_face: the face's weight, value and store; the closed faces' neighbours are left out.
    for (int layer = 0; layer < 2; ++layer)
        t.add(F * 12, W + 8 * F);
    // finish: φ, the final residual, the divergence after and the vorticity (six cell velocities, vec4 out).
    t.add(C * (12 * 4 + 6 * 3 * 4 + 3 * 2 * 6 * 4 + 16), W + 8 * F + 24 * C);
    return t;
}

/// The byte model of one step, per pass in the order the solver runs them.
std::vector<std::pair<std::string, Traffic>> step_traffic(const Workload& w) {
    return {{"solid", solid_traffic(w)},       {"fill", fill_traffic(w)},
            {"faces", faces_traffic(w)},       {"advect", advect_traffic(w)},
            {"pressure", pressure_traffic(w)}, {"project", project_traffic(w)}};
}

/// The workload of a frame-time row (its frames run the API's solver settings: warm start, default
/// smoothing).
Workload workload_of(const StepRow& row, const gust::SolverDesc& desc) {
    const gust::SolverDesc api;
    Workload w;
    w.levels = gust::detail::build_levels(row.cells, desc.cell_size);
    w.advection = desc.advection;
    w.smoothing = api.smoothing;
    w.cell_words = gust::detail::cell_words(desc.voxels_per_cell);
    w.cycles = row.cycles();
    w.warm_start = api.warm_start;
    w.cut_cells = median_of(row.steps, [](const StepSample& s) { return s.stats.cut_cells; });
    w.fragments = median_of(row.steps, [&](const StepSample& s) { return row.moving_fragments(s); });
    w.tree_bytes = double(row.steps.back().stats.pool_bytes);
    return w;
}

/// Decimal gigabytes per second.
std::string fmt_gbs(double bytes_per_s) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.2f", bytes_per_s / 1e9);
    return text;
}

/// Megabytes with two decimals (decimal MB, as GB/s is).
std::string fmt_mb(double bytes) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.2f", bytes / 1e6);
    return text;
}

/// The passes the frame-time table shows, in the solver's order.
constexpr const char* kPasses[] = {"solid", "fill", "faces", "advect", "pressure", "project"};

void render_steps(std::ostringstream& out, const std::vector<StepRow>& rows, const gust::SolverDesc& desc,
                  const Options& options, std::vector<std::string>& notes) {
    out << "### Frame time per pass\n\n";
    out << "Every grid has " << kCellSize
        << " m cells, so a larger grid covers more ground, and holds the same "
        << "scene: " << Layout::describe()
        << ". The frame runs through the public API, as a game drives it: one `gust::System` on its own "
           "device, the wind domain over the grid ("
        << desc.voxels_per_cell
        << " voxels per cell per axis, tree branching 4, the compute voxelizer), the unit box as one mesh, "
           "the static boxes as instances, the sliding box as a moving instance moved with `set_transform` "
           "before each `System::step`, which records the whole frame (voxelizer, tree, wind, texture) and "
           "submits it once. Ambient wind ("
        << kAmbient.x << ", " << kAmbient.y << ", " << kAmbient.z
        << ") m/s, dt = 1/30 s, `WindSettings` defaults otherwise: "
        << (desc.advection == gust::Advection::MacCormack ? "MacCormack" : "semi-Lagrangian")
        << " advection, MGPCG (conjugate gradients preconditioned by one multigrid V-cycle per iteration, "
        << gust::SolverDesc{}.smoothing << " + " << gust::SolverDesc{}.smoothing
        << " red-black sweeps), tolerance " << fmt_sci(desc.tolerance) << ", at most " << desc.max_cycles
        << " V-cycles, `cycles_per_step` 0 (each frame solves to the tolerance, recording the V-cycles the "
           "last frame suggests; docs/solver.md, \"Cycles recorded\"), the warm start, vorticity "
           "confinement "
        << desc.vorticity << ", no viscosity. The air starts at rest; " << kWarmupSteps
        << " untimed frames, then up to " << options.repeat << " timed ones, fewer once they pass "
        << options.budget_s
        << " s; every column is the median over the timed frames. Pass columns are `FrameStats::ms` (GPU "
           "timestamps): the wind's passes by name, *world* the voxelizer's and the tree's together; frame "
           "GPU ms sums them all; wall ms is around `System::step()` (recording, the submission and the "
           "wait). Moving fragments are `FrameStats::fragments` less those of a System holding the static "
           "boxes alone.\n\n";
    out << "| Grid | Cells | Levels | Cut cells | Moving fragments | Frames | World ms |";
    for (const char* pass : kPasses)
        out << " `" << pass << "` ms |";
    out << " Frame GPU ms | Wall ms | V-cycles | Dispatches | Converged |\n|--:|--:|--:|--:|--:|--:|--:|";
    for (std::size_t i = 0; i < std::size(kPasses); ++i)
        out << "--:|";
    out << "--:|--:|--:|--:|---|\n";
    for (const StepRow& row : rows) {
        out << "| " << size_name(row.cells) << " | " << grouped(cell_count(row.cells)) << " | ";
        if (!row.error.empty()) {
            out << failed_cell(notes, size_name(row.cells) + " frames", row.error) << " |";
            for (std::size_t i = 0; i < std::size(kPasses) + 9; ++i)
                out << " |";
            out << "\n";
            continue;
        }
        const gust::FrameStats& last = row.steps.back().stats;
        std::size_t converged = 0;
        for (const StepSample& s : row.steps)
            converged += s.stats.converged ? 1 : 0;
        out << row.levels << " | " << grouped(last.cut_cells) << " | "
            << grouped(std::uint64_t(row.moving_fragments(row.steps.back()))) << " | " << row.steps.size()
            << " | " << fmt_ms(row.world()) << " |";
        for (const char* pass : kPasses)
            out << " " << fmt_ms(row.pass(pass)) << " |";
        out << " " << fmt_ms(row.total()) << " | " << fmt_ms(row.wall()) << " | " << row.cycles() << " | "
            << grouped(last.dispatches) << " | " << converged << " of " << row.steps.size() << " |\n";
    }
    out << "\n";
}

/// The frame-budget table: the frame-time scene with a fixed number of V-cycles a step, as a game that
/// gives the solver a slice of its frame would run it, and how far those cycles got.
void render_budget(std::ostringstream& out, const std::vector<StepRow>& rows, const Options& options,
                   std::vector<std::string>& notes) {
    if (rows.empty()) return;
    out << "### Frame time at a budget of " << options.frame_cycles << " V-cycles\n\n";
    out << "The frame-time scene and settings with " << options.frame_cycles
        << " V-cycles a frame (`--frame-cycles`, `WindSettings::cycles_per_step`, the API's default for "
           "games), converged or not, as a game that gives the solver a fixed slice of its frame runs it; "
           "the warm start carries the rest of the solve into the next frame. Same warm-up and timed "
           "frames, medians over the timed frames. Residual / "
           "divergence is max |residual| / max |divergence before projection| after the last cycle; "
           "divergence after / before is the largest divergence left by the projection over the largest "
           "before it.\n\n";
    out << "| Grid | Frames | `pressure` ms | Frame GPU ms | Wall ms | V-cycles | Dispatches | Submissions | "
           "Waits | Residual / divergence | Divergence after / before "
           "|\n|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
           "--:|\n";
    for (const StepRow& row : rows) {
        out << "| " << size_name(row.cells) << " | ";
        if (!row.error.empty()) {
            out << failed_cell(notes, size_name(row.cells) + " at the frame budget", row.error)
                << " | | | | | | | | | |\n";
            continue;
        }
        const gust::FrameStats& last = row.steps.back().stats;
        const auto ratio = [&](auto field) {
            return median_of(row.steps, [&](const StepSample& s) {
                return s.stats.divergence_before > 0.0 ? field(s.stats) / s.stats.divergence_before : 0.0;
            });
        };
        out << row.steps.size() << " | " << fmt_ms(row.pass("pressure")) << " | " << fmt_ms(row.total())
            << " | " << fmt_ms(row.wall()) << " | " << row.cycles() << " | " << grouped(last.dispatches)
            << " | " << last.submissions << " | " << last.waits << " | "
            << fmt_sci(ratio([](const gust::FrameStats& f) { return f.residual; })) << " | "
            << fmt_sci(ratio([](const gust::FrameStats& f) { return f.divergence_after; })) << " |\n";
    }
    out << "\n";
}

void render_solves(std::ostringstream& out, const std::vector<SolveRow>& rows,
                   const std::vector<StepRow>& steps, const Options& options,
                   std::vector<std::string>& notes) {
    const std::string base = kContenders[0].name;
    out << "### MGPCG, multigrid and Jacobi to a tolerance\n\n";
    out << "The same scene with the moving box stopped where the frame-time runs left it, the same settings, "
           "and one step from the uniform ambient wind each time, so the divergence is smooth (the emitter, "
           "the inflow side and the solids' faces). Every solver stops when max |residual| <= tolerance "
           "x max |divergence before projection|. A solver records every cycle or iteration its cap allows "
           "and the check zeroes the dispatches left once the tolerance is met, so a generous cap costs time "
           "after convergence too. Each solver therefore first runs once at a generous cap (";
    for (const Contender& c : kContenders)
        out << (&c == &kContenders[0] ? "" : ", ") << c.name << " " << grouped(c.cap) << " " << c.unit;
    out << "; Jacobi is damped with weight " << gust::shaderio::kJacobiWeight << " and checked every "
        << gust::detail::kJacobiBlock
        << " iterations): that step's wall time is the last column, and the cycles or iterations it took are "
           "the count; its residual / divergence is max |residual| / max |divergence before| at its last "
           "check. Then a solver capped at that count is timed, the three side by side in rounds, up to the "
           "stated runs, fewer once a solver's timed steps pass "
        << options.budget_s
        << " s; a solver that did not converge at its cap is not timed. Wall s is around "
           "`WindSolver::step()` (the whole step), pressure ms the `pressure` pass's GPU time; medians over "
           "the timed runs; the ratio columns divide a solver's medians by "
        << base << "'s at the same grid and tolerance.";
    const bool left_out = std::any_of(steps.begin(), steps.end(), [&](const StepRow& row) {
        return cell_count(row.cells) > options.solve_max_cells;
    });
    if (left_out)
        out << " Grids above " << grouped(options.solve_max_cells)
            << " cells (`--solve-max-cells`) are left out: Jacobi's iterations grow with the square of the "
               "grid's width, so at 128^3 one solve would take about 32 times as long as at 64^3, hours on "
               "lavapipe.";
    out << "\n\n";
    out << "| Grid | Tolerance | Solver | Converged | V-cycles / iterations | Residual / divergence | Runs | "
           "Wall s | Pressure GPU ms | Wall / "
        << base << " | Pressure GPU / " << base << " | Wall s at the cap |\n";
    out << "|--:|--:|---|---|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    const auto measured = [](const SolveSide& r) { return r.converged() && !r.timed.empty(); };
    for (const SolveRow& row : rows) {
        const std::string grid = size_name(row.cells);
        const std::string tol = fmt_sci(row.tolerance);
        const SolveSide& first = row.sides[0];
        for (const SolveSide& r : row.sides) {
            out << "| " << grid << " | " << tol << " | " << r.solver->name << " | ";
            if (!r.error.empty()) {
                out << failed_cell(notes, grid + " " + r.solver->name + " at " + tol, r.error)
                    << " | | | | | | | | |\n";
                continue;
            }
            const gust::WindStats& found = r.search.stats;
            out << (found.converged ? "yes" : "no (cap " + grouped(r.solver->cap) + ")") << " | "
                << grouped(found.cycles) << " | " << fmt_sci(r.residual_ratio()) << " | " << r.timed.size();
            const auto missed = std::count_if(r.timed.begin(), r.timed.end(),
                                              [](const Solve& t) { return !t.stats.converged; });
            if (missed > 0) out << " (" << missed << " not converged)";
            out << " | ";
            if (r.timed.empty())
                out << "- | - | ";
            else
                out << fmt_s(r.wall_s()) << " | " << fmt_ms(r.pressure_ms()) << " | ";
            if (&r != &first && measured(r) && measured(first))
                out << fmt_ratio(r.wall_s() / first.wall_s()) << " | "
                    << fmt_ratio(r.pressure_ms() / first.pressure_ms()) << " | ";
            else
                out << "- | - | ";
            out << fmt_s(r.search.wall_s) << " |\n";
        }
    }
    for (const StepRow& row : steps)
        if (cell_count(row.cells) > options.solve_max_cells)
            out << "| " << size_name(row.cells) << " | - | all | skipped (more than "
                << grouped(options.solve_max_cells) << " cells) | | | | | | | | |\n";
    out << "\n";
    for (const SolveRow& row : rows) {
        out << "- At " << size_name(row.cells) << " to " << fmt_sci(row.tolerance) << ": ";
        for (const SolveSide& r : row.sides) {
            out << (&r == &row.sides[0] ? "" : &r == &row.sides.back() ? " and " : ", ") << r.solver->name;
            if (!r.error.empty()) {
                out << " failed";
            } else if (r.search.stats.converged) {
                out << " converged in " << grouped(r.search.stats.cycles) << " " << r.solver->unit;
                const gust::SolverDesc defaults;
                const std::uint32_t cap = r.solver->pressure == gust::PressureSolver::Jacobi
                                              ? defaults.max_iterations
                                              : defaults.max_cycles;
                if (r.search.stats.cycles > cap)
                    out << " (more than the default cap of " << grouped(cap) << ")";
            } else {
                out << " did not converge (" << fmt_sci(r.residual_ratio()) << " of the divergence after "
                    << grouped(r.search.stats.cycles) << " " << r.solver->unit << ")";
            }
        }
        out << ".\n";
    }
    out << "\n";
}

void render_bytes(std::ostringstream& out, const std::vector<StepRow>& rows, const gust::SolverDesc& desc,
                  const Bandwidth& copies, const Options& options) {
    const double bandwidth = copies.compute;
    out << "### Bytes per step against the bandwidth floor\n\n";
    out << "Copy bandwidth: " << fmt_gbs(bandwidth) << " GB/s copying with a compute shader "
        << "(shaders/bench/copy.comp, vec4 loads and stores in a grid-stride loop), " << fmt_gbs(copies.copy)
        << " GB/s with one `vkCmdCopyBuffer`; each of " << grouped(kCopyBytes >> 20)
        << " MiB timed by GPU timestamps (`gpu::Profiler`), counted as " << grouped(kCopyBytes >> 20)
        << " MiB read plus as much written, median of " << options.repeat
        << " after one warm-up. Bytes per pass are counted from the kernels (shaders/solver/*.comp, "
           "solver_kernels.h) for an interior face or cell at 4 bytes per float: *accessed* counts every "
           "load and store a thread issues as if there were no cache (an advected face traces from its own "
           "velocity, 9 loads, through a velocity sample of 3 x 8 loads and samples its field with 8 more; "
           "a red-black sweep touches "
           "half the cells, each reading six weights, six neighbours and its right-hand side); *unique* "
           "counts every array element a dispatch touches once, as a perfect cache would, and is the least a "
           "pass must move, so floor ms = unique bytes / copy bandwidth. Uniform parameters (bindings, level "
           "table, emitters) and one-thread or one-workgroup passes (the convergence check, the fragment "
           "count, conjugate gradients' sums for alpha and beta) are left out; the tree's live pools count "
           "once; the three `vkCmdCopyBuffer` of a step count as read plus write. The pressure pass (MGPCG) "
           "is counted per iteration (one V-cycle, at every level but the coarsest: "
        << 2 * gust::SolverDesc{}.smoothing << " half-sweeps down and " << 2 * gust::SolverDesc{}.smoothing
        << " up, restriction (which computes the finer level's residual), prolongation; the coarsest level's "
        << 2 * gust::detail::kCoarseSweeps
        << " half-sweeps; then conjugate gradients' five level-0 passes: the sums of z*r and z*r_old, "
           "p = z + beta*p, the sum of p*Lp, the update of x, r_old and z, and r = b - Lx with the check's "
           "maximum) times the median V-cycles of the frame-time table, plus the divergence (which also sets "
           "b and zeroes x, p and r_old), the warm start (q = L phi with the sums b*q and q*q), the start "
           "(x0 = s*phi and r0 = b - s*q) and the copy of x into the pressure. "
           "Measured ms are that table's medians of the wind's passes; the step row sums them (the voxelizer "
           "and the tree, the frame-time table's world column, are not modelled). A frame records the "
           "V-cycles the last frame suggests (at most "
        << desc.max_cycles
        << ") and the check zeroes the dispatches of those left after convergence, so the measured "
           "pressure ms also holds their empty dispatches. Accessed at bandwidth ms is what the accessed "
           "bytes would take at the copy bandwidth, for a kernel whose loads all miss the cache.\n\n";
    out << "| Grid | Pass | Dispatches | Accessed MB | Unique MB | Accessed / unique | Floor ms | Measured "
           "ms | "
           "Measured / floor | Accessed at bandwidth ms |\n";
    out << "|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    for (const StepRow& row : rows) {
        if (!row.error.empty()) continue;
        const Workload w = workload_of(row, desc);
        Traffic total;
        double measured_total = 0.0;
        const auto line = [&](const std::string& pass, const Traffic& t, double measured) {
            const double floor_ms = t.unique / bandwidth * 1000.0;
            out << "| " << size_name(row.cells) << " | " << pass << " | " << grouped(t.dispatches) << " | "
                << fmt_mb(t.accessed) << " | " << fmt_mb(t.unique) << " | "
                << fmt_ratio(t.accessed / t.unique) << " | " << fmt_ms(floor_ms) << " | " << fmt_ms(measured)
                << " | " << fmt_ratio(measured / floor_ms) << " | " << fmt_ms(t.accessed / bandwidth * 1000.0)
                << " |\n";
        };
        for (const auto& [pass, t] : step_traffic(w)) {
            const double measured = row.pass(pass);
            line("`" + pass + "`", t, measured);
            total.accessed += t.accessed;
            total.unique += t.unique;
            total.dispatches += t.dispatches;
            measured_total += measured;
        }
        line("**step**", total, measured_total);
    }
    out << "\n";
}

/// The Markdown body of the results block: heading, command, machine, the three sections and notes.
std::string render(const std::vector<StepRow>& steps, const std::vector<SolveRow>& solves,
                   const std::vector<StepRow>& budget_rows, const gust::SolverDesc& desc,
                   const Bandwidth& bandwidth, const Options& options, const gust::gpu::DeviceInfo& device,
                   const RunInfo& run) {
    std::ostringstream out;
    std::vector<std::string> notes;
    out << "## Wind solver: frame time through the API, MGPCG, multigrid and Jacobi to a tolerance, bytes "
           "against bandwidth"
        << heading_device(device) << "\n\n";
    out << "Command: `" << run.command << "`\n\n";
    out << "Machine: Vulkan device " << device.name << " (" << device.type << ", " << device.driver
        << "); CPU " << cpu_model() << ", " << usable_cores() << " usable cores. Run started " << run.started
        << " and took " << fmt_ms(ms_since(run.start) / 60000.0) << " min; 1-minute load average "
        << run.load_start << " at the start and " << load_average()
        << " at the end (a load above the core count means other processes shared the cores).\n\n";
    render_steps(out, steps, desc, options, notes);
    render_solves(out, solves, steps, options, notes);
    render_budget(out, budget_rows, options, notes);
    render_bytes(out, steps, desc, bandwidth, options);
    if (!notes.empty()) {
        out << "Notes:\n\n";
        for (std::size_t i = 0; i < notes.size(); ++i)
            out << i + 1 << ". " << notes[i] << "\n";
        out << "\n";
    }
    if (device.type == "cpu")
        out << device.name
            << " is a CPU-emulated Vulkan device: its \"GPU\" time is the CPU's, so only the "
               "ratios carry over to a GPU.\n";
    return out.str();
}

} // namespace

/// Runs the three measurements per grid, prints the block and writes it where --write says.
int main(int argc, char** argv) {
    Options options;
    CLI::App app{
        "Wind solver step time per pass, MGPCG, multigrid and Jacobi to a tolerance, and bytes per step "
        "against the copy bandwidth"};
    app.add_option("--sizes", options.sizes, "wind grids, each N (a cube) or XxYxZ")->expected(1, -1);
    app.add_option("--repeat", options.repeat, "timed steps per measurement (median is reported)")
        ->check(CLI::Range(1, 1000));
    app.add_option("--budget", options.budget_s,
                   "seconds of timed steps after which a measurement stops short of --repeat (at least one)")
        ->check(CLI::Range(0.0, 1e6));
    app.add_option("--solve-max-cells", options.solve_max_cells,
                   "largest grid, in cells, of the time-to-tolerance table")
        ->check(CLI::Range(std::uint64_t(1), std::uint64_t(256) * 256 * 256));
    app.add_option("--max-cycles", options.max_cycles, "frame-time table: V-cycles per frame at most")
        ->check(CLI::Range(1, 1000));
    const std::map<std::string, gust::Advection> advections{
        {"semi_lagrangian", gust::Advection::SemiLagrangian}, {"maccormack", gust::Advection::MacCormack}};
    app.add_option("--advection", options.advection, "semi_lagrangian or maccormack (SolverDesc::advection)")
        ->transform(CLI::CheckedTransformer(advections));
    app.add_option("--frame-cycles", options.frame_cycles,
                   "frame-budget table: V-cycles per frame, converged or not (0: leave the table out)")
        ->check(CLI::Range(0, 1000));
    app.add_option("--write", options.write, "Markdown file whose solver block is replaced (or appended)");
    app.add_option("--device", options.device, "Vulkan device index or name substring");
    CLI11_PARSE(app, argc, argv);
    const RunInfo run{command_line(argc, argv), utc_now(), load_average(), Clock::now()};

    std::vector<glm::uvec3> sizes;
    for (const std::string& text : options.sizes) {
        auto cells = parse_size(text);
        if (!cells) return fail(cells.message());
        gust::SolverDesc desc;
        desc.cells = *cells;
        if (gust::Status s = gust::validate(desc); !s) return fail("--sizes " + text + ": " + s.message());
        sizes.push_back(*cells);
    }

    gust::gpu::ContextDesc context;
    context.device = options.device;
    context.on_message = [](gust::gpu::Severity severity, const std::string& message) {
        if (severity != gust::gpu::Severity::Info) std::cerr << kTool << ": vulkan: " << message << "\n";
    };
    auto ctx = gust::gpu::Context::create(context);
    if (!ctx) return fail("cannot create a Vulkan context: " + ctx.message());
    if ((*ctx)->info().timestamp_period_ns <= 0.0f)
        return fail(std::string((*ctx)->info().name) +
                    " has no timestamps, and every table here is in GPU time");
    std::cerr << "device: " << (*ctx)->info().name << "\n";

    auto bandwidth = copy_bandwidth(**ctx, options.repeat);
    if (!bandwidth) return fail("copy bandwidth: " + bandwidth.message());
    std::cerr << "copy bandwidth: " << fmt_gbs(bandwidth->compute) << " GB/s by a compute shader, "
              << fmt_gbs(bandwidth->copy) << " GB/s by vkCmdCopyBuffer" << std::endl;

    gust::SolverDesc defaults;
    defaults.cell_size = kCellSize;
    defaults.max_cycles = options.max_cycles;
    defaults.advection = options.advection;
    std::vector<StepRow> steps;
    std::vector<SolveRow> solves;
    for (glm::uvec3 cells : sizes) {
        std::cerr << size_name(cells) << ":" << std::endl;
        gust::SolverDesc desc = defaults;
        desc.cells = cells;
        StepRow row;
        if (gust::Status s = run_frames(desc, options, 0, row); !s) row.error = s.message();
        if (row.error.empty())
            std::cerr << "  frame: " << fmt_ms(row.total()) << " ms GPU, " << fmt_ms(row.wall())
                      << " ms wall, " << row.cycles() << " V-cycles" << std::endl;
        else
            std::cerr << "  frames failed: " << row.error << std::endl;
        const bool stepped = row.error.empty();
        const std::int64_t last_frame = std::int64_t(kWarmupSteps + row.steps.size()) - 1;
        steps.push_back(std::move(row));
        if (!stepped) continue;
        if (cell_count(cells) > options.solve_max_cells) continue;
        // The solver alone, on the solids where the frames left them.
        auto scene = Scene::create(**ctx, desc);
        gust::Status placed = scene ? (*scene)->advance(last_frame) : scene.status();
        for (float tolerance : kTolerances) {
            if (!placed) {
                SolveRow failed;
                failed.cells = cells;
                failed.tolerance = tolerance;
                for (std::size_t i = 0; i < std::size(kContenders); ++i) {
                    failed.sides[i].solver = &kContenders[i];
                    failed.sides[i].error = placed.message();
                }
                solves.push_back(std::move(failed));
                continue;
            }
            SolveRow solve = bench_solve(**ctx, **scene, cells, tolerance, options.repeat, options.budget_s);
            for (const SolveSide& side : solve.sides) {
                std::cerr << "  " << side.solver->name << " to " << fmt_sci(tolerance) << ": ";
                if (!side.error.empty())
                    std::cerr << "failed: " << side.error << std::endl;
                else
                    std::cerr << grouped(side.search.stats.cycles)
                              << (side.search.stats.converged ? " (converged), " : " (not converged), ")
                              << fmt_s(side.search.wall_s) << " s at the generous cap"
                              << (side.timed.empty() ? "" : ", " + fmt_s(side.wall_s()) + " s capped")
                              << std::endl;
            }
            solves.push_back(std::move(solve));
        }
    }
    std::vector<StepRow> budget_rows;
    for (glm::uvec3 cells : options.frame_cycles > 0 ? sizes : std::vector<glm::uvec3>{}) {
        std::cerr << size_name(cells) << " at " << options.frame_cycles << " V-cycles a step:" << std::endl;
        gust::SolverDesc desc = defaults;
        desc.cells = cells;
        desc.max_cycles = options.frame_cycles;
        StepRow row;
        if (gust::Status s = run_frames(desc, options, options.frame_cycles, row); !s)
            row.error = s.message();
        budget_rows.push_back(std::move(row));
    }

    const std::string body =
        render(steps, solves, budget_rows, defaults, *bandwidth, options, (*ctx)->info(), run);
    std::cout << body << std::flush;
    if (!options.write.empty()) {
        if (gust::Status s =
                gust::bench::write_block(options.write, block_name(kBlock, (*ctx)->info()), body);
            !s)
            return fail(s.message());
        std::cerr << "wrote the solver block of " << options.write << "\n";
    }
    for (const StepRow& row : steps)
        if (!row.error.empty()) return fail(size_name(row.cells) + ": " + row.error);
    for (const SolveRow& row : solves)
        for (const SolveSide& r : row.sides)
            if (!r.error.empty()) return fail(size_name(row.cells) + " " + r.solver->name + ": " + r.error);
    return 0;
}
