// Times VoxelWorld::step after a one-voxel scroll of a grid over a large terrain (issue 30): the slab
// pass, which shifts the kept static list and voxelizes only the uncovered slab, against the whole
// static set voxelized again, in one run. The two worlds alternate step by step, so both see the same
// machine load, and their trees are compared after every scroll.
#include "bench_common.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <bit>
#include <cstdint>
#include <gust/gpu/context.hpp>
#include <gust/scene/primitives.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

using gust::bench::Clock;
using gust::bench::fmt_ms;
using gust::bench::fmt_ratio;
using gust::bench::grouped;
using gust::bench::ms_since;

constexpr const char* kTool = "gust_bench_scroll";

int fail(const std::string& message) {
    return gust::bench::fail(kTool, message);
}

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values.empty() ? 0.0 : values[values.size() / 2];
}

/// Sums a step's GPU milliseconds whose pass name starts with `prefix`.
double gpu_ms(const gust::gpu::Timings& timings, const std::string& prefix) {
    double sum = 0.0;
    for (const auto& [name, ms] : timings)
        if (name.compare(0, prefix.size(), prefix) == 0) sum += ms;
    return sum;
}

} // namespace

int main(int argc, char** argv) {
    std::uint32_t res = 64;
    std::uint32_t samples = 224;
    float size = 1.25f;
    int scrolls = 8;
    std::string device;
    CLI::App app{"Times a one-voxel scroll over a terrain: slab pass against whole voxelization"};
    app.add_option("--res", res, "grid voxels per axis (a power of 2)");
    app.add_option("--samples", samples, "terrain quads per side (2 * samples^2 triangles)");
    app.add_option("--size", size, "terrain side, in grid widths (> 1: it crosses the grid)");
    app.add_option("--scrolls", scrolls, "scrolls timed per world");
    app.add_option("--device", device, "Vulkan device name substring");
    CLI11_PARSE(app, argc, argv);

    gust::gpu::ContextDesc desc;
    desc.device = device;
    auto ctx = gust::gpu::Context::create(desc);
    if (!ctx) return fail("cannot create a Vulkan context: " + ctx.message());

    gust::TerrainDesc terrain_desc;
    terrain_desc.size = glm::vec2(float(res) * size);
    terrain_desc.samples = glm::uvec2(samples);
    terrain_desc.noise = gust::TerrainNoise{float(res) / 8.0f, float(res) / 2.0f, 4, 3};
    const gust::Mesh terrain = gust::make_terrain_mesh(terrain_desc);

    gust::WorldDesc world_desc;
    world_desc.grid.res = res;
    world_desc.grid.voxel_size = 1.0f;
    world_desc.grid.origin = glm::vec3(-float(res) / 2.0f);
    world_desc.method = gust::VoxelizeMethod::Auto;
    // Branching 4 where res is a power of 4, else 2.
    world_desc.tree.branching = std::countr_zero(res) % 2 == 0 ? 4u : 2u;
    // [0]: slab passes; [1]: the whole static set again at every scroll (as before issue 30).
    std::unique_ptr<gust::VoxelWorld> worlds[2];
    gust::GpuMesh meshes[2];
    std::vector<gust::GpuInstance> statics[2];
    for (int w = 0; w < 2; ++w) {
        auto world = gust::VoxelWorld::create(**ctx, world_desc);
        if (!world) return fail("cannot create a world: " + world.message());
        worlds[w] = std::move(*world);
        auto mesh = worlds[w]->upload(gust::view_of(terrain));
        if (!mesh) return fail("terrain upload failed: " + mesh.message());
        meshes[w] = std::move(*mesh);
        statics[w] = {{&meshes[w], glm::mat4(1.0f)}};
        worlds[w]->set_static(statics[w]);
        auto first = worlds[w]->step({}, 0.1f);
        if (!first) return fail("first step failed: " + first.message());
    }

    std::vector<double> wall[2], voxelize[2], shift[2];
    std::uint64_t voxels = 0;
    glm::vec3 origin = world_desc.grid.origin;
    for (int s = 0; s < scrolls; ++s) {
        origin.x += world_desc.grid.voxel_size;
        for (int w = 0; w < 2; ++w) {
            if (!worlds[w]->move_grid(origin)) return fail("move_grid failed");
            if (w == 1) {
                // A set that changed is voxelized whole.
                worlds[w]->set_static({});
                worlds[w]->set_static(statics[w]);
            }
            const auto start = Clock::now();
            auto frame = worlds[w]->step({}, 0.1f);
            const double ms = ms_since(start);
            if (!frame) return fail("step failed: " + frame.message());
            if (frame->static_slabs != (w == 0))
                return fail("the step did not take the path it was timed for");
            wall[w].push_back(ms);
            voxelize[w].push_back(gpu_ms(frame->ms, "voxelize_static_"));
            shift[w].push_back(gpu_ms(frame->ms, "voxelize_static_shift"));
            voxels = frame->tree.voxels;
        }
        auto a = worlds[0]->tree().leaf_voxels();
        auto b = worlds[1]->tree().leaf_voxels();
        if (!a || !b) return fail("leaf readback failed");
        if (!std::equal(a->begin(), a->end(), b->begin(), b->end()))
            return fail("the slab pass's tree differs from the whole voxelization's after scroll " +
                        std::to_string(s + 1));
    }

    std::cout << "device: " << (*ctx)->info().name << ", " << gust::bench::usable_cores() << " cores, load "
              << gust::bench::load_average() << ", " << gust::bench::utc_now() << "\n"
              << "terrain: " << grouped(terrain.triangle_count()) << " triangles over " << size
              << " grid widths; grid " << res << "^3 of 1 m; " << grouped(voxels) << " voxels; " << scrolls
              << " scrolls of +1 voxel in x\n"
              << "median ms per step        slabs    whole    whole/slabs\n"
              << "  step (wall)             " << fmt_ms(median(wall[0])) << "    " << fmt_ms(median(wall[1]))
              << "    " << fmt_ratio(median(wall[1]) / median(wall[0])) << "\n"
              << "  static voxelize (GPU)   " << fmt_ms(median(voxelize[0])) << "    "
              << fmt_ms(median(voxelize[1])) << "    " << fmt_ratio(median(voxelize[1]) / median(voxelize[0]))
              << "\n"
              << "  of which shift (GPU)    " << fmt_ms(median(shift[0])) << "\n";
    return 0;
}
