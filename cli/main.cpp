// The `gust` command line: voxelize, simulate, info.
#include "pipeline_cache.hpp"
#include "simulate.hpp"
#include "vdb_writer.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <gust/gpu/context.hpp>
#include <gust/scene/import.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

int fail(const std::string& message) {
    std::cerr << "gust: error: " << message << "\n";
    return 1;
}

/// Parses "x,y,z" into three finite floats.
bool parse_vec3(const std::string& text, glm::vec3& out) {
    std::istringstream in(text);
    char c1 = 0, c2 = 0;
    if (!(in >> out.x >> c1 >> out.y >> c2 >> out.z) || c1 != ',' || c2 != ',') return false;
    in >> std::ws;
    return in.eof() && std::isfinite(out.x) && std::isfinite(out.y) && std::isfinite(out.z);
}

/// Sorts packed voxel keys (30 bits) ascending and removes duplicates: a least-significant-digit radix sort,
/// three passes of 10 bits, since a fragment list holds millions of keys (several per voxel).
void sort_unique_keys(std::vector<std::uint32_t>& keys) {
    std::vector<std::uint32_t> scratch(keys.size());
    for (unsigned shift = 0; shift < 30; shift += 10) {
        std::vector<std::size_t> start(1025, 0);
        for (std::uint32_t key : keys)
            ++start[((key >> shift) & 1023u) + 1];
        for (std::size_t d = 1; d < start.size(); ++d)
            start[d] += start[d - 1];
        for (std::uint32_t key : keys)
            scratch[start[(key >> shift) & 1023u]++] = key;
        keys.swap(scratch);
    }
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

std::unique_ptr<gust::gpu::Context> make_context(const std::string& device, bool validation,
                                                 const std::string& pipeline_cache, std::string& error) {
    gust::gpu::ContextDesc desc;
    desc.device = device;
    desc.validation = validation;
    desc.pipeline_cache = pipeline_cache;
    desc.on_message = [](gust::gpu::Severity severity, const std::string& message) {
        if (severity != gust::gpu::Severity::Info) std::cerr << "gust: vulkan: " << message << "\n";
    };
    auto ctx = gust::gpu::Context::create(desc);
    if (!ctx) {
        error = ctx.message();
        return nullptr;
    }
    return std::move(ctx.value());
}

struct VoxelizeArgs {
    std::string mesh;
    std::uint32_t res = 0;
    std::string origin;
    std::optional<float> size;
    std::string method = "auto";
    std::string out;
    std::string device;
    bool validation = false;
    bool no_pipeline_cache = false;
};

int run_voxelize(const VoxelizeArgs& args) {
    nlohmann::ordered_json ms;
    auto start = Clock::now();
    gust::VoxelizeMethod method{};
    if (!gust::parse_method(args.method, method))
        return fail("--method must be raster, compute or auto, got '" + args.method + "'");
    if (args.res < gust::kMinRes || args.res > gust::kMaxRes)
        return fail("--res must be in [" + std::to_string(gust::kMinRes) + ", " +
                    std::to_string(gust::kMaxRes) + "]");
    if (args.origin.empty() != !args.size.has_value())
        return fail("--origin and --size go together (give both or neither)");

    std::cerr << "gust: loading " << args.mesh << "\n";
    auto mesh = gust::load_mesh(args.mesh);
    if (!mesh) return fail(mesh.message());
    ms["import"] = ms_since(start);

    gust::GridDesc grid;
    if (args.size) {
        grid.res = args.res;
        if (!parse_vec3(args.origin, grid.origin)) return fail("--origin must be three finite numbers X,Y,Z");
        if (!std::isfinite(*args.size) || *args.size <= 0.0f) return fail("--size must be finite and > 0");
        grid.voxel_size = *args.size / float(args.res);
    } else {
        const auto [lo, hi] = gust::mesh_bounds(gust::view_of(*mesh));
        grid = gust::grid_around(lo, hi, args.res);
        if (!std::isfinite(grid.voxel_size)) {
            return fail(args.mesh + ": its bounding box is too large for float coordinates (the voxel size " +
                        "overflows); give --origin and --size around the part to voxelize");
        }
    }
    if (gust::Status s = gust::validate_grid(grid); !s) {
        if (args.size) return fail("--origin and --size: " + s.message());
        return fail(args.mesh + ": the grid around its bounding box is invalid (" + s.message() +
                    "); give --origin and --size around the part to voxelize");
    }
    if (gust::Status s = gust::vdb::check_voxel_size(grid.voxel_size); !s) {
        return fail(args.mesh + ": " + s.message() + "; use a lower --res or a larger --size, or scale the " +
                    "mesh up");
    }

    std::string error;
    start = Clock::now();
    const std::string pipeline_cache = gust::cli::pipeline_cache_file(args.no_pipeline_cache);
    auto ctx = make_context(args.device, args.validation, pipeline_cache, error);
    if (!ctx) return fail(error);
    auto voxelizer = gust::Voxelizer::create(*ctx);
    if (!voxelizer) return fail(voxelizer.message());
    ms["device"] = ms_since(start);

    start = Clock::now();
    auto gpu_mesh = (*voxelizer)->upload(gust::view_of(*mesh));
    if (!gpu_mesh) return fail(args.mesh + ": " + gpu_mesh.message());
    ms["upload"] = ms_since(start);

    std::cerr << "gust: voxelizing " << mesh->triangle_count() << " triangles at " << args.res << "^3\n";
    start = Clock::now();
    const gust::GpuInstance instance{&*gpu_mesh, glm::mat4(1.0f)};
    auto stats = (*voxelizer)->voxelize({&instance, 1}, grid, method);
    if (!stats) return fail(stats.message());
    ms["voxelize"] = ms_since(start);
    nlohmann::ordered_json gpu_ms;
    for (const auto& [pass, t] : stats->ms)
        gpu_ms[std::string(pass)] = t;

    start = Clock::now();
    auto fragments = (*voxelizer)->read_fragments();
    if (!fragments) return fail(fragments.message());
    ms["readback"] = ms_since(start);
    start = Clock::now();
    std::vector<std::uint32_t>& keys = *fragments;
    sort_unique_keys(keys);
    ms["unique"] = ms_since(start);

    start = Clock::now();
    if (gust::Status s = gust::vdb::write_occupancy_vdb(args.out, keys, grid); !s) return fail(s.message());
    ms["write"] = ms_since(start);
    if (ctx->validation_messages() > 0)
        return fail(std::to_string(ctx->validation_messages()) +
                    " Vulkan validation messages; last: " + ctx->last_validation_message());
    // The cache only saves time: a run whose cache cannot be written is still a good run.
    const bool cache_saved = static_cast<bool>(ctx->save_pipeline_cache());

    nlohmann::ordered_json line;
    line["triangles"] = stats->triangles;
    line["rejected"] = stats->rejected;
    line["fragments"] = stats->fragments;
    line["voxels"] = keys.size();
    line["ms"] = ms;
    line["gpu_ms"] = gpu_ms;
    line["device"] = ctx->info().name;
    line["method"] = gust::to_string(stats->method);
    line["res"] = grid.res;
    line["voxel_size"] = grid.voxel_size;
    line["origin"] = {grid.origin.x, grid.origin.y, grid.origin.z};
    line["retries"] = stats->retries;
    line["fragment_bytes"] = stats->fragments * sizeof(std::uint32_t);
    line["dense_bytes"] = std::uint64_t(grid.res) * grid.res * grid.res;
    if (pipeline_cache.empty()) {
        line["pipeline_cache"] = nullptr;
    } else {
        line["pipeline_cache"] = {
            {"file", pipeline_cache}, {"loaded", ctx->pipeline_cache_loaded()}, {"saved", cache_saved}};
    }
    std::cout << line.dump() << std::endl;
    return 0;
}

int run_info(const std::string& mesh_path, const std::string& device) {
    nlohmann::ordered_json out;
    out["version"] = GUST_VERSION;
    std::string error;
    auto ctx = make_context(device, false, std::string(), error);
    if (!ctx) return fail(error);
    const auto& info = ctx->info();
    out["device"] = info.name;
    out["device_type"] = info.type;
    out["driver"] = info.driver;
    out["vulkan"] = std::to_string(VK_API_VERSION_MAJOR(info.api_version)) + "." +
                    std::to_string(VK_API_VERSION_MINOR(info.api_version)) + "." +
                    std::to_string(VK_API_VERSION_PATCH(info.api_version));
    out["conservative_rasterization"] = info.conservative_rasterization;
    out["timestamps"] = info.timestamp_period_ns > 0.0f;
    out["subgroup_size"] = info.subgroup_size;
    out["max_storage_buffer_range"] = info.max_storage_buffer_range;
    out["max_allocation_size"] = info.max_allocation_size;
    out["devices"] = ctx->device_names();
    if (!mesh_path.empty()) {
        auto mesh = gust::load_mesh(mesh_path);
        if (!mesh) return fail(mesh.message());
        glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
        std::uint64_t non_finite = 0;
        for (const glm::vec3& p : mesh->positions) {
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
                ++non_finite;
                continue;
            }
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        nlohmann::ordered_json m;
        m["path"] = mesh_path;
        m["vertices"] = mesh->positions.size();
        m["triangles"] = mesh->triangle_count();
        m["non_finite_vertices"] = non_finite;
        if (lo.x <= hi.x) m["bbox"] = {{lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z}};
        out["mesh"] = m;
    }
    std::cout << out.dump(2) << std::endl;
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"gust: GPU voxelization and wind for games"};
    app.require_subcommand(1);

    VoxelizeArgs vox;
    auto* voxelize =
        app.add_subcommand("voxelize", "voxelize a mesh (PLY, OBJ, STL, glTF, GLB) into an OpenVDB file");
    voxelize->add_option("mesh", vox.mesh, "mesh file")->required();
    voxelize->add_option("--res", vox.res, "voxels per axis (8..1024)")->required();
    voxelize->add_option("--origin", vox.origin, "grid min corner X,Y,Z (world units); with --size");
    voxelize->add_option("--size", vox.size,
                         "grid edge length (world units); voxel size = size / res; with --origin");
    voxelize->add_option("--method", vox.method, "raster, compute or auto (default auto)");
    voxelize->add_option("--out", vox.out, "output .vdb file")->required();
    voxelize->add_option("--device", vox.device,
                         "device index or name substring (default: $GUST_DEVICE, then best)");
    voxelize->add_flag("--validation", vox.validation,
                       "enable the Vulkan validation layer; any message fails");
    voxelize->add_flag("--no-pipeline-cache", vox.no_pipeline_cache,
                       "neither read nor write the pipeline cache file (also: GUST_PIPELINE_CACHE=off)");

    gust::cli::SimulateArgs sim;
    auto* simulate =
        app.add_subcommand("simulate", "run a scene file headless, writing stats.jsonl and OpenVDB frames");
    simulate->add_option("scene", sim.scene, "scene file (JSON, docs/scene-format.md)")->required();
    simulate->add_option("--frames", sim.frames, "frames to run")->required();
    simulate->add_option("--out", sim.out, "output folder")->required();
    simulate->add_option("--every", sim.every, "also write every K-th frame's VDB (frame 0 always)");
    simulate->add_option("--method", sim.method, "raster, compute or auto (default auto)");
    simulate->add_option("--device", sim.device, "device index or name substring");
    simulate->add_flag("--validation", sim.validation,
                       "enable the Vulkan validation layer; any message fails");
    simulate->add_flag("--no-pipeline-cache", sim.no_pipeline_cache,
                       "neither read nor write the pipeline cache file (also: GUST_PIPELINE_CACHE=off)");

    std::string info_mesh, info_device;
    auto* info = app.add_subcommand("info", "print the Vulkan device gust picks (and a mesh's statistics)");
    info->add_option("mesh", info_mesh, "optional mesh file to describe");
    info->add_option("--device", info_device, "device index or name substring");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help prints the usage and succeeds; every other parse error is ours to report.
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
        return fail(std::string(e.what()) + " (see gust --help)");
    }
    if (voxelize->parsed()) return run_voxelize(vox);
    if (simulate->parsed()) return gust::cli::run_simulate(sim);
    return run_info(info_mesh, info_device);
}
