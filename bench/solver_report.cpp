// The results block of gust_bench_solver: the frame-time, time-to-tolerance, frame-budget and
// bytes-per-step tables from the rows the measurements filled, the last against the byte model
// (traffic_model.hpp).
#include "solver_bench.hpp"
#include "solver_scene.hpp"
#include "solver_setup.hpp"
#include "traffic_model.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace gust::bench::solver {

/// Median of `values` (mean of the middle two for an even count), the statistic every column reports.
double median(std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const std::size_t mid = values.size() / 2;
    return values.size() % 2 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
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

std::string fmt_gbs(double bytes_per_s) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.2f", bytes_per_s / 1e9);
    return text;
}

namespace {

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
    out << " Frame GPU ms | Wall ms | V-cycles | Dispatches | Stages | Converged "
           "|\n|--:|--:|--:|--:|--:|--:|--:|";
    for (std::size_t i = 0; i < std::size(kPasses); ++i)
        out << "--:|";
    out << "--:|--:|--:|--:|--:|---|\n";
    for (const StepRow& row : rows) {
        out << "| " << size_name(row.cells) << " | " << grouped(cell_count(row.cells)) << " | ";
        if (!row.error.empty()) {
            out << failed_cell(notes, size_name(row.cells) + " frames", row.error) << " |";
            for (std::size_t i = 0; i < std::size(kPasses) + 10; ++i)
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
            << grouped(last.dispatches) << " | " << grouped(last.stages) << " | " << converged << " of "
            << row.steps.size() << " |\n";
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
    out << "| Grid | Frames | `pressure` ms | Frame GPU ms | Wall ms | V-cycles | Dispatches | Stages | "
           "Submissions | Waits | Residual / divergence | Divergence after / before "
           "|\n|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
           "--:|\n";
    for (const StepRow& row : rows) {
        out << "| " << size_name(row.cells) << " | ";
        if (!row.error.empty()) {
            out << failed_cell(notes, size_name(row.cells) + " at the frame budget", row.error)
                << " | | | | | | | | | | |\n";
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
            << " | " << grouped(last.stages) << " | " << last.submissions << " | " << last.waits << " | "
            << fmt_sci(ratio([](const gust::FrameStats& f) { return f.residual; })) << " | "
            << fmt_sci(ratio([](const gust::FrameStats& f) { return f.divergence_after; })) << " |\n";
    }
    out << "\n";
}

/// Where each frame-budget row's GPU time goes: one frame more, every dispatch timed apart
/// (System::set_dispatch_timing), consecutive dispatches of one pipeline on one line.
void render_timeline(std::ostringstream& out, const std::vector<StepRow>& rows) {
    const auto timed =
        std::find_if(rows.begin(), rows.end(), [](const StepRow& r) { return !r.timeline.empty(); });
    if (timed == rows.end()) return;
    out << "### Where a frame's GPU time goes\n\n";
    out << "Each frame-budget row's scene for one frame more with every dispatch and draw timed apart "
           "(`System::set_dispatch_timing`): each time runs from the end of all the work before the dispatch "
           "to "
           "its own end, so the times add up to the frame (and a dispatch that overlaps the one before it "
           "shows only what it adds). Consecutive dispatches of one pipeline are summed on one line, with "
           "their "
           "count. Timestamps between dispatches cost a little themselves, so the total exceeds the frame "
           "table's.\n\n";
    for (const StepRow& row : rows) {
        if (row.timeline.empty()) continue;
        out << "**" << size_name(row.cells)
            << "**\n\n| # | Pipeline | Dispatches | GPU us | Share |\n"
               "|--:|---|--:|--:|--:|\n";
        const double total = summed(row.timeline);
        std::size_t line = 0;
        for (std::size_t i = 0; i < row.timeline.size();) {
            std::size_t j = i;
            double ms = 0.0;
            for (; j < row.timeline.size() && row.timeline[j].first == row.timeline[i].first; ++j)
                ms += row.timeline[j].second;
            out << "| " << ++line << " | " << row.timeline[i].first << " | " << j - i << " | "
                << fmt_ms(ms * 1000.0) << " | " << fmt_ms(total > 0.0 ? 100.0 * ms / total : 0.0) << " % |\n";
            i = j;
        }
        out << "| | **frame** | " << row.timeline.size() << " | " << fmt_ms(total * 1000.0) << " | |\n\n";
    }
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
           "table, emitters, the solver's state), shared-memory traffic (the smoothing's tiles, the coarse "
           "solve's levels) and the wind texture's texels are left out; the tree's live pools count once "
           "(traffic_model.hpp). The pressure pass (MGPCG) is the start (b, and with the warm start q = L "
           "phi "
           "with the sums b*q and q*q) plus, per iteration, the passes `WindSolver` records: the first "
           "smoothing at level 0 (the iterate x + alpha*p, its residual and the convergence check, then "
        << 2 * gust::SolverDesc{}.smoothing
        << " half-sweeps in 8^3 tiles), per level down to the coarse solve the next level's smoothing, which "
           "first restricts its right-hand side from the finer level's residual (computed there), the coarse "
           "solve (which restricts its own) of every level of at most "
        << grouped(gust::shaderio::kCoarseCells) << " cells in one workgroup ("
        << 2 * gust::detail::kCoarseSweeps
        << " half-sweeps on the coarsest), per level up the prolongation with its smoothing (at level 0 "
           "with the sums z*r and z*r_old), and conjugate gradients' direction p = z + beta*p with the sum "
           "of "
           "p*Lp; times the median V-cycles of the frame-time table. The project pass is the gradient with "
           "the first layer of the velocity's extension into closed faces, the second layer, and the step's "
           "end per cell (the pressure, its residual, the divergence after and the vorticity). "
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

} // namespace

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
    render_timeline(out, budget_rows);
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

} // namespace gust::bench::solver
