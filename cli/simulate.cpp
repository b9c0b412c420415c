#include "simulate.hpp"

#include "pipeline_cache.hpp"
#include "vdb_writer.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <gust/gpu/context.hpp>
#include <gust/scene/domain_grid.hpp>
#include <gust/scene/scene_runtime.hpp>
#include <gust/solver/wind_solver.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

namespace gust::cli {

namespace {

int fail(const std::string& message) {
    std::cerr << "gust: error: " << message << "\n";
    return 1;
}

std::string frame_file(std::uint64_t frame) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04llu.vdb", static_cast<unsigned long long>(frame));
    return name;
}

/// The scene's emitters at time t (motors moved along their paths).
std::vector<Emitter> emitters_at(const SceneDesc& scene, double t) {
    std::vector<Emitter> out;
    for (const EmitterDesc& e : scene.emitters) {
        Emitter emitter;
        emitter.type = e.type == "directional" ? EmitterType::Directional
                       : e.type == "omni"      ? EmitterType::Omni
                       : e.type == "vortex"    ? EmitterType::Vortex
                       : e.shape == "cone"     ? EmitterType::ConeMotor
                                               : EmitterType::CapsuleMotor;
        emitter.position = emitter_position(e, t);
        emitter.direction = e.direction;
        emitter.radius = e.radius;
        emitter.strength = e.strength;
        emitter.falloff = e.falloff;
        emitter.length = e.type == "motor" ? e.length : 0.0f;
        out.push_back(emitter);
    }
    return out;
}

} // namespace

int run_simulate(const SimulateArgs& args) {
    namespace fs = std::filesystem;
    VoxelizeMethod method{};
    if (!parse_method(args.method, method))
        return fail("--method must be raster, compute or auto, got '" + args.method + "'");
    if (args.frames == 0) return fail("--frames must be at least 1");
    auto scene = load_scene(args.scene);
    if (!scene) return fail(scene.message());
    auto runtime = SceneRuntime::load(*scene);
    if (!runtime) return fail(runtime.message());
    auto grid = domain_grid(scene->domain);
    if (!grid) return fail(args.scene + ": domain: " + grid.message());

    std::error_code ec;
    fs::create_directories(args.out, ec);
    if (ec) return fail(args.out + ": cannot create the output folder: " + ec.message());
    std::ofstream stats_file(fs::path(args.out) / "stats.jsonl");
    if (!stats_file) return fail(args.out + "/stats.jsonl: cannot open for writing");

    gpu::ContextDesc ctx_desc;
    ctx_desc.device = args.device;
    ctx_desc.validation = args.validation;
    ctx_desc.pipeline_cache = pipeline_cache_file(args.no_pipeline_cache);
    ctx_desc.on_message = [](gpu::Severity severity, const std::string& message) {
        if (severity != gpu::Severity::Info) std::cerr << "gust: vulkan: " << message << "\n";
    };
    auto ctx = gpu::Context::create(ctx_desc);
    if (!ctx) return fail(ctx.message());

    WorldDesc world_desc;
    world_desc.grid = *grid;
    world_desc.method = method;
    world_desc.tree.branching = scene->domain.branching;
    world_desc.tree.hysteresis = scene->domain.hysteresis;
    auto world = VoxelWorld::create(**ctx, world_desc);
    if (!world) return fail(world.message());
    auto wind = WindSolver::create(**ctx, solver_desc(*scene));
    if (!wind) return fail(args.scene + ": " + wind.message());
    if (Status s = (*wind)->set_ambient(scene->ambient_velocity); !s)
        return fail(args.scene + ": ambient: " + s.message());

    // Objects showing the same mesh share one device copy (and one `auto` measurement); deforming
    // objects get their own, since their vertex buffers change every frame.
    const std::size_t count = runtime->object_count();
    std::vector<GpuMesh> uploaded;
    uploaded.reserve(count);
    std::vector<std::size_t> slot(count);
    std::map<const Mesh*, std::size_t> shared;
    for (std::size_t i = 0; i < count; ++i) {
        const Mesh& source = runtime->mesh(i);
        if (!runtime->deforms(i))
            if (const auto it = shared.find(&source); it != shared.end()) {
                slot[i] = it->second;
                continue;
            }
        auto mesh = (*world)->upload(view_of(source));
        if (!mesh) return fail(scene->objects[i].mesh.string() + ": " + mesh.message());
        slot[i] = uploaded.size();
        if (!runtime->deforms(i)) shared.emplace(&source, slot[i]);
        uploaded.push_back(std::move(*mesh));
    }
    const auto mesh_of = [&](std::size_t object) -> GpuMesh& { return uploaded[slot[object]]; };
    const double dt = scene->dt;
    std::vector<GpuInstance> statics;
    for (std::size_t i = 0; i < count; ++i)
        if (scene->objects[i].is_static) statics.push_back({&mesh_of(i), runtime->model(i, 0.0)});
    (*world)->set_static(statics);
    // The pose one frame before the first, so that frame 0's velocities are those of the motion.
    for (std::size_t i = 0; i < count; ++i)
        if (runtime->deforms(i))
            if (Status s = (*world)->update_positions(mesh_of(i), runtime->positions(i, -dt)); !s)
                return fail(s.message());

    std::cerr << "gust: simulating " << args.frames << " frames of " << args.scene << " (" << grid->res
              << "^3 voxels, " << (*ctx)->info().name << ")\n";
    const auto start = std::chrono::steady_clock::now();
    for (std::uint64_t frame = 0; frame < args.frames; ++frame) {
        const double t = double(frame) * dt;
        const gpu::WorkCounts before = (*ctx)->work();
        std::vector<GpuInstance> dynamic;
        for (std::size_t i = 0; i < count; ++i) {
            if (scene->objects[i].is_static) continue;
            if (runtime->deforms(i))
                if (Status s = (*world)->update_positions(mesh_of(i), runtime->positions(i, t)); !s)
                    return fail(s.message());
            GpuInstance inst{&mesh_of(i), runtime->model(i, t)};
            inst.prev_model = runtime->model(i, t - dt);
            inst.teleport = runtime->jumps(i, t - dt, t);
            dynamic.push_back(inst);
        }
        auto step = (*world)->step(dynamic, float(dt));
        if (!step) return fail("frame " + std::to_string(frame) + ": " + step.message());
        const std::vector<Emitter> emitters = emitters_at(*scene, t);
        if (Status s = (*wind)->set_emitters(emitters); !s) return fail(args.scene + ": " + s.message());
        const SolidSource solid = solid_source(**world);
        auto air = (*wind)->step(float(dt), &solid);
        if (!air) return fail("frame " + std::to_string(frame) + ": wind: " + air.message());

        nlohmann::ordered_json line;
        const TreeStats& tree = step->tree;
        const std::uint64_t fragments = step->static_voxelize.fragments + step->dynamic_voxelize.fragments;
        line["frame"] = frame;
        line["time"] = t;
        line["fragments"] = fragments;
        line["voxels"] = tree.voxels;
        line["nodes"] = tree.nodes;
        line["refined"] = tree.refined;
        line["coarsened"] = tree.coarsened;
        line["pool_bytes"] = tree.pool_bytes;
        // Keys (4 bytes) of both lists, plus velocities (8 bytes) of the dynamic list.
        line["fragment_bytes"] = fragments * 4 + step->dynamic_voxelize.fragments * 8;
        line["dense_bytes"] = std::uint64_t(grid->res) * grid->res * grid->res * 4;
        nlohmann::ordered_json ms;
        for (const auto& [pass, value] : step->ms)
            ms[std::string(pass)] = value;
        for (const auto& [pass, value] : air->ms)
            ms["wind_" + std::string(pass)] = value;
        line["ms"] = ms;
        const gpu::WorkCounts& after = (*ctx)->work();
        line["dispatches"] = after.dispatches - before.dispatches;
        line["submissions"] = after.submissions - before.submissions;
        line["waits"] = after.waits - before.waits;
        line["divergence_before"] = air->divergence_before;
        line["divergence_after"] = air->divergence_after;
        line["residual"] = air->residual;
        line["cycles"] = air->cycles;
        line["converged"] = air->converged;
        line["cut_cells"] = air->cut_cells;
        line["fluid_cells"] = air->fluid_cells;
        line["sealed_cells"] = air->sealed_cells;
        line["diverged"] = air->diverged;
        line["nodes_per_level"] = tree.nodes_per_level;
        line["exhausted"] = tree.exhausted;
        line["pool_growths"] = step->pool_growths;
        line["free_node_blocks"] = tree.free_node_blocks;
        line["free_mask_blocks"] = tree.free_mask_blocks;
        line["static_rebuilt"] = step->static_rebuilt;
        line["rejected"] = step->static_voxelize.rejected + step->dynamic_voxelize.rejected;
        stats_file << line.dump() << "\n";

        if (frame == 0 || (args.every > 0 && frame % args.every == 0)) {
            auto voxels = (*world)->tree().leaf_voxels();
            if (!voxels) return fail(voxels.message());
            auto velocity = (*wind)->read_cell_velocity();
            auto solid_fraction = (*wind)->read_solid_fraction();
            auto pressure = (*wind)->read_pressure();
            if (!velocity || !solid_fraction || !pressure)
                return fail("frame " + std::to_string(frame) + ": wind readback failed");
            vdb::WindGrids grids{scene->domain.cells, scene->domain.cell_size,
                                 (*wind)->origin(),   *solid_fraction,
                                 *velocity,           *pressure};
            const fs::path path = fs::path(args.out) / frame_file(frame);
            if (Status s = vdb::write_frame_vdb(path, *voxels, *grid, grids); !s) return fail(s.message());
        }
        if ((frame + 1) % std::max<std::uint64_t>(1, args.frames / 10) == 0 || frame + 1 == args.frames) {
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            std::cerr << "gust: frame " << frame + 1 << "/" << args.frames << " (" << seconds << " s)\n";
        }
    }
    stats_file.flush();
    if (!stats_file) return fail(args.out + "/stats.jsonl: write failed");
    if ((*ctx)->validation_messages() > 0)
        return fail(std::to_string((*ctx)->validation_messages()) +
                    " Vulkan validation messages; last: " + (*ctx)->last_validation_message());
    // The cache only saves time: failing to write it does not fail the run.
    static_cast<void>((*ctx)->save_pipeline_cache());
    return 0;
}

} // namespace gust::cli
