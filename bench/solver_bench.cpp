// Measures the wind solver (docs/design.md "Wind solver"): GPU time per pass of one step at God of War's
// 32x16x32 grid and larger ones, the three pressure solvers (multigrid-preconditioned conjugate gradients,
// plain multigrid and the Jacobi baseline) to the same tolerance, and the bytes each pass moves against the
// device's copy bandwidth. The scene is solver_scene.hpp, the tables solver_report.cpp, the byte model
// traffic_model.cpp.
#include "solver_bench.hpp"

#include "gust_shaders/copy_comp.h"
#include "solver_scene.hpp"
#include "solver_setup.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <gust/gpu/buffer.hpp>
#include <iostream>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace gust::bench::solver {
namespace {

/// Names this tool in its error and Vulkan messages.
constexpr const char* kTool = "gust_bench_solver";
/// Names this bench's block in the results file (`<!-- bench:solver:begin -->`).
constexpr const char* kBlock = "solver";

/// Prints a fatal error under this tool's name and gives the exit status.
int fail(const std::string& message) {
    return gust::bench::fail(kTool, message);
}

/// Push constants of shaders/bench/copy.comp.
struct CopyPush {
    std::uint64_t source;
    std::uint64_t target;
    std::uint32_t count; ///< vec4s
};

/// Parses "N" (a cube) or "XxYxZ".
gust::Result<glm::uvec3> parse_size(const std::string& text) {
    glm::uvec3 cells(0);
    char tail = 0;
    if (std::sscanf(text.c_str(), "%ux%ux%u%c", &cells.x, &cells.y, &cells.z, &tail) == 3) return cells;
    if (std::sscanf(text.c_str(), "%u%c", &cells.x, &tail) == 1) return glm::uvec3(cells.x);
    return gust::Result<glm::uvec3>::failure("--sizes: \"" + text + "\" is neither N nor XxYxZ");
}

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
/// from a System holding them alone, then bench_frames on the whole scene; with `timeline`, one frame more
/// with its dispatches timed apart.
gust::Status run_frames(const gust::SolverDesc& desc, const Options& options, std::uint32_t cycles_per_step,
                        StepRow& row, bool timeline = false) {
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
    if (gust::Status s = bench_frames(**frames, options.repeat, options.budget_s, row); !s || !timeline)
        return s;
    if (gust::Status s = (*frames)->time_dispatches(true); !s) return s;
    auto wall = (*frames)->advance(kWarmupSteps + std::int64_t(row.steps.size()));
    if (!wall) return wall.status();
    row.timeline = (*frames)->stats().ms;
    return {};
}

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

} // namespace
} // namespace gust::bench::solver

/// Runs the three measurements per grid, prints the block and writes it where --write says.
int main(int argc, char** argv) {
    using namespace gust::bench;
    using namespace gust::bench::solver;
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
    app.add_option("--tolerance", options.tolerance,
                   "frame-time and frame-budget tables: the pressure solve's relative tolerance")
        ->check(CLI::Range(1e-7f, 1e-1f));
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
    defaults.tolerance = options.tolerance;
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
        if (gust::Status s = run_frames(desc, options, options.frame_cycles, row, true); !s)
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