// Issue 30: a grid scrolled by whole voxels voxelizes only the slabs it uncovered, and its tree holds
// the voxels a world made at the new origin voxelizes from scratch.
#include "support/gpu_env.hpp"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <gust/scene/primitives.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <memory>
#include <string>
#include <vector>

namespace gust::test {
namespace {

/// Vertices on a 1/256 m lattice: with voxels of 1/4 m and origins on whole voxels every grid-space
/// coordinate is exact in a float, so voxelizations at two origins agree to the bit.
Mesh quantized(Mesh mesh, const glm::mat4& transform = glm::mat4(1.0f)) {
    for (glm::vec3& p : mesh.positions)
        p = glm::round(glm::vec3(transform * glm::vec4(p, 1.0f)) * 256.0f) / 256.0f;
    return mesh;
}

Mesh sphere_mesh(glm::vec3 centre, float radius, std::uint32_t rings, std::uint32_t segments) {
    Mesh mesh;
    for (std::uint32_t r = 0; r <= rings; ++r) {
        const float theta = 3.14159265f * float(r) / float(rings);
        for (std::uint32_t s = 0; s < segments; ++s) {
            const float phi = 6.2831853f * float(s) / float(segments);
            mesh.positions.push_back(centre + radius * glm::vec3(std::sin(theta) * std::cos(phi),
                                                                 std::cos(theta),
                                                                 std::sin(theta) * std::sin(phi)));
        }
    }
    for (std::uint32_t r = 0; r < rings; ++r)
        for (std::uint32_t s = 0; s < segments; ++s) {
            const std::uint32_t a = r * segments + s, b = r * segments + (s + 1) % segments;
            const std::uint32_t c = a + segments, d = b + segments;
            mesh.indices.insert(mesh.indices.end(), {a, c, b, b, c, d});
        }
    return mesh;
}

/// A tilted box, a sphere, a thin upright quad and a terrain wider than every grid the test scrolls to.
struct SlabScene {
    SlabScene() {
        const glm::mat4 tilt =
            glm::rotate(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(1.1f, 0.9f, 0.7f)), 0.4f,
                                    glm::vec3(0, 1, 0)),
                        0.3f, glm::vec3(1, 0, 1));
        meshes.push_back(
            quantized(make_box_mesh(glm::vec3(-0.9f, -0.5f, -0.7f), glm::vec3(0.9f, 0.5f, 0.7f)), tilt));
        meshes.push_back(quantized(sphere_mesh(glm::vec3(-1.3f, 0.6f, -0.8f), 1.1f, 12, 18)));
        Mesh quad;
        quad.positions = {{-0.4f, -1.0f, 2.3f}, {2.6f, -1.0f, 1.9f}, {2.6f, 2.0f, 1.9f}, {-0.4f, 2.0f, 2.3f}};
        quad.indices = {0, 1, 2, 0, 2, 3};
        meshes.push_back(quantized(quad));
        TerrainDesc terrain;
        terrain.size = glm::vec2(40.0f);
        terrain.samples = glm::uvec2(60);
        terrain.base = -2.2f;
        terrain.noise = TerrainNoise{0.8f, 6.0f, 3, 7};
        meshes.push_back(
            quantized(make_terrain_mesh(terrain), glm::translate(glm::mat4(1.0f), glm::vec3(8.0f, 0, 8.0f))));
        grid.res = 32;
        grid.voxel_size = 0.25f;
        grid.keep = glm::uvec3(30, 26, 32);
        grid.origin = glm::vec3(-4.0f, -2.5f, -4.0f);
    }
    /// A world with the scene as its static set (`gpu_meshes` holds the uploads), at `origin`.
    std::unique_ptr<VoxelWorld> world(gpu::Context& ctx, glm::vec3 origin, VoxelizeMethod method,
                                      std::vector<GpuMesh>& gpu_meshes) const {
        WorldDesc desc;
        desc.grid = grid;
        desc.grid.origin = origin;
        desc.method = method;
        desc.tree.branching = 2;
        auto made = VoxelWorld::create(ctx, desc);
        EXPECT_TRUE(made) << made.message();
        if (!made) return nullptr;
        gpu_meshes.clear();
        for (const Mesh& mesh : meshes) {
            auto uploaded = (*made)->upload(view_of(mesh));
            EXPECT_TRUE(uploaded) << uploaded.message();
            if (!uploaded) return nullptr;
            gpu_meshes.push_back(std::move(*uploaded));
        }
        std::vector<GpuInstance> statics;
        for (const GpuMesh& mesh : gpu_meshes)
            statics.push_back({&mesh, glm::mat4(1.0f)});
        (*made)->set_static(statics);
        return std::move(*made);
    }
    /// The tree's voxels of a world that voxelized the scene at `origin` from scratch.
    std::vector<std::uint32_t> scratch(gpu::Context& ctx, glm::vec3 origin, VoxelizeMethod method) const {
        std::vector<GpuMesh> gpu_meshes;
        auto fresh = world(ctx, origin, method, gpu_meshes);
        if (!fresh) return {};
        auto frame = fresh->step({}, 0.1f);
        EXPECT_TRUE(frame) << frame.message();
        return leaves(*fresh);
    }
    static std::vector<std::uint32_t> leaves(const VoxelWorld& world) {
        auto voxels = world.tree().leaf_voxels();
        EXPECT_TRUE(voxels) << voxels.message();
        return voxels ? std::vector<std::uint32_t>(voxels->begin(), voxels->end())
                      : std::vector<std::uint32_t>{};
    }

    std::vector<Mesh> meshes;
    GridDesc grid;
};

/// One scroll: the move in voxels and whether it voxelizes only slabs.
struct Scroll {
    glm::vec3 voxels;
    bool slabs;
    const char* name;
};

class ScrollSlabs : public GpuTestWithParam<VoxelizeMethod> {};

TEST_P(ScrollSlabs, voxelizeOnlyTheUncoveredSlabsAndEqualAWholeVoxelization) {
    const VoxelizeMethod method = GetParam();
    const SlabScene scene;
    std::vector<GpuMesh> gpu_meshes;
    auto world = scene.world(ctx(), scene.grid.origin, method, gpu_meshes);
    ASSERT_TRUE(world);
    auto first = world->step({}, 0.1f);
    ASSERT_TRUE(first) << first.message();
    EXPECT_FALSE(first->static_slabs);
    const Scroll scrolls[] = {
        {{3, 0, 0}, true, "+x"},
        {{0, -2, 0}, true, "-y"},
        {{2, -1, 3}, true, "+x+z-y"},
        {{1, 0, 0}, true, "one voxel"},
        {{0, 0, -40}, false, "farther than the grid"},
        {{0, 1, 0}, true, "after the far one"},
        {{0.5f, 0, 0}, false, "half a voxel"},
        {{-1, 0, 2}, true, "whole voxels from the half"},
    };
    glm::vec3 origin = scene.grid.origin;
    std::uint64_t generation = world->static_generation();
    for (const Scroll& scroll : scrolls) {
        origin += scroll.voxels * scene.grid.voxel_size;
        ASSERT_TRUE(world->move_grid(origin));
        auto frame = world->step({}, 0.1f);
        ASSERT_TRUE(frame) << frame.message();
        EXPECT_EQ(frame->static_slabs, scroll.slabs) << scroll.name;
        EXPECT_TRUE(frame->static_rebuilt) << scroll.name;
        EXPECT_GT(world->static_generation(), generation) << scroll.name;
        generation = world->static_generation();
        const std::vector<std::uint32_t> voxels = SlabScene::leaves(*world);
        const std::vector<std::uint32_t> expected = scene.scratch(ctx(), origin, method);
        EXPECT_GT(expected.size(), 500u) << scroll.name;
        EXPECT_EQ(voxels, expected) << scroll.name;
        EXPECT_EQ(frame->tree.voxels, expected.size()) << scroll.name;
    }
    // A move back to a lattice point already voxelized does nothing.
    ASSERT_TRUE(world->move_grid(origin + glm::vec3(1e-6f, 0.0f, 0.0f)));
    auto still = world->step({}, 0.1f);
    ASSERT_TRUE(still) << still.message();
    EXPECT_FALSE(still->static_rebuilt);
    EXPECT_FALSE(still->static_slabs);
}

INSTANTIATE_TEST_SUITE_P(Methods, ScrollSlabs,
                         ::testing::Values(VoxelizeMethod::Compute, VoxelizeMethod::Raster),
                         [](const ::testing::TestParamInfo<VoxelizeMethod>& p) {
                             return std::string(to_string(p.param));
                         });

using ScrollSlabsWorld = GpuTest;

TEST_F(ScrollSlabsWorld, aChangedStaticSetIsVoxelizedWhole) {
    const SlabScene scene;
    std::vector<GpuMesh> gpu_meshes;
    auto world = scene.world(ctx(), scene.grid.origin, VoxelizeMethod::Compute, gpu_meshes);
    ASSERT_TRUE(world);
    ASSERT_TRUE(world->step({}, 0.1f));
    const GpuInstance sphere[] = {{&gpu_meshes[1], glm::mat4(1.0f)}};
    world->set_static(sphere);
    ASSERT_TRUE(world->move_grid(scene.grid.origin + glm::vec3(scene.grid.voxel_size, 0.0f, 0.0f)));
    auto frame = world->step({}, 0.1f);
    ASSERT_TRUE(frame) << frame.message();
    EXPECT_TRUE(frame->static_rebuilt);
    EXPECT_FALSE(frame->static_slabs);
}

/// Frames in flight: recorded scrolls take the slab pass too and come out as whole voxelizations. The
/// context is the test's own, since begin_frame() switches a context to deferred releases for good.
TEST(ScrollSlabsRecorded, recordedScrollsEqualAWholeVoxelization) {
    gpu::ContextDesc context_desc;
    context_desc.validation = true;
    auto context = gpu::Context::create(context_desc);
    ASSERT_TRUE(context) << context.message();
    gpu::Context& ctx = **context;
    const SlabScene scene;
    std::vector<GpuMesh> gpu_meshes;
    auto world = scene.world(ctx, scene.grid.origin, VoxelizeMethod::Compute, gpu_meshes);
    ASSERT_TRUE(world);
    auto readback = gpu::Buffer::create(ctx, VoxelWorld::readback_bytes(), gpu::MemoryUse::Readback);
    ASSERT_TRUE(readback);
    const glm::vec3 moves[] = {{0, 0, 0}, {2, 0, 0}, {0, -1, 1}, {-3, 0, 0}};
    glm::vec3 origin = scene.grid.origin;
    for (std::uint64_t n = 0; n < std::size(moves); ++n) {
        origin += moves[n] * scene.grid.voxel_size;
        ASSERT_TRUE(world->move_grid(origin));
        ctx.begin_frame(n);
        Status recorded;
        ASSERT_TRUE(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
            recorded = world->record(cmd, {}, 0.1f);
            gpu::barrier(ctx, cmd);
            world->record_readback(cmd, readback->handle(), 0);
        }));
        ASSERT_TRUE(recorded) << recorded.message();
        auto frame = world->collect(readback->mapped());
        ASSERT_TRUE(frame) << frame.message();
        ctx.retire(n);
        EXPECT_FALSE(frame->truncated) << "frame " << n;
        EXPECT_EQ(frame->static_slabs, n > 0) << "frame " << n;
        EXPECT_EQ(SlabScene::leaves(*world), scene.scratch(ctx, origin, VoxelizeMethod::Compute))
            << "frame " << n;
    }
    EXPECT_EQ(ctx.validation_messages(), 0u) << ctx.last_validation_message();
}

} // namespace
} // namespace gust::test
