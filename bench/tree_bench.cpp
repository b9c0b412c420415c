// Reproduces the seed's second and third tables (sparse-tree build time against depth at 512^3, and the
// bytes each representation of the same voxels takes) on the full Stanford dragon, and measures the
// incremental frame docs/design.md asks for (dynamic voxelize + tree update) against rebuilding everything.
#include "tree_bench.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <gust/gpu/context.hpp>
#include <gust/scene/animated_mesh.hpp>
#include <gust/scene/mesh.hpp>
#include <gust/scene/primitives.hpp>
#include <gust/voxelizer/sparse_tree.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <iostream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace gust::bench::tree {
namespace {

using PassMs = gust::gpu::Timings;

/// Names this tool in its error and Vulkan messages.
constexpr const char* kTool = "gust_bench_tree";
/// Names this bench's block in the results file (`<!-- bench:tree:begin -->`).
constexpr const char* kBlock = "tree";

/// Prints a fatal error under this tool's name and gives the exit status.
int fail(const std::string& message) {
    return gust::bench::fail(kTool, message);
}

/// Pool doublings tried before a tree is declared unbuildable.
constexpr std::uint32_t kMaxGrowths = 16;
/// Frame time of the walk-through, seconds.
constexpr float kDt = 1.0f / 30.0f;

/// Sum of timestamp passes, or a negative number when the device gave none.
double summed(const PassMs& passes) {
    if (passes.empty()) return -1.0;
    double total = 0.0;
    for (const auto& pass : passes)
        total += pass.second;
    return total;
}

/// log2 of a power of two, for tree depths and fragment shifts.
std::uint32_t log2u(std::uint32_t power_of_two) {
    return std::uint32_t(std::countr_zero(power_of_two));
}

/// Voxelizes the dragon once with the compute path and keeps its unique voxels for the host checks.
gust::Result<Voxelized> voxelize_dragon(gust::Voxelizer& voxelizer, const gust::GpuInstance& dragon,
                                        std::pair<glm::vec3, glm::vec3> bounds, std::uint32_t res) {
    Voxelized out;
    out.res = res;
    out.grid = gust::grid_around(bounds.first, bounds.second, res);
    const auto start = Clock::now();
    auto stats = voxelizer.voxelize(std::span(&dragon, 1), out.grid, gust::VoxelizeMethod::Compute);
    out.wall_ms = ms_since(start);
    if (!stats) return stats.status();
    out.fragments = stats->fragments;
    auto keys = voxelizer.read_fragments();
    if (!keys) return keys.status();
    out.unique = std::move(*keys);
    std::sort(out.unique.begin(), out.unique.end());
    out.unique.erase(std::unique(out.unique.begin(), out.unique.end()), out.unique.end());
    return out;
}

/// Unique voxels of a grid coarser by 2^shift, which is what a tree fed those fragments must hold.
std::uint64_t unique_at_shift(const std::vector<std::uint32_t>& unique, std::uint32_t shift) {
    if (shift == 0) return unique.size();
    std::vector<std::uint32_t> coarse;
    coarse.reserve(unique.size());
    for (std::uint32_t key : unique) {
        const glm::uvec3 v = gust::unpack_voxel(key) >> shift;
        coarse.push_back(gust::pack_voxel(v.x, v.y, v.z));
    }
    std::sort(coarse.begin(), coarse.end());
    return std::uint64_t(std::unique(coarse.begin(), coarse.end()) - coarse.begin());
}

/// One tree's shape: branching per axis and depth.
struct Shape {
    std::uint32_t branching;
    std::uint32_t depth;
};

/// A tree kept alive while it is timed, with the row it fills.
struct TreeUnderTest {
    TreeRow row;
    std::unique_ptr<gust::SparseTree> tree;
};

/// Creates a tree of `shape` over `fragments` and builds it once, doubling its pools until nothing is
/// refused, so that the timed builds neither grow pools nor run partial.
TreeUnderTest prepare_tree(gust::gpu::Context& ctx, const gust::FragmentSource& source,
                           const Voxelized& fragments, Shape shape, int runs) {
    TreeUnderTest t;
    TreeRow& row = t.row;
    row.fragment_res = fragments.res;
    row.branching = shape.branching;
    row.depth = shape.depth;
    row.shift = log2u(fragments.res) - log2u(shape.branching) * shape.depth;
    row.runs = runs;
    row.host_voxels = unique_at_shift(fragments.unique, row.shift);

    gust::TreeDesc desc;
    desc.branching = shape.branching;
    desc.res = row.res();
    desc.fragment_shift = row.shift;
    auto tree = gust::SparseTree::create(ctx, desc);
    if (!tree) {
        row.error = tree.message();
        return t;
    }
    t.tree = std::move(*tree);
    auto stats = t.tree->update(&source, nullptr);
    while (stats && stats->exhausted > 0 && row.growths < kMaxGrowths) {
        if (gust::Status s = t.tree->reserve(t.tree->node_capacity() * 2, t.tree->mask_capacity() * 2); !s) {
            row.error = s.message();
            return t;
        }
        ++row.growths;
        stats = t.tree->update(&source, nullptr);
    }
    if (!stats) {
        row.error = stats.message();
    } else if (stats->exhausted > 0) {
        row.error = "pools still exhausted after " + std::to_string(kMaxGrowths) + " doublings";
    } else {
        row.stats = *stats;
        row.gpu_ms = summed(stats->ms);
    }
    return t;
}

/// Builds every shape over the voxelizer's current fragments, then times `runs` rounds in which each
/// tree is rebuilt from scratch once, keeping each tree's best; rounds rather than back-to-back runs
/// spread a change in the machine's load over all shapes instead of a few.
std::vector<TreeRow> sweep(gust::gpu::Context& ctx, const gust::Voxelizer& voxelizer,
                           const Voxelized& fragments, std::span<const Shape> shapes, int runs) {
    const gust::FragmentSource source{voxelizer.fragment_buffer().address(),
                                      voxelizer.fragment_count_address(), voxelizer.fragment_capacity()};
    std::vector<TreeUnderTest> trees;
    for (Shape shape : shapes)
        trees.push_back(prepare_tree(ctx, source, fragments, shape, runs));
    if (runs > 0 && !trees.empty())
        std::cerr << "  built " << trees.size() << " trees; timing " << runs << " round(s)" << std::endl;
    for (int run = 0; run < runs; ++run)
        for (TreeUnderTest& t : trees) {
            if (!t.row.ok()) continue;
            const auto start = Clock::now();
            auto timed = t.tree->update(&source, nullptr);
            const double ms = ms_since(start);
            if (!timed) {
                t.row.error = timed.message();
                continue;
            }
            if (run > 0 && ms >= t.row.wall_ms) continue;
            t.row.wall_ms = ms;
            t.row.gpu_ms = summed(timed->ms);
            t.row.stats = *timed;
        }
    std::vector<TreeRow> rows;
    for (TreeUnderTest& t : trees)
        rows.push_back(std::move(t.row));
    return rows;
}

/// Prints one tree row's outcome to stderr as it finishes, so a long run shows progress.
void report_tree(const TreeRow& row) {
    std::cerr << "  b=" << row.branching << " depth " << row.depth << " (" << row.res() << "^3, shift "
              << row.shift << "): ";
    if (!row.ok()) {
        std::cerr << "failed: " << row.error << std::endl;
        return;
    }
    if (row.runs > 0) std::cerr << fmt_ms(row.wall_ms) << " ms wall, " << fmt_ms(row.gpu_ms) << " ms GPU, ";
    std::cerr << grouped(row.stats.nodes) << " nodes, " << grouped(row.stats.voxels) << " leaf voxels, "
              << grouped(row.stats.pool_bytes) << " pool bytes" << std::endl;
}

/// Model matrix standing `mesh` on the ground at `at`: longest extent scaled to `size` metres, turned
/// by `yaw` degrees about +y, its lowest point at at.y.
glm::mat4 standing(const gust::Mesh& mesh, float size, glm::vec3 at, float yaw) {
    const auto [lo, hi] = gust::mesh_bounds(gust::view_of(mesh));
    const glm::vec3 extent = hi - lo;
    const float scale = size / std::max({extent.x, extent.y, extent.z});
    const glm::vec3 foot(0.5f * (lo.x + hi.x), lo.y, 0.5f * (lo.z + hi.z));
    glm::mat4 model = glm::translate(glm::mat4(1.0f), at);
    model = glm::rotate(model, glm::radians(yaw), glm::vec3(0.0f, 1.0f, 0.0f));
    model = glm::scale(model, glm::vec3(scale));
    return glm::translate(model, -foot);
}

/// The skinned character: posed on the CPU each frame and moved along +x at walking pace.
class Walker {
  public:
    /// Fits the character (up axis = its longest one at t = 0) to `height` metres, feet at y = 0.
    Walker(gust::AnimatedMesh mesh, std::size_t clip, float height) : mesh_(std::move(mesh)), clip_(clip) {
        mesh_.pose(clip_, 0.0, true, posed_);
        glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& p : posed_) {
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        const glm::vec3 extent = hi - lo;
        glm::mat4 up(1.0f);
        if (extent.z >= extent.x && extent.z >= extent.y)
            up = glm::rotate(up, glm::radians(-90.0f), glm::vec3(1.0f, 0.0f, 0.0f));
        else if (extent.x >= extent.y)
            up = glm::rotate(up, glm::radians(90.0f), glm::vec3(0.0f, 0.0f, 1.0f));
        glm::vec3 ulo(std::numeric_limits<float>::max()), uhi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& p : posed_) {
            const glm::vec3 q = glm::vec3(up * glm::vec4(p, 1.0f));
            ulo = glm::min(ulo, q);
            uhi = glm::max(uhi, q);
        }
        const glm::vec3 foot(0.5f * (ulo.x + uhi.x), ulo.y, 0.5f * (ulo.z + uhi.z));
        base_ = glm::scale(glm::mat4(1.0f), glm::vec3(height / (uhi.y - ulo.y))) *
                glm::translate(glm::mat4(1.0f), -foot) * up;
    }

    /// The unposed triangles, uploaded once; each frame's pose then replaces their positions.
    const gust::Mesh& rest_pose() const { return mesh_.rest_pose(); }

    /// World-space box of the pose at time t, printed so that a badly fitted character is obvious.
    std::pair<glm::vec3, glm::vec3> bounds(double t) {
        mesh_.pose(clip_, t, true, posed_);
        const glm::mat4 model = place(t);
        glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& p : posed_) {
            const glm::vec3 w = glm::vec3(model * glm::vec4(p, 1.0f));
            lo = glm::min(lo, w);
            hi = glm::max(hi, w);
        }
        return {lo, hi};
    }

    /// Poses the character at frame `index` and uploads the vertices; gives this frame's instance.
    gust::Result<gust::GpuInstance> advance(gust::VoxelWorld& world, gust::GpuMesh& gpu,
                                            std::uint64_t index) {
        const double t = double(index) * double(kDt);
        mesh_.pose(clip_, t, true, posed_);
        if (gust::Status s = world.update_positions(gpu, posed_); !s) return s;
        gust::GpuInstance instance{&gpu, place(t), std::nullopt};
        if (index > 0) instance.prev_model = place(t - double(kDt));
        return instance;
    }

    /// Where the walk puts the character at time t: along z = 0 from x = -8 m at 1.2 m/s, wrapping at 16 m.
    glm::mat4 place(double t) const {
        const float x = -8.0f + float(std::fmod(1.2 * std::max(t, 0.0), 16.0));
        return glm::translate(glm::mat4(1.0f), glm::vec3(x, 0.0f, 0.0f)) * base_;
    }

  private:
    gust::AnimatedMesh mesh_;
    std::size_t clip_;
    glm::mat4 base_{1.0f};
    std::vector<glm::vec3> posed_;
};

/// One static object of the walk-through: a file (or the generated ground) and where it stands.
struct Prop {
    const char* file; ///< under assets/; nullptr for the ground box
    float size;       ///< longest extent, metres
    glm::vec3 at;     ///< where its footprint's centre stands, metres
    float yaw;        ///< turn about +y, degrees
};

/// Steps the world `count` times, rotating the static set's order first when `rebuild` is set (identical
/// geometry, but set_static sees a changed set, so it is voxelized again and the tree rebuilt).
gust::Status run_frames(gust::VoxelWorld& world, Walker& walker, gust::GpuMesh& character,
                        std::vector<gust::GpuInstance>& statics, bool rebuild, int count,
                        std::uint64_t& index, std::vector<FrameSample>* out, std::uint32_t& growths) {
    for (int i = 0; i < count; ++i, ++index) {
        if (rebuild) {
            std::rotate(statics.begin(), statics.begin() + 1, statics.end());
            world.set_static(statics);
        }
        FrameSample sample;
        const auto pose_start = Clock::now();
        auto instance = walker.advance(world, character, index);
        sample.pose_ms = ms_since(pose_start);
        if (!instance) return instance.status();
        const auto start = Clock::now();
        auto frame = world.step(std::span(&*instance, 1), kDt);
        sample.wall_ms = ms_since(start);
        if (!frame) return frame.status();
        growths += frame->pool_growths;
        if (frame->static_rebuilt != (rebuild || index == 0))
            return gust::Status::failure("frame " + std::to_string(index) + (rebuild ? " did not" : " did") +
                                         " voxelize the static set again");
        sample.gpu_ms = summed(frame->ms);
        sample.frame = std::move(*frame);
        if (out) out->push_back(std::move(sample));
    }
    return {};
}

/// Builds the walk-through scene in a b = 4 world and measures incremental frames, then rebuilds.
gust::Result<WorldResult> bench_world(gust::gpu::Context& ctx, const Options& options, const Plan& plan) {
    const Prop props[] = {{nullptr, 20.0f, glm::vec3(0.0f), 0.0f},
                          {"scans/dragon_res2.ply", 4.0f, glm::vec3(-5.0f, 0.0f, -5.0f), 30.0f},
                          {"scans/dragon_res2.ply", 4.0f, glm::vec3(5.0f, 0.0f, 5.0f), 120.0f},
                          {"scans/bunny_full.ply", 2.5f, glm::vec3(-5.0f, 0.0f, 5.0f), 0.0f},
                          {"architecture/building-garage.glb", 5.0f, glm::vec3(6.0f, 0.0f, -6.0f), 0.0f},
                          {"architecture/building-small-a.glb", 5.0f, glm::vec3(0.0f, 0.0f, -6.5f), 0.0f},
                          {"architecture/building-small-c.glb", 8.0f, glm::vec3(0.0f, 0.0f, 6.5f), 90.0f}};
    WorldResult result;
    std::map<std::string, gust::Mesh> meshes;
    std::vector<std::pair<const gust::Mesh*, glm::mat4>> placed;
    std::ostringstream scene;
    for (const Prop& prop : props) {
        const std::string key = prop.file ? prop.file : "ground";
        if (!meshes.count(key)) {
            if (prop.file) {
                auto mesh = load_asset(options.assets, prop.file);
                if (!mesh) return mesh.status();
                meshes.emplace(key, std::move(*mesh));
            } else {
                const float half = 0.5f * prop.size;
                meshes.emplace(
                    key, gust::make_box_mesh(glm::vec3(-half, -0.2f, -half), glm::vec3(half, 0.0f, half)));
            }
        }
        const gust::Mesh& mesh = meshes.at(key);
        placed.emplace_back(&mesh,
                            prop.file ? standing(mesh, prop.size, prop.at, prop.yaw) : glm::mat4(1.0f));
        result.static_triangles += mesh.triangle_count();
        if (!scene.str().empty()) scene << "; ";
        if (prop.file)
            scene << "`" << prop.file << "` (" << grouped(mesh.triangle_count())
                  << " triangles, longest side " << prop.size << " m) at (x, z) = (" << prop.at.x << ", "
                  << prop.at.z << ")";
        else
            scene << "a ground box " << prop.size << " x 0.2 x " << prop.size
                  << " m, top at y = 0 (12 triangles)";
    }

    auto character_path = asset_path(options.assets, "characters/CesiumMan.glb");
    if (!character_path) return character_path.status();
    auto animated = gust::AnimatedMesh::load(*character_path);
    if (!animated) return animated.status();
    if (animated->clip_names().empty())
        return gust::Status::failure(character_path->string() + ": no animation clip");
    const std::string clip_name = animated->clip_names().front();
    Walker walker(std::move(*animated), 0, 1.5f);
    result.dynamic_triangles = walker.rest_pose().triangle_count();
    const auto [char_lo, char_hi] = walker.bounds(0.0);
    std::cerr << "character at t = 0 spans (" << char_lo.x << ", " << char_lo.y << ", " << char_lo.z
              << ") to (" << char_hi.x << ", " << char_hi.y << ", " << char_hi.z << ") m" << std::endl;
    scene << "; a walking `characters/CesiumMan.glb` (" << grouped(result.dynamic_triangles)
          << " triangles, clip `" << clip_name
          << "` looped, 1.5 m tall) moved along z = 0 from x = -8 m at 1.2 m/s";
    result.scene = scene.str();

    gust::WorldDesc desc;
    desc.grid.res = plan.world_res;
    desc.grid.voxel_size = plan.world_h;
    const float half = 0.5f * float(plan.world_res) * plan.world_h;
    desc.grid.origin = glm::vec3(-half, -0.4f, -half);
    desc.tree.branching = 4;
    desc.method = gust::VoxelizeMethod::Compute;
    result.grid = desc.grid;
    result.hysteresis = desc.tree.hysteresis;
    auto world = gust::VoxelWorld::create(ctx, desc);
    if (!world) return world.status();

    std::map<const gust::Mesh*, gust::GpuMesh> uploaded;
    for (const auto& [mesh, model] : placed)
        if (!uploaded.count(mesh)) {
            auto gpu = (*world)->upload(gust::view_of(*mesh));
            if (!gpu) return gust::Status::failure(mesh->name + ": upload failed: " + gpu.message());
            uploaded.emplace(mesh, std::move(*gpu));
        }
    std::vector<gust::GpuInstance> statics;
    for (const auto& [mesh, model] : placed)
        statics.push_back({&uploaded.at(mesh), model, std::nullopt});
    auto character = (*world)->upload(gust::view_of(walker.rest_pose()));
    if (!character) return gust::Status::failure("CesiumMan.glb: upload failed: " + character.message());
    (*world)->set_static(statics);

    std::uint64_t index = 0;
    std::cerr << "walk-through: " << grouped(result.static_triangles) << " static triangles, "
              << plan.warmup_frames << " warm-up frames" << std::endl;
    if (gust::Status s = run_frames(**world, walker, *character, statics, false, plan.warmup_frames, index,
                                    nullptr, result.growths);
        !s)
        return s;
    std::cerr << "  " << plan.frames << " incremental frames" << std::endl;
    if (gust::Status s = run_frames(**world, walker, *character, statics, false, plan.frames, index,
                                    &result.incremental, result.growths);
        !s)
        return s;
    std::cerr << "  " << plan.rebuild_warmup << " + " << plan.frames << " rebuild frames" << std::endl;
    if (gust::Status s = run_frames(**world, walker, *character, statics, true, plan.rebuild_warmup, index,
                                    nullptr, result.growths);
        !s)
        return s;
    if (gust::Status s = run_frames(**world, walker, *character, statics, true, plan.frames, index,
                                    &result.rebuild, result.growths);
        !s)
        return s;
    return result;
}

} // namespace
} // namespace gust::bench::tree

/// Runs the three measurements in order, prints the block and writes it where --write says.
int main(int argc, char** argv) {
    using namespace gust::bench;
    using namespace gust::bench::tree;
    Options options;
    CLI::App app{"Sparse-tree build time against depth and bytes per representation (the seed's second and "
                 "third tables), and the incremental frame against a full rebuild"};
    app.add_option("--assets", options.assets, "gust's assets folder")->check(CLI::ExistingDirectory);
    app.add_option("--repeat", options.repeat, "timed builds per tree (best is reported)")
        ->check(CLI::Range(1, 1000));
    app.add_option("--frames", options.frames,
                   "timed frames per kind in the walk-through (median is reported)")
        ->check(CLI::Range(1, 10000));
    app.add_flag("--quick", options.quick, "smoke run: fragments at 128^3, depths up to 6, 5 frames");
    app.add_option("--write", options.write, "Markdown file whose tree block is replaced (or appended)");
    app.add_option("--device", options.device, "Vulkan device index or name substring");
    CLI11_PARSE(app, argc, argv);
    const RunInfo run{command_line(argc, argv), utc_now(), load_average(), Clock::now()};

    Plan plan;
    plan.frames = options.frames;
    if (options.quick) {
        plan.depth_res = 128;
        plan.max_octree_depth = 6;
        plan.byte_res = {64, 128};
        plan.warmup_frames = 3;
        plan.rebuild_warmup = 1;
        if (!app.count("--frames")) plan.frames = 5;
    }

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

    auto dragon = load_asset(options.assets, "scans/dragon_full.glb");
    if (!dragon) return fail(dragon.message());
    auto dragon_gpu = (*voxelizer)->upload(gust::view_of(*dragon));
    if (!dragon_gpu) return fail("dragon_full.glb: upload failed: " + dragon_gpu.message());
    const gust::GpuInstance dragon_instance{&*dragon_gpu, glm::mat4(1.0f), std::nullopt};
    const auto bounds = gust::mesh_bounds(gust::view_of(*dragon));

    std::vector<std::uint32_t> resolutions = {plan.depth_res};
    for (std::uint32_t res : plan.byte_res)
        if (res != plan.depth_res) resolutions.push_back(res);
    std::vector<Voxelized> grids;
    std::vector<TreeRow> depth_rows, byte_rows;
    for (std::uint32_t res : resolutions) {
        std::cerr << "dragon_full.glb at " << res << "^3:" << std::endl;
        auto fragments = voxelize_dragon(**voxelizer, dragon_instance, bounds, res);
        if (!fragments)
            return fail("voxelizing dragon_full.glb at " + std::to_string(res) +
                        "^3: " + fragments.message());
        std::cerr << "  " << grouped(fragments->fragments) << " fragments, "
                  << grouped(fragments->unique.size()) << " unique voxels, " << fmt_ms(fragments->wall_ms)
                  << " ms" << std::endl;
        const bool bytes = std::find(plan.byte_res.begin(), plan.byte_res.end(), res) != plan.byte_res.end();
        std::vector<Shape> timed, untimed;
        for (std::uint32_t b : {2u, 4u, 8u}) {
            const std::uint32_t finest = log2u(res) / log2u(b);
            const std::uint32_t deepest = b == 2 ? std::min(finest, plan.max_octree_depth) : finest;
            if (res == plan.depth_res)
                for (std::uint32_t depth = 1; depth <= deepest; ++depth)
                    timed.push_back({b, depth});
            if (bytes && log2u(b) * finest == log2u(res) && (res != plan.depth_res || deepest != finest))
                untimed.push_back({b, finest});
        }
        for (const TreeRow& row : sweep(**ctx, **voxelizer, *fragments, timed, options.repeat)) {
            report_tree(row);
            depth_rows.push_back(row);
            if (bytes && row.shift == 0) byte_rows.push_back(row);
        }
        for (const TreeRow& row : sweep(**ctx, **voxelizer, *fragments, untimed, 0)) {
            report_tree(row);
            byte_rows.push_back(row);
        }
        grids.push_back(std::move(*fragments));
    }
    std::sort(byte_rows.begin(), byte_rows.end(), [](const TreeRow& a, const TreeRow& b) {
        return std::pair(a.res(), a.branching) < std::pair(b.res(), b.branching);
    });
    std::sort(grids.begin(), grids.end(),
              [](const Voxelized& a, const Voxelized& b) { return a.res < b.res; });

    auto world = bench_world(**ctx, options, plan);
    if (!world) return fail("walk-through: " + world.message());

    const std::string body =
        render(depth_rows, byte_rows, grids, *world, dragon->triangle_count(), plan, (*ctx)->info(), run);
    std::cout << body << std::flush;
    if (!options.write.empty()) {
        if (gust::Status s =
                gust::bench::write_block(options.write, block_name(kBlock, (*ctx)->info()), body);
            !s)
            return fail(s.message());
        std::cerr << "wrote the tree block of " << options.write << "\n";
    }
    for (const std::vector<TreeRow>* rows : {&depth_rows, &byte_rows})
        for (const TreeRow& row : *rows) {
            if (!row.ok())
                return fail("b = " + std::to_string(row.branching) + " depth " + std::to_string(row.depth) +
                            " failed: " + row.error);
            if (row.stats.voxels != row.host_voxels)
                return fail("b = " + std::to_string(row.branching) + " depth " + std::to_string(row.depth) +
                            " holds " + grouped(row.stats.voxels) + " leaf voxels; the fragments have " +
                            grouped(row.host_voxels));
        }
    return 0;
}