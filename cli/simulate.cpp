#include "simulate.hpp"

#include "pipeline_cache.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/type_ptr.hpp>
#include <gust/gust.hpp>
#include <gust/scene/domain_grid.hpp>
#include <gust/scene/scene_runtime.hpp>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

namespace gust::cli {

namespace {

int fail(const std::string& message) {
    std::cerr << "gust: error: " << message << "\n";
    return 1;
}

/// "<scene>: objects[i].mesh: <mesh>: " (or "objects[i].terrain: "), the start of an error about object i.
std::string object_at(const std::string& scene, std::size_t i, const SceneObject& object) {
    const std::string at = scene + ": objects[" + std::to_string(i) + "]";
    return object.terrain ? at + ".terrain: " : at + ".mesh: " + object.mesh.string() + ": ";
}

std::string frame_file(std::uint64_t frame) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04llu.vdb", static_cast<unsigned long long>(frame));
    return name;
}

Vec3 to_vec3(const glm::vec3& v) {
    return {v.x, v.y, v.z};
}

Mat4 to_mat4(const glm::mat4& m) {
    Mat4 out;
    std::memcpy(out.m, glm::value_ptr(m), sizeof(out.m));
    return out;
}

/// The scene's emitters at time t (motors moved along their paths).
std::vector<WindEmitter> emitters_at(const SceneDesc& scene, double t) {
    std::vector<WindEmitter> out;
    for (const EmitterDesc& e : scene.emitters) {
        WindEmitter emitter;
        emitter.type = e.type == "directional" ? WindEmitterType::Directional
                       : e.type == "omni"      ? WindEmitterType::Omni
                       : e.type == "vortex"    ? WindEmitterType::Vortex
                       : e.shape == "cone"     ? WindEmitterType::ConeMotor
                                               : WindEmitterType::CapsuleMotor;
        emitter.position = to_vec3(emitter_position(e, t));
        emitter.direction = to_vec3(e.direction);
        emitter.radius = e.radius;
        emitter.strength = e.strength;
        emitter.falloff = e.falloff;
        emitter.length = e.type == "motor" ? e.length : 0.0f;
        out.push_back(emitter);
    }
    return out;
}

bool parse_path(const std::string& text, VoxelizePath& out) {
    if (text == "raster")
        out = VoxelizePath::Raster;
    else if (text == "compute")
        out = VoxelizePath::Compute;
    else if (text == "auto")
        out = VoxelizePath::Auto;
    else
        return false;
    return true;
}

/// What the System logs (Hooks::log): the Vulkan validation layer's and the driver's messages, and its own
/// (a frame that ran out of a list or pool). Errors are what the validation layer reports when the device
/// is used wrongly; with --validation they fail the run.
struct Messages {
    std::uint32_t errors = 0;
    std::string last_error;
};

void on_log(void* user, LogLevel level, const char* message) {
    auto* messages = static_cast<Messages*>(user);
    if (level == LogLevel::Info) return;
    if (level == LogLevel::Error) {
        ++messages->errors;
        messages->last_error = message;
        std::cerr << "gust: vulkan: " << message << "\n";
    } else {
        std::cerr << "gust: warning: " << message << "\n";
    }
}

const float* floats(const std::vector<glm::vec3>& positions) {
    return positions.empty() ? nullptr : glm::value_ptr(positions.front());
}

MeshDesc mesh_desc(const Mesh& mesh, const std::vector<glm::vec3>& positions, bool deforming) {
    MeshDesc desc;
    desc.positions = floats(positions);
    desc.vertex_count = std::uint32_t(positions.size());
    desc.indices = mesh.indices.data();
    desc.index_count = std::uint32_t(mesh.indices.size());
    desc.deforming = deforming;
    return desc;
}

/// One line of stats.jsonl from a step's FrameStats and the System's queue (docs/cli.md lists the keys).
nlohmann::ordered_json stats_line(const FrameStats& st, const QueueInfo& queue, double t) {
    nlohmann::ordered_json line;
    line["frame"] = st.frame;
    line["time"] = t;
    line["fragments"] = st.fragments;
    line["voxels"] = st.voxels;
    line["nodes"] = st.nodes;
    line["refined"] = st.refined;
    line["coarsened"] = st.coarsened;
    line["pool_bytes"] = st.pool_bytes;
    line["fragment_bytes"] = st.fragment_bytes;
    line["dense_bytes"] = st.dense_bytes;
    nlohmann::ordered_json ms = nlohmann::ordered_json::object();
    for (const auto& [pass, value] : st.ms)
        ms[std::string(pass)] = value;
    line["ms"] = ms;
    line["dispatches"] = st.dispatches;
    line["stages"] = st.stages;
    line["submissions"] = st.submissions;
    line["waits"] = st.waits;
    line["queue_family"] = queue.family;
    line["async_compute"] = queue.async_compute;
    line["divergence_before"] = st.divergence_before;
    line["divergence_after"] = st.divergence_after;
    line["residual"] = st.residual;
    line["cycles"] = st.cycles;
    line["converged"] = st.converged;
    line["cut_cells"] = st.cut_cells;
    line["fluid_cells"] = st.fluid_cells;
    line["sealed_cells"] = st.sealed_cells;
    line["diverged"] = st.diverged;
    line["nodes_per_level"] =
        std::vector<std::uint64_t>(st.nodes_per_level.begin(), st.nodes_per_level.end());
    line["exhausted"] = st.exhausted;
    line["pool_growths"] = st.pool_growths;
    line["free_node_blocks"] = st.free_node_blocks;
    line["free_mask_blocks"] = st.free_mask_blocks;
    line["static_rebuilt"] = st.static_rebuilt;
    line["rejected"] = st.rejected_triangles;
    return line;
}

} // namespace

int run_simulate(const SimulateArgs& args) {
    namespace fs = std::filesystem;
    VoxelizePath path{};
    if (!parse_path(args.method, path))
        return fail("--method must be raster, compute or auto, got '" + args.method + "'");
    if (args.frames == 0) return fail("--frames must be at least 1");
    auto scene = load_scene(args.scene);
    if (!scene) return fail(scene.message());
    auto runtime = SceneRuntime::load(*scene);
    if (!runtime) return fail(runtime.message());

    std::error_code ec;
    fs::create_directories(args.out, ec);
    if (ec) return fail(args.out + ": cannot create the output folder: " + ec.message());
    std::ofstream stats_file(fs::path(args.out) / "stats.jsonl");
    if (!stats_file) return fail(args.out + "/stats.jsonl: cannot open for writing");

    // The frame runs through the public API: System::step records it once, submits it once and waits once
    // (docs/design.md "One frame").
    SystemDesc desc = system_desc(*scene);
    desc.validation = args.validation;
    desc.device = args.device.empty() ? nullptr : args.device.c_str();
    desc.voxelize = path;
    const std::string cache = pipeline_cache_file(args.no_pipeline_cache);
    desc.pipeline_cache = cache.empty() ? nullptr : cache.c_str();
    Messages messages;
    desc.hooks.user = &messages;
    desc.hooks.log = on_log;
    std::unique_ptr<System> system;
    if (Outcome o = System::create(desc, system); !o) return fail(args.scene + ": " + o.message());
    if (Outcome o = system->set_ambient(to_vec3(scene->ambient_velocity)); !o)
        return fail(args.scene + ": ambient: " + o.message());

    // Objects showing the same mesh share one device copy; deforming objects get their own, since their
    // vertices change every frame. Everything starts where it was one frame before
    // frame 0, so that frame 0's velocities are those of the motion.
    const double dt = scene->dt;
    const std::size_t count = runtime->object_count();
    std::vector<MeshId> meshes(count);
    std::vector<InstanceId> instances(count);
    std::map<const Mesh*, MeshId> shared;
    for (std::size_t i = 0; i < count; ++i) {
        const Mesh& source = runtime->mesh(i);
        const bool deforms = runtime->deforms(i);
        if (const auto it = shared.find(&source); !deforms && it != shared.end()) {
            meshes[i] = it->second;
        } else {
            const std::vector<glm::vec3>& positions = runtime->positions(i, -dt);
            if (Outcome o = system->create_mesh(mesh_desc(source, positions, deforms), meshes[i]); !o)
                return fail(object_at(args.scene, i, scene->objects[i]) +
                            (deforms ? "posed one step before frame 0: " : "") + o.message());
            if (!deforms) shared.emplace(&source, meshes[i]);
        }
        const Outcome placed =
            scene->objects[i].is_static
                ? system->create_instance(meshes[i], to_mat4(runtime->model(i, 0.0)), false, instances[i])
                : system->create_moving_instance(meshes[i], to_mat4(runtime->model(i, 0.0)),
                                                 to_mat4(runtime->model(i, -dt)), instances[i]);
        if (!placed) return fail(object_at(args.scene, i, scene->objects[i]) + placed.message());
    }

    VoxelGridInfo grid;
    static_cast<void>(system->debug_voxel_grid(grid));
    std::cerr << "gust: simulating " << args.frames << " frames of " << args.scene << " ("
              << scene->domain.cells.x << "x" << scene->domain.cells.y << "x" << scene->domain.cells.z
              << " cells in a tree of " << grid.resolution[0] << "^3 voxels, " << system->device_name()
              << ")\n";
    const auto start = std::chrono::steady_clock::now();
    for (std::uint64_t frame = 0; frame < args.frames; ++frame) {
        const double t = double(frame) * dt;
        for (std::size_t i = 0; i < count; ++i) {
            if (scene->objects[i].is_static) continue;
            // A keyframe jump or a clip's wrap moves the solid without pushing air.
            const bool jump = runtime->jumps(i, t - dt, t);
            if (runtime->deforms(i)) {
                const std::vector<glm::vec3>& positions = runtime->positions(i, t);
                if (Outcome o = system->set_vertices(meshes[i], floats(positions),
                                                     std::uint32_t(positions.size()), 12, jump);
                    !o)
                    return fail(object_at(args.scene, i, scene->objects[i]) + "posed at frame " +
                                std::to_string(frame) + ": " + o.message());
            }
            if (Outcome o = system->set_transform(instances[i], to_mat4(runtime->model(i, t)), jump); !o)
                return fail(object_at(args.scene, i, scene->objects[i]) + "placed at frame " +
                            std::to_string(frame) + ": " + o.message());
        }
        const std::vector<WindEmitter> emitters = emitters_at(*scene, t);
        if (Outcome o = system->set_emitters(emitters); !o) return fail(args.scene + ": " + o.message());
        if (Outcome o = system->step(float(dt)); !o)
            return fail("frame " + std::to_string(frame) + ": " + o.message());
        stats_file << stats_line(system->stats(), system->queue_info(), t).dump() << "\n";

        if (frame == 0 || (args.every > 0 && frame % args.every == 0)) {
            const fs::path file = fs::path(args.out) / frame_file(frame);
            if (Outcome o = system->export_vdb(file.c_str()); !o) return fail(o.message());
        }
        if ((frame + 1) % std::max<std::uint64_t>(1, args.frames / 10) == 0 || frame + 1 == args.frames) {
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            std::cerr << "gust: frame " << frame + 1 << "/" << args.frames << " (" << seconds << " s)\n";
        }
    }
    stats_file.flush();
    if (!stats_file) return fail(args.out + "/stats.jsonl: write failed");
    if (args.validation && messages.errors > 0)
        return fail(std::to_string(messages.errors) +
                    " Vulkan validation messages; last: " + messages.last_error);
    return 0;
}

} // namespace gust::cli
