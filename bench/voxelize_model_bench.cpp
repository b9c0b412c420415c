// Calibrates the cost model that `auto` picks a voxelizer path with (voxelize_cost.hpp): times both
// paths on meshes of every kind in assets/ at several grid sizes, sets the times beside the work the
// model predicts from the triangles' sizes, reports how often the model's pick is the faster path and
// what a wrong pick costs, and fits the coefficients anew from this run's times.
#include "bench_common.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <gust/gpu/context.hpp>
#include <gust/scene/mesh.hpp>
#include <gust/voxelizer/voxelize_cost.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

using gust::bench::Clock;
using gust::bench::fmt_ms;
using gust::bench::fmt_ratio;
using gust::bench::grouped;
using gust::bench::ms_since;

constexpr const char* kTool = "gust_bench_voxelize_model";
/// Names this bench's block in the results file (`<!-- bench:voxelize-model:begin -->`).
constexpr const char* kBlock = "voxelize-model";

int fail(const std::string& message) {
    return gust::bench::fail(kTool, message);
}

struct Options {
    std::filesystem::path assets = GUST_ASSETS_DIR;
    std::vector<std::string> meshes = {"scenes/wall.obj",           "architecture/building-small-c.glb",
                                       "foliage/tree_detailed.glb", "characters/Fox.glb",
                                       "scans/bunny.ply",           "characters/CesiumMan.glb",
                                       "scans/dragon_res3.ply",     "scans/bunny_full.ply",
                                       "scans/dragon_res2.ply",     "scans/dragon_full.glb"};
    std::vector<std::uint32_t> res = {64, 128, 256, 512, 1024};
    int repeat = 3;
    std::string write;
    std::string device;
};

/// One mesh on one grid: the model's inputs and outputs beside the measured times.
struct Row {
    std::string mesh;
    std::uint32_t res = 0;
    gust::VoxelizeWork work;
    double mean_size = 0.0;      ///< side of a square of the mean projected triangle area, voxels
    std::uint64_t fragments = 0; ///< measured (the compute path's list)
    double ms[2] = {0.0, 0.0};   ///< best wall ms: raster, compute
    gust::PathCosts predicted;   ///< by the library's model
    gust::VoxelizeMethod pick{}; ///< the library's model's pick
    double cost_of(gust::VoxelizeMethod m) const { return ms[m == gust::VoxelizeMethod::Raster ? 0 : 1]; }
    double best() const { return std::min(ms[0], ms[1]); }
};

/// Best wall time of `runs` calls after one untimed warm-up (list growth, first use of the pipelines).
gust::Result<double> time_path(gust::Voxelizer& voxelizer, const gust::GpuInstance& instance,
                               const gust::GridDesc& grid, gust::VoxelizeMethod method, int runs,
                               std::uint64_t& fragments) {
    double best = 0.0;
    for (int run = 0; run <= runs; ++run) {
        const auto start = Clock::now();
        auto stats = voxelizer.voxelize({&instance, 1}, grid, method);
        const double ms = ms_since(start);
        if (!stats) return stats.status();
        fragments = stats->fragments;
        if (run == 1 || (run > 1 && ms < best)) best = ms;
    }
    return best;
}

/// Least squares with non-negative coefficients for three unknowns, relative to each row's time (so
/// that small grids weigh as much as large ones): the best of the exact fits over every subset of the
/// unknowns whose solution is non-negative.
gust::PathCoefficients fit(const std::vector<std::array<double, 3>>& x, const std::vector<double>& y) {
    gust::PathCoefficients best_fit;
    double best_error = HUGE_VAL;
    for (int mask = 1; mask < 8; ++mask) {
        int used[3], n = 0;
        for (int j = 0; j < 3; ++j)
            if (mask & (1 << j)) used[n++] = j;
        double a[3][4] = {};
        for (std::size_t i = 0; i < x.size(); ++i) {
            const double w = 1.0 / (y[i] * y[i]);
            for (int r = 0; r < n; ++r) {
                for (int c = 0; c < n; ++c)
                    a[r][c] += w * x[i][used[r]] * x[i][used[c]];
                a[r][n] += w * x[i][used[r]] * y[i];
            }
        }
        // Gauss-Jordan elimination with partial pivoting on the n x n normal equations.
        bool singular = false;
        for (int c = 0; c < n && !singular; ++c) {
            int pivot = c;
            for (int r = c + 1; r < n; ++r)
                if (std::abs(a[r][c]) > std::abs(a[pivot][c])) pivot = r;
            if (std::abs(a[pivot][c]) < 1e-300) {
                singular = true;
                break;
            }
            for (int k = 0; k <= n; ++k)
                std::swap(a[c][k], a[pivot][k]);
            for (int r = 0; r < n; ++r) {
                if (r == c) continue;
                const double f = a[r][c] / a[c][c];
                for (int k = c; k <= n; ++k)
                    a[r][k] -= f * a[c][k];
            }
        }
        if (singular) continue;
        double coefficient[3] = {0.0, 0.0, 0.0};
        bool negative = false;
        for (int r = 0; r < n; ++r) {
            coefficient[used[r]] = a[r][n] / a[r][r];
            negative = negative || coefficient[used[r]] < 0.0;
        }
        if (negative) continue;
        double error = 0.0;
        for (std::size_t i = 0; i < x.size(); ++i) {
            const double p = coefficient[0] * x[i][0] + coefficient[1] * x[i][1] + coefficient[2] * x[i][2];
            error += (p - y[i]) * (p - y[i]) / (y[i] * y[i]);
        }
        if (error < best_error) {
            best_error = error;
            best_fit = {coefficient[0], coefficient[1], coefficient[2]};
        }
    }
    return best_fit;
}

/// Both paths' coefficients fitted to this run's times.
gust::CostModel fit_model(const std::vector<Row>& rows) {
    std::vector<std::array<double, 3>> raster_x, compute_x;
    std::vector<double> raster_y, compute_y;
    for (const Row& row : rows) {
        raster_x.push_back({1.0, row.work.triangles, row.work.pixels});
        raster_y.push_back(row.ms[0]);
        compute_x.push_back({1.0, row.work.triangles, row.work.columns});
        compute_y.push_back(row.ms[1]);
    }
    return {fit(raster_x, raster_y), fit(compute_x, compute_y)};
}

std::string coefficients(const gust::CostModel& model) {
    std::ostringstream out;
    out.precision(3);
    out << "raster " << model.raster.fixed_ms << " ms + " << model.raster.per_triangle_ms * 1e6
        << " ns per triangle + " << model.raster.per_item_ms * 1e6 << " ns per pixel; compute "
        << model.compute.fixed_ms << " ms + " << model.compute.per_triangle_ms * 1e6 << " ns per triangle + "
        << model.compute.per_item_ms * 1e6 << " ns per column";
    return out.str();
}

/// How a model's picks fare against the measured times.
struct Verdict {
    int right = 0;           ///< rows where it picked the faster path
    double worst = 1.0;      ///< largest picked / best ratio
    double picked_ms = 0.0;  ///< sum of the picked paths' times
    double best_ms = 0.0;    ///< sum of the faster paths' times
    double compute_ms = 0.0; ///< sum of the compute path's times (always compute)
};

Verdict judge(const std::vector<Row>& rows, const gust::CostModel& model) {
    Verdict v;
    for (const Row& row : rows) {
        const gust::PathCosts p = model.predict(row.work);
        const double picked = p.raster_ms < p.compute_ms ? row.ms[0] : row.ms[1];
        v.right += picked == row.best();
        v.worst = std::max(v.worst, picked / row.best());
        v.picked_ms += picked;
        v.best_ms += row.best();
        v.compute_ms += row.ms[1];
    }
    return v;
}

std::string render(const std::vector<Row>& rows, const gust::gpu::DeviceInfo& device,
                   const gust::bench::RunInfo& run, int repeat) {
    std::ostringstream out;
    out << "## Voxelizer: the cost model of `auto`" << gust::bench::heading_device(device) << "\n\n";
    out << "Command: `" << run.command << "`\n\n";
    out << "Machine: Vulkan device " << device.name << " (" << device.type << ", " << device.driver
        << "); CPU " << gust::bench::cpu_model() << ", " << gust::bench::usable_cores()
        << " usable cores. Run started " << run.started << " and took "
        << fmt_ms(ms_since(run.start) / 60000.0) << " min; 1-minute load average " << run.load_start
        << " at the start and " << gust::bench::load_average()
        << " at the end (a load above the core count means other processes shared the cores).\n\n";
    out << "Each mesh is voxelized alone on the grid around it (`grid_around`). Raster and compute ms are "
           "wall-clock around one blocking `Voxelizer::voxelize()` call, best of "
        << repeat
        << " after one warm-up. The work columns are the model's inputs (voxelize_cost.hpp): mean "
           "triangle is the side of a square of the mean projected triangle area in voxels; columns are "
           "what the compute path walks, pixels what the raster path shades, fragments the expected "
           "length of the fragment list (beside the measured one). Predicted ms use the coefficients "
           "compiled into gust for this device type; `auto` picks the lower, and auto / best is the time "
           "of its pick over the faster path's.\n\n";
    out << "| Mesh | Triangles | Grid | Mean triangle | Columns | Pixels | Fragments expected | Fragments | "
           "Raster ms | Compute ms | Predicted raster | Predicted compute | auto | auto / best |\n";
    out << "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|---|--:|\n";
    for (const Row& row : rows) {
        out << "| " << row.mesh << " | " << grouped(std::uint64_t(row.work.triangles)) << " | " << row.res
            << "^3 | " << fmt_ms(row.mean_size) << " | " << grouped(std::uint64_t(row.work.columns)) << " | "
            << grouped(std::uint64_t(row.work.pixels)) << " | " << grouped(std::uint64_t(row.work.fragments))
            << " | " << grouped(row.fragments) << " | " << fmt_ms(row.ms[0]) << " | " << fmt_ms(row.ms[1])
            << " | " << fmt_ms(row.predicted.raster_ms) << " | " << fmt_ms(row.predicted.compute_ms) << " | "
            << gust::to_string(row.pick) << " | " << fmt_ratio(row.cost_of(row.pick) / row.best()) << " |\n";
    }
    const gust::CostModel& used = gust::cost_model(device);
    const gust::CostModel fitted = fit_model(rows);
    const auto summary = [&](const char* name, const gust::CostModel& model) {
        const Verdict v = judge(rows, model);
        out << "- " << name << ": " << coefficients(model) << ". It picks the faster path in " << v.right
            << " of " << rows.size() << " rows; its picks take " << fmt_ratio(v.picked_ms / v.best_ms)
            << " the time of always the faster path (always compute: " << fmt_ratio(v.compute_ms / v.best_ms)
            << "), and its worst pick " << fmt_ratio(v.worst) << ".\n";
    };
    out << "\n";
    summary("Compiled into gust", used);
    summary("Fitted to this run (least squares relative to each time, coefficients >= 0)", fitted);
    return out.str();
}

} // namespace

int main(int argc, char** argv) {
    Options options;
    CLI::App app{"Times both voxelizer paths on meshes of every kind and grid sizes, beside the work the "
                 "cost model of `auto` predicts, and fits its coefficients"};
    app.add_option("--assets", options.assets, "gust's assets folder")->check(CLI::ExistingDirectory);
    app.add_option("--meshes", options.meshes, "meshes under the assets folder, comma separated")
        ->delimiter(',');
    app.add_option("--res", options.res, "grid resolutions, comma separated")
        ->delimiter(',')
        ->check(CLI::Range(gust::kMinRes, gust::kMaxRes));
    app.add_option("--repeat", options.repeat, "timed runs per path (best is reported)")
        ->check(CLI::Range(1, 1000));
    app.add_option("--write", options.write,
                   "Markdown file whose voxelize-model block is replaced (or appended)");
    app.add_option("--device", options.device, "Vulkan device index or name substring");
    CLI11_PARSE(app, argc, argv);
    const gust::bench::RunInfo run{gust::bench::command_line(argc, argv), gust::bench::utc_now(),
                                   gust::bench::load_average(), Clock::now()};

    gust::gpu::ContextDesc desc;
    desc.device = options.device;
    desc.on_message = [](gust::gpu::Severity severity, const std::string& message) {
        if (severity != gust::gpu::Severity::Info) std::cerr << kTool << ": vulkan: " << message << "\n";
    };
    auto ctx = gust::gpu::Context::create(desc);
    if (!ctx) return fail("cannot create a Vulkan context: " + ctx.message());
    auto voxelizer = gust::Voxelizer::create(**ctx);
    if (!voxelizer) return fail("cannot create the voxelizer: " + voxelizer.message());
    const gust::CostModel& model = gust::cost_model((*ctx)->info());
    std::cerr << "device: " << (*ctx)->info().name << "\n";

    std::vector<Row> rows;
    for (const std::string& name : options.meshes) {
        auto mesh = gust::bench::load_asset(options.assets, name);
        if (!mesh) return fail(mesh.message());
        auto uploaded = (*voxelizer)->upload(gust::view_of(*mesh));
        if (!uploaded) return fail(name + ": upload failed: " + uploaded.message());
        const gust::GpuInstance instance{&*uploaded, glm::mat4(1.0f)};
        const auto [lo, hi] = gust::mesh_bounds(gust::view_of(*mesh));
        for (std::uint32_t res : options.res) {
            Row row;
            row.mesh = std::filesystem::path(name).filename().string();
            row.res = res;
            const gust::GridDesc grid = gust::grid_around(lo, hi, res);
            row.work = gust::voxelize_work(uploaded->sizes(), instance.model, grid);
            const double scale = 1.0 / double(grid.voxel_size);
            row.mean_size = std::sqrt(scale * scale * uploaded->sizes().projected_area /
                                      std::max(1.0, row.work.triangles));
            row.predicted = model.predict(row.work);
            row.pick = row.predicted.raster_ms < row.predicted.compute_ms ? gust::VoxelizeMethod::Raster
                                                                          : gust::VoxelizeMethod::Compute;
            const gust::VoxelizeMethod paths[2] = {gust::VoxelizeMethod::Raster,
                                                   gust::VoxelizeMethod::Compute};
            for (int p = 0; p < 2; ++p) {
                auto ms = time_path(**voxelizer, instance, grid, paths[p], options.repeat, row.fragments);
                if (!ms) return fail(name + " at " + std::to_string(res) + "^3: " + ms.message());
                row.ms[p] = *ms;
            }
            std::cerr << row.mesh << " at " << res << "^3: raster " << fmt_ms(row.ms[0]) << " ms, compute "
                      << fmt_ms(row.ms[1]) << " ms; predicted " << fmt_ms(row.predicted.raster_ms) << " and "
                      << fmt_ms(row.predicted.compute_ms) << " ms; fragments " << grouped(row.fragments)
                      << " (expected " << grouped(std::uint64_t(row.work.fragments)) << ")" << std::endl;
            rows.push_back(row);
        }
    }

    const std::string body = render(rows, (*ctx)->info(), run, options.repeat);
    std::cout << body << std::flush;
    if (!options.write.empty()) {
        if (gust::Status s = gust::bench::write_block(options.write,
                                                      gust::bench::block_name(kBlock, (*ctx)->info()), body);
            !s)
            return fail(s.message());
        std::cerr << "wrote the " << kBlock << " block of " << options.write << "\n";
    }
    return 0;
}
