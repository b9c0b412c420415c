// Reproduces the seed's first table (voxelization time against grid resolution for the 7.2M-triangle
// XYZRGB dragon) on this machine, beside OpenVDB's mesh-to-volume on the same triangles, grid and cores,
// with the memory each representation of the result takes.
#include "bench_common.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <gust/gpu/context.hpp>
#include <gust/scene/mesh.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <iostream>
#include <limits>
#include <memory>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <span>
#include <sstream>
#include <string>
#include <tbb/task_arena.h>
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
using gust::bench::load_asset;
using gust::bench::load_average;
using gust::bench::ms_since;
using gust::bench::RatioBelowTenth;
using gust::bench::RunInfo;
using gust::bench::usable_cores;
using gust::bench::utc_now;

/// Names this tool in its error and Vulkan messages.
constexpr const char* kTool = "gust_bench_voxelize";
/// Names this bench's block in the results file (`<!-- bench:voxelize:begin -->`).
constexpr const char* kBlock = "voxelize";

/// Prints a fatal error under this tool's name and gives the exit status.
int fail(const std::string& message) {
    return gust::bench::fail(kTool, message);
}

/// The seed's first table: seconds per voxelization of the XYZRGB dragon on an RTX 2070 Super, in ms.
constexpr std::pair<std::uint32_t, double> kSeedMs[] = {
    {64, 4.37}, {128, 4.40}, {256, 4.45}, {512, 4.57}, {1024, 4.82}};
constexpr std::uint64_t kSeedTriangles = 7219045;

/// What the command line asked for.
struct Options {
    std::filesystem::path assets = GUST_ASSETS_DIR;
    std::vector<std::uint32_t> res = {64, 128, 256, 512, 1024};
    int repeat = 3;
    int heavy_repeat = 0; ///< runs for the instanced dragon at 1024^3; 0 means `repeat`
    bool quick = false;
    std::string write;
    std::string device;
};

/// A mesh placed one or more times: what both the voxelizer and OpenVDB are given.
struct Scene {
    std::string label;             ///< table name, e.g. "dragon_full.glb x8"
    bool seed_mesh = false;        ///< stands in for the seed's XYZRGB dragon
    gust::Mesh mesh;               ///< mesh space
    std::vector<glm::mat4> models; ///< mesh space -> world space, one per instance
    std::uint64_t triangles() const { return std::uint64_t(mesh.triangle_count()) * models.size(); }
};

/// The same placed triangles in world space, as OpenVDB takes them.
struct WorldMesh {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
};

/// One gust path measured on one scene and grid.
struct GustTiming {
    std::string error;                 ///< empty when every run succeeded
    double wall_ms = 0.0;              ///< best wall-clock time around voxelize()
    double gpu_ms = -1.0;              ///< summed timestamp passes of the best run; < 0 without timestamps
    std::uint64_t fragments = 0;       ///< fragment list entries
    std::vector<std::uint32_t> voxels; ///< sorted unique voxel keys
    bool ok() const { return error.empty(); }
};

/// OpenVDB's mesh-to-volume measured on one scene and grid.
struct VdbTiming {
    std::string error;
    double ms = 0.0;          ///< best wall-clock time
    std::uint64_t active = 0; ///< active voxels of the band
    std::uint64_t bytes = 0;  ///< Grid::memUsage()
    bool ok() const { return error.empty(); }
};

/// One row of the tables.
struct Row {
    std::string mesh;
    bool seed_mesh = false;
    std::uint64_t triangles = 0;
    std::uint32_t res = 0;
    int runs = 0;
    GustTiming raster;
    GustTiming compute;
    VdbTiming vdb;
    std::uint64_t unique = 0; ///< voxels both paths produced (raster's when they differ)
    std::string agreement;    ///< "yes", "no (...)" or "n/a"
};

/// Eight copies of `mesh`, each centred in one octant of a cube twice its largest extent: the seed's
/// 7.2M-triangle XYZRGB dragon is not in assets/, so eight 871k-triangle dragons stand in for it.
std::vector<glm::mat4> octant_models(const gust::Mesh& mesh) {
    const auto [lo, hi] = gust::mesh_bounds(gust::view_of(mesh));
    const glm::vec3 centre = 0.5f * (lo + hi);
    const glm::vec3 extent = hi - lo;
    const float cell = std::max({extent.x, extent.y, extent.z});
    std::vector<glm::mat4> models;
    for (int i = 0; i < 8; ++i) {
        const glm::vec3 octant(float(i & 1) - 0.5f, float((i >> 1) & 1) - 0.5f, float((i >> 2) & 1) - 0.5f);
        models.push_back(glm::translate(glm::mat4(1.0f), octant * cell - centre));
    }
    return models;
}

/// Applies every instance transform once on the host so OpenVDB sees exactly the triangles the GPU does.
WorldMesh world_mesh(const Scene& scene) {
    WorldMesh world;
    const std::size_t vertices = scene.mesh.positions.size();
    world.points.reserve(vertices * scene.models.size());
    world.triangles.reserve(scene.mesh.triangle_count() * scene.models.size());
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (std::size_t m = 0; m < scene.models.size(); ++m) {
        for (const glm::vec3& p : scene.mesh.positions) {
            const glm::vec3 w = glm::vec3(scene.models[m] * glm::vec4(p, 1.0f));
            world.points.emplace_back(w.x, w.y, w.z);
        }
        const auto base = std::uint32_t(m * vertices);
        const std::vector<std::uint32_t>& idx = scene.mesh.indices;
        for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
            world.triangles.emplace_back(base + idx[t], base + idx[t + 1], base + idx[t + 2]);
            for (int k = 0; k < 3; ++k) {
                const openvdb::Vec3s& w = world.points[base + idx[t + std::size_t(k)]];
                lo = glm::min(lo, glm::vec3(w.x(), w.y(), w.z()));
                hi = glm::max(hi, glm::vec3(w.x(), w.y(), w.z()));
            }
        }
    }
    world.lo = lo;
    world.hi = hi;
    return world;
}

/// Best wall time of `runs` calls after one untimed warm-up, so that fragment-list growth and first
/// pipeline use are not counted; keeps the voxel set of the last call for the raster/compute check.
GustTiming time_gust(gust::Voxelizer& voxelizer, std::span<const gust::GpuInstance> instances,
                     const gust::GridDesc& grid, gust::VoxelizeMethod method, int runs) {
    GustTiming timing;
    for (int run = 0; run <= runs; ++run) {
        const auto start = Clock::now();
        auto stats = voxelizer.voxelize(instances, grid, method);
        const double ms = ms_since(start);
        if (!stats) {
            timing.error = stats.message();
            return timing;
        }
        if (run == 0 || (run > 1 && ms >= timing.wall_ms)) continue;
        timing.wall_ms = ms;
        timing.fragments = stats->fragments;
        timing.gpu_ms = -1.0;
        if (!stats->ms.empty()) {
            timing.gpu_ms = 0.0;
            for (const auto& pass : stats->ms)
                timing.gpu_ms += pass.second;
        }
    }
    auto fragments = voxelizer.read_fragments();
    if (!fragments) {
        timing.error = fragments.message();
        return timing;
    }
    timing.voxels = std::move(*fragments);
    std::sort(timing.voxels.begin(), timing.voxels.end());
    timing.voxels.erase(std::unique(timing.voxels.begin(), timing.voxels.end()), timing.voxels.end());
    return timing;
}

/// Best of `runs` OpenVDB unsigned distance fields with a one-voxel band, on the grid gust uses: voxel
/// size h and index (i,j,k) at the voxel centre origin + (i + 0.5) h, as docs/design.md's .vdb export maps
/// it.
VdbTiming time_openvdb(const WorldMesh& world, const gust::GridDesc& grid, int runs) {
    VdbTiming timing;
    try {
        auto transform = openvdb::math::Transform::createLinearTransform(double(grid.voxel_size));
        const glm::dvec3 centre0 = glm::dvec3(grid.origin) + 0.5 * double(grid.voxel_size);
        transform->postTranslate(openvdb::Vec3d(centre0.x, centre0.y, centre0.z));
        const std::vector<openvdb::Vec4I> quads;
        for (int run = 0; run < runs; ++run) {
            const auto start = Clock::now();
            auto sdf = openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(
                *transform, world.points, world.triangles, quads, 1.0f);
            const double ms = ms_since(start);
            if (run == 0 || ms < timing.ms) timing.ms = ms;
            timing.active = sdf->activeVoxelCount();
            timing.bytes = sdf->memUsage();
        }
    } catch (const std::exception& e) {
        timing.error = std::string("OpenVDB: ") + e.what();
    }
    return timing;
}

/// The seed's time for `res`, or a negative number where it has none.
double seed_ms(std::uint32_t res) {
    for (const auto& [r, ms] : kSeedMs)
        if (r == res) return ms;
    return -1.0;
}

/// The Markdown body of the results block: heading, method, machine, tables, notes and the seed comparison.
std::string render(const std::vector<Row>& rows, const Options& options, const gust::gpu::DeviceInfo& device,
                   const RunInfo& run) {
    std::ostringstream out;
    std::vector<std::string> notes;
    out << "## Voxelizer: time against grid resolution (seed table 1)" << heading_device(device) << "\n\n";
    out << "Command: `" << run.command << "`\n\n";
    out << "Machine: Vulkan device " << device.name << " (" << device.type << ", " << device.driver
        << "); CPU " << cpu_model() << ", " << usable_cores() << " usable cores, TBB arena of "
        << tbb::this_task_arena::max_concurrency() << " threads. Run started " << run.started << " and took "
        << fmt_ms(ms_since(run.start) / 60000.0) << " min; 1-minute load average " << run.load_start
        << " at the start and " << load_average()
        << " at the end (a load above the core count means other processes shared the cores).\n\n";
    out << "Each grid is the bounding box of all instances made cubic and padded by one voxel "
           "(`grid_around`). gust ms is wall-clock around one blocking `Voxelizer::voxelize()` call, best of "
           "the stated runs after one warm-up; GPU ms sums that run's timestamp passes. OpenVDB ms is "
           "`tools::meshToUnsignedDistanceField<FloatGrid>` with a one-voxel band on the same world-space "
           "triangles and grid transform, best of the stated runs, in the same process on the same cores. "
           "Ratios are OpenVDB ms over gust wall ms. The seed column is the seed report's RTX 2070 Super "
           "time for its " +
               grouped(kSeedTriangles) + "-triangle XYZRGB dragon.\n\n";

    out << "| Mesh | Triangles | Grid | Runs | Raster ms | Raster GPU ms | Compute ms | Compute GPU ms | "
           "OpenVDB ms | OpenVDB / raster | OpenVDB / compute | Seed ms |\n";
    out << "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    for (const Row& row : rows) {
        const std::string where = row.mesh + " at " + std::to_string(row.res) + "^3";
        const auto gust_cells = [&](const GustTiming& t, const char* path) {
            if (!t.ok()) return failed_cell(notes, where + ", " + path, t.error) + " | ";
            return fmt_ms(t.wall_ms) + " | " + (t.gpu_ms < 0.0 ? std::string("n/a") : fmt_ms(t.gpu_ms));
        };
        const auto ratio = [&](const GustTiming& t) {
            return t.ok() && row.vdb.ok() ? fmt_ratio(row.vdb.ms / t.wall_ms, RatioBelowTenth::TwoDecimals)
                                          : std::string("n/a");
        };
        const double seed = row.seed_mesh ? seed_ms(row.res) : -1.0;
        out << "| " << row.mesh << " | " << grouped(row.triangles) << " | " << row.res << "^3 | " << row.runs
            << " | " << gust_cells(row.raster, "raster") << " | " << gust_cells(row.compute, "compute")
            << " | "
            << (row.vdb.ok() ? fmt_ms(row.vdb.ms) : failed_cell(notes, where + ", OpenVDB", row.vdb.error))
            << " | " << ratio(row.raster) << " | " << ratio(row.compute) << " | "
            << (seed < 0.0 ? std::string("-") : fmt_ms(seed)) << " |\n";
    }

    out << "\nMemory: the dense grid at 4 bytes per voxel (as the seed counted its regular grid) and at 1 "
           "bit "
           "per voxel, the fragment list at 4 bytes per entry, and OpenVDB's band grid (`memUsage()`).\n\n";
    out << "| Mesh | Grid | Dense grid B | Bit grid B | Fragments (raster) | Fragment list B (raster) | "
           "Fragment list B (compute) | Unique voxels | Raster = compute | OpenVDB active voxels | "
           "OpenVDB grid B |\n";
    out << "|---|--:|--:|--:|--:|--:|--:|--:|---|--:|--:|\n";
    for (const Row& row : rows) {
        const std::uint64_t cells = std::uint64_t(row.res) * row.res * row.res;
        const auto list_bytes = [](const GustTiming& t) {
            return t.ok() ? grouped(t.fragments * sizeof(std::uint32_t)) : std::string("n/a");
        };
        out << "| " << row.mesh << " | " << row.res << "^3 | " << grouped(cells * 4) << " | "
            << grouped(cells / 8) << " | "
            << (row.raster.ok() ? grouped(row.raster.fragments) : std::string("n/a")) << " | "
            << list_bytes(row.raster) << " | " << list_bytes(row.compute) << " | "
            << (row.raster.ok() || row.compute.ok() ? grouped(row.unique) : std::string("n/a")) << " | "
            << row.agreement << " | " << (row.vdb.ok() ? grouped(row.vdb.active) : std::string("n/a"))
            << " | " << (row.vdb.ok() ? grouped(row.vdb.bytes) : std::string("n/a")) << " |\n";
    }

    const int heavy = options.heavy_repeat > 0 ? options.heavy_repeat : options.repeat;
    if (heavy != options.repeat)
        for (const Row& row : rows)
            if (row.runs != options.repeat) {
                notes.push_back("the instanced dragon at 1024^3 was run " + std::to_string(heavy) +
                                " time(s) per path instead of " + std::to_string(options.repeat) +
                                " (`--heavy-repeat`) to bound the total run time");
                break;
            }
    if (!notes.empty()) {
        out << "\nNotes:\n\n";
        for (std::size_t i = 0; i < notes.size(); ++i)
            out << i + 1 << ". " << notes[i] << "\n";
    }

    for (const Row& row : rows) {
        if (!row.seed_mesh || row.res != 512 || !row.raster.ok() || !row.compute.ok()) continue;
        out << "\nThe seed voxelized its " << grouped(kSeedTriangles)
            << "-triangle XYZRGB dragon at 512^3 in 4.57 ms on an RTX 2070 Super; here the "
            << grouped(row.triangles) << "-triangle instanced dragon took " << fmt_ms(row.raster.wall_ms)
            << " ms (raster) and " << fmt_ms(row.compute.wall_ms) << " ms (compute) on " << device.name
            << (device.type == "cpu" ? ", a CPU-emulated Vulkan device, so these numbers are not comparable"
                                     : ", a different device, so these numbers are not comparable")
            << " in absolute terms";
        if (row.vdb.ok())
            out << "; on the same cores OpenVDB took "
                << fmt_ratio(row.vdb.ms / row.raster.wall_ms, RatioBelowTenth::TwoDecimals)
                << " the raster time and "
                << fmt_ratio(row.vdb.ms / row.compute.wall_ms, RatioBelowTenth::TwoDecimals)
                << " the compute time (the goal is at least 10x)";
        out << ".\n";
    }
    return out.str();
}

/// Measures every resolution of one scene, printing progress to stderr as each cell starts and ends.
gust::Status bench_scene(gust::Voxelizer& voxelizer, const Scene& scene, const Options& options,
                         std::vector<Row>& rows) {
    auto uploaded = voxelizer.upload(gust::view_of(scene.mesh));
    if (!uploaded) return gust::Status::failure(scene.label + ": upload failed: " + uploaded.message());
    std::vector<gust::GpuInstance> instances;
    for (const glm::mat4& model : scene.models)
        instances.push_back({&*uploaded, model});
    const WorldMesh world = world_mesh(scene);

    for (std::uint32_t res : options.res) {
        Row row;
        row.mesh = scene.label;
        row.seed_mesh = scene.seed_mesh;
        row.triangles = scene.triangles();
        row.res = res;
        row.runs = scene.seed_mesh && res >= 1024 && options.heavy_repeat > 0 ? options.heavy_repeat
                                                                              : options.repeat;
        const gust::GridDesc grid = gust::grid_around(world.lo, world.hi, res);
        const std::string where = scene.label + " at " + std::to_string(res) + "^3";
        std::cerr << where << " (" << grouped(row.triangles) << " triangles, h = " << grid.voxel_size
                  << ", best of " << row.runs << "):" << std::endl;

        const auto report = [&](const char* path, const GustTiming& t) {
            if (t.ok())
                std::cerr << "  " << path << " " << fmt_ms(t.wall_ms) << " ms, " << grouped(t.fragments)
                          << " fragments, " << grouped(t.voxels.size()) << " voxels" << std::endl;
            else
                std::cerr << "  " << path << " failed: " << t.error << std::endl;
        };
        row.raster = time_gust(voxelizer, instances, grid, gust::VoxelizeMethod::Raster, row.runs);
        report("raster", row.raster);
        row.compute = time_gust(voxelizer, instances, grid, gust::VoxelizeMethod::Compute, row.runs);
        report("compute", row.compute);
        if (row.raster.ok() && row.compute.ok()) {
            row.unique = row.raster.voxels.size();
            row.agreement = row.raster.voxels == row.compute.voxels
                                ? "yes"
                                : "no (compute " + grouped(row.compute.voxels.size()) + ")";
        } else {
            row.unique = row.raster.ok() ? row.raster.voxels.size() : row.compute.voxels.size();
            row.agreement = "n/a";
        }
        row.raster.voxels = {};
        row.compute.voxels = {};

        row.vdb = time_openvdb(world, grid, row.runs);
        if (row.vdb.ok())
            std::cerr << "  openvdb " << fmt_ms(row.vdb.ms) << " ms, " << grouped(row.vdb.active)
                      << " active voxels" << std::endl;
        else
            std::cerr << "  openvdb failed: " << row.vdb.error << std::endl;
        rows.push_back(std::move(row));
    }
    return {};
}

} // namespace

int main(int argc, char** argv) {
    Options options;
    CLI::App app{"Voxelization time against grid resolution (the seed's first table), gust raster and "
                 "compute paths against OpenVDB on the same cores"};
    app.add_option("--assets", options.assets, "gust's assets folder")->check(CLI::ExistingDirectory);
    app.add_option("--res", options.res, "grid resolutions, comma separated")
        ->delimiter(',')
        ->check(CLI::Range(gust::kMinRes, gust::kMaxRes));
    app.add_option("--repeat", options.repeat, "timed runs per cell (best is reported)")
        ->check(CLI::Range(1, 1000));
    app.add_option("--heavy-repeat", options.heavy_repeat,
                   "timed runs for the instanced dragon at 1024^3 (default: --repeat)")
        ->check(CLI::Range(1, 1000));
    app.add_flag("--quick", options.quick, "smoke run: the bunny only, at 64, 128 and 256");
    app.add_option("--write", options.write, "Markdown file whose voxelize block is replaced (or appended)");
    app.add_option("--device", options.device, "Vulkan device index or name substring");
    CLI11_PARSE(app, argc, argv);
    const RunInfo run{command_line(argc, argv), utc_now(), load_average(), Clock::now()};
    if (options.quick && !app.count("--res")) options.res = {64, 128, 256};

    openvdb::initialize();
    gust::gpu::ContextDesc desc;
    desc.device = options.device;
    desc.on_message = [](gust::gpu::Severity severity, const std::string& message) {
        if (severity != gust::gpu::Severity::Info) std::cerr << kTool << ": vulkan: " << message << "\n";
    };
    auto ctx = gust::gpu::Context::create(desc);
    if (!ctx) return fail("cannot create a Vulkan context: " + ctx.message());
    auto voxelizer = gust::Voxelizer::create(**ctx);
    if (!voxelizer) return fail("cannot create the voxelizer: " + voxelizer.message());
    std::cerr << "device: " << (*ctx)->info().name << "\n";

    std::vector<Scene> scenes;
    if (!options.quick) {
        auto dragon = load_asset(options.assets, "scans/dragon_full.glb");
        if (!dragon) return fail(dragon.message());
        Scene scene{"dragon_full.glb x8", true, std::move(*dragon), {}};
        scene.models = octant_models(scene.mesh);
        scenes.push_back(std::move(scene));
    }
    auto bunny = load_asset(options.assets, "scans/bunny.ply");
    if (!bunny) return fail(bunny.message());
    scenes.push_back(Scene{"bunny.ply", false, std::move(*bunny), {glm::mat4(1.0f)}});

    std::vector<Row> rows;
    for (const Scene& scene : scenes)
        if (gust::Status s = bench_scene(**voxelizer, scene, options, rows); !s) return fail(s.message());

    const std::string body = render(rows, options, (*ctx)->info(), run);
    std::cout << body << std::flush;
    if (!options.write.empty()) {
        if (gust::Status s =
                gust::bench::write_block(options.write, block_name(kBlock, (*ctx)->info()), body);
            !s)
            return fail(s.message());
        std::cerr << "wrote the voxelize block of " << options.write << "\n";
    }
    for (const Row& row : rows)
        if (row.agreement.rfind("no", 0) == 0)
            return fail("raster and compute disagree on the voxel set of " + row.mesh + " at " +
                        std::to_string(row.res) + "^3");
    return 0;
}
