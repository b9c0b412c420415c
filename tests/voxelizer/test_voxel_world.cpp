// Animated scenes through VoxelWorld: after every frame the tree's leaves equal a from-scratch
// voxelization of that frame's geometry, for every branching factor.
#include "support/gpu_env.hpp"

#include <algorithm>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <gust/scene/domain_grid.hpp>
#include <gust/scene/primitives.hpp>
#include <gust/scene/scene_runtime.hpp>
#include <gust/voxelizer/cpu_reference.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <memory>
#include <set>
#include <string>
#include <tuple>

namespace gust::test {
namespace {

/// Uploads every object of the scene into `world` (into `meshes`, which the instances point into) and
/// makes the static ones, posed at t = 0, its static set (`statics`).
void upload_scene(const SceneDesc& scene, SceneRuntime& runtime, VoxelWorld& world,
                  std::vector<GpuMesh>& meshes, std::vector<GpuInstance>& statics) {
    for (std::size_t i = 0; i < runtime.object_count(); ++i) {
        auto mesh = world.upload(view_of(runtime.mesh(i)));
        ASSERT_TRUE(mesh) << mesh.message();
        meshes.push_back(std::move(*mesh));
    }
    for (std::size_t i = 0; i < meshes.size(); ++i)
        if (scene.objects[i].is_static) statics.push_back({&meshes[i], runtime.model(i, 0.0)});
    world.set_static(statics);
}

/// This frame's dynamic instances of a scene at time t (deforming meshes posed), moving since t - stride.
std::vector<GpuInstance> dynamic_at(const SceneDesc& scene, SceneRuntime& runtime, VoxelWorld& world,
                                    std::vector<GpuMesh>& meshes, double t, double stride) {
    std::vector<GpuInstance> dynamic;
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        if (scene.objects[i].is_static) continue;
        if (runtime.deforms(i)) {
            EXPECT_TRUE(world.update_positions(meshes[i], runtime.positions(i, t)));
        }
        GpuInstance inst{&meshes[i], runtime.model(i, t)};
        inst.prev_model = runtime.model(i, t - stride);
        dynamic.push_back(inst);
    }
    return dynamic;
}

/// The voxels of a from-scratch voxelization of `statics` and `dynamic`, sorted and unique.
std::vector<std::uint32_t> scratch_voxels(Voxelizer& scratch, const std::vector<GpuInstance>& statics,
                                          const std::vector<GpuInstance>& dynamic, const GridDesc& grid) {
    std::vector<GpuInstance> everything = statics;
    everything.insert(everything.end(), dynamic.begin(), dynamic.end());
    EXPECT_TRUE(scratch.voxelize(everything, grid, VoxelizeMethod::Compute));
    auto fragments = scratch.read_fragments();
    EXPECT_TRUE(fragments);
    std::vector<std::uint32_t> voxels = fragments ? *fragments : std::vector<std::uint32_t>{};
    std::sort(voxels.begin(), voxels.end());
    voxels.erase(std::unique(voxels.begin(), voxels.end()), voxels.end());
    return voxels;
}

using Param = std::tuple<std::string, std::uint32_t>; // scene file, branching

class WorldMatchesScratch : public GpuTestWithParam<Param> {};

TEST_P(WorldMatchesScratch, afterEveryFrame) {
    const auto& [file, branching] = GetParam();
    auto scene = load_scene(std::string(GUST_ASSETS_DIR) + "/scenes/" + file);
    ASSERT_TRUE(scene) << scene.message();
    scene->domain.branching = branching;
    auto runtime = SceneRuntime::load(*scene);
    ASSERT_TRUE(runtime) << runtime.message();
    auto grid = domain_grid(scene->domain);
    ASSERT_TRUE(grid) << grid.message();

    WorldDesc desc;
    desc.grid = *grid;
    desc.method = VoxelizeMethod::Compute;
    desc.tree.branching = branching;
    desc.tree.hysteresis = 2;
    // Small pools so that growing them during the run is exercised too.
    desc.tree.node_blocks = 8;
    desc.tree.mask_blocks = 64;
    auto world = VoxelWorld::create(ctx(), desc);
    ASSERT_TRUE(world) << world.message();
    auto scratch = Voxelizer::create(ctx());
    ASSERT_TRUE(scratch);

    std::vector<GpuMesh> meshes;
    std::vector<GpuInstance> statics;
    ASSERT_NO_FATAL_FAILURE(upload_scene(*scene, *runtime, **world, meshes, statics));

    // Frames spread over three seconds of the animation, so the movers cross the whole scene.
    const int frames = 10;
    const double stride = 3.0 / frames;
    std::uint32_t growths = 0;
    for (int f = 0; f < frames; ++f) {
        const std::vector<GpuInstance> dynamic =
            dynamic_at(*scene, *runtime, **world, meshes, f * stride, stride);
        auto step = (*world)->step(dynamic, float(stride));
        ASSERT_TRUE(step) << step.message();
        EXPECT_EQ(step->static_rebuilt, f == 0 || step->pool_growths > 0);
        EXPECT_EQ(step->tree.exhausted, 0u);
        growths += step->pool_growths;

        const std::vector<std::uint32_t> expected = scratch_voxels(**scratch, statics, dynamic, *grid);
        const auto leaves = (*world)->tree().leaf_voxels();
        ASSERT_TRUE(leaves);
        ASSERT_EQ(std::vector<std::uint32_t>(leaves->begin(), leaves->end()), expected)
            << file << " frame " << f;
        EXPECT_EQ(step->tree.voxels, expected.size());
    }
    EXPECT_GT(growths, 0u);
}

INSTANTIATE_TEST_SUITE_P(Scenes, WorldMatchesScratch,
                         ::testing::Combine(::testing::Values("fox_bunnies.json", "dragon_wall_arch.json"),
                                            ::testing::Values(2u, 4u, 8u)),
                         [](const ::testing::TestParamInfo<Param>& p) {
                             std::string name =
                                 std::get<0>(p.param).substr(0, std::get<0>(p.param).find('.'));
                             name += "_b";
                             name += std::to_string(std::get<1>(p.param));
                             return name;
                         });

using WorldTest = GpuTest;

TEST_F(WorldTest, staticSetIsVoxelizedAgainOnlyWhenItChanges) {
    GridDesc grid;
    grid.res = 16;
    grid.voxel_size = 1.0f / 16.0f;
    WorldDesc desc;
    desc.grid = grid;
    desc.tree.branching = 2;
    auto world = VoxelWorld::create(ctx(), desc);
    ASSERT_TRUE(world);
    const Mesh box = make_box_mesh(glm::vec3(0.2f), glm::vec3(0.6f));
    auto mesh = (*world)->upload(view_of(box));
    ASSERT_TRUE(mesh);
    const GpuInstance still[] = {{&*mesh, glm::mat4(1.0f)}};
    (*world)->set_static(still);
    EXPECT_TRUE((*world)->step({}, 0.1f)->static_rebuilt);
    EXPECT_FALSE((*world)->step({}, 0.1f)->static_rebuilt);
    (*world)->set_static(still);
    EXPECT_FALSE((*world)->step({}, 0.1f)->static_rebuilt);
    glm::mat4 moved(1.0f);
    moved[3] = glm::vec4(0.1f, 0.0f, 0.0f, 1.0f);
    const GpuInstance shifted[] = {{&*mesh, moved}};
    (*world)->set_static(shifted);
    auto frame = (*world)->step({}, 0.1f);
    ASSERT_TRUE(frame);
    EXPECT_TRUE(frame->static_rebuilt);
    EXPECT_EQ(frame->frame, 3u);
    EXPECT_FALSE((*world)->step({}, 0.0f));
}

/// Frames in flight: recorded frames are read back `kFrames` frames later. The pools start too small, so
/// the first frames run out; collect() reports them as truncated and grows the pools, and every frame
/// recorded after the last truncated one was collected equals a from-scratch voxelization. The context
/// is the test's own, since begin_frame() switches a context to deferred releases for good.
TEST(WorldRecorded, growsWhatRanOutAndLaterFramesAreWhole) {
    constexpr std::uint64_t kFrames = 2;
    gpu::ContextDesc context_desc;
    context_desc.validation = true;
    auto context = gpu::Context::create(context_desc);
    ASSERT_TRUE(context) << context.message();
    gpu::Context& ctx = **context;
    auto scene = load_scene(std::string(GUST_ASSETS_DIR) + "/scenes/fox_bunnies.json");
    ASSERT_TRUE(scene) << scene.message();
    auto runtime = SceneRuntime::load(*scene);
    ASSERT_TRUE(runtime) << runtime.message();
    auto grid = domain_grid(scene->domain);
    ASSERT_TRUE(grid) << grid.message();
    WorldDesc desc;
    desc.grid = *grid;
    desc.method = VoxelizeMethod::Compute;
    desc.tree.branching = scene->domain.branching;
    desc.tree.node_blocks = 8;
    desc.tree.mask_blocks = 64;
    auto world = VoxelWorld::create(ctx, desc);
    ASSERT_TRUE(world) << world.message();
    auto scratch = Voxelizer::create(ctx);
    ASSERT_TRUE(scratch);
    std::vector<GpuMesh> meshes;
    std::vector<GpuInstance> statics;
    ASSERT_NO_FATAL_FAILURE(upload_scene(*scene, *runtime, **world, meshes, statics));

    std::vector<gpu::Buffer> readbacks;
    for (std::uint64_t i = 0; i < kFrames; ++i) {
        auto buffer = gpu::Buffer::create(ctx, VoxelWorld::readback_bytes(), gpu::MemoryUse::Readback);
        ASSERT_TRUE(buffer);
        readbacks.push_back(std::move(*buffer));
    }
    const std::uint64_t frames = 12;
    const double stride = 0.25;
    std::uint64_t whole_from = 0; // frames recorded from here on had every growth
    std::uint32_t truncated = 0;
    std::vector<bool> matches;
    const auto collect = [&](std::uint64_t n) {
        auto done = (*world)->collect(readbacks[n % kFrames].mapped());
        ASSERT_TRUE(done) << done.message();
        EXPECT_EQ(done->frame, n - kFrames);
        // The tree stamps its first update frame 1 and each recorded frame updates it once.
        EXPECT_EQ(done->tree.frame, std::uint32_t(n - kFrames + 1));
        if (done->truncated) {
            ++truncated;
            whole_from = n;
        }
        ctx.retire(n - kFrames);
    };
    for (std::uint64_t n = 0; n < frames; ++n) {
        if (n >= kFrames) collect(n);
        ctx.begin_frame(n);
        const std::vector<GpuInstance> dynamic =
            dynamic_at(*scene, *runtime, **world, meshes, double(n) * stride, stride);
        Status recorded;
        ASSERT_TRUE(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
            recorded = (*world)->record(cmd, dynamic, float(stride));
            gpu::barrier(ctx, cmd);
            (*world)->record_readback(cmd, readbacks[n % kFrames].handle(), 0);
        }));
        ASSERT_TRUE(recorded) << recorded.message();
        const std::vector<std::uint32_t> expected = scratch_voxels(**scratch, statics, dynamic, *grid);
        const auto leaves = (*world)->tree().leaf_voxels();
        ASSERT_TRUE(leaves);
        matches.push_back(std::equal(leaves->begin(), leaves->end(), expected.begin(), expected.end()));
    }
    for (std::uint64_t n = frames; n < frames + kFrames; ++n)
        collect(n);
    EXPECT_GT(truncated, 0u) << "the small pools ran out";
    EXPECT_FALSE(matches.front()) << "the first frame ran out, so its tree is partial";
    ASSERT_LE(whole_from + 3, frames) << "at least three frames recorded after the last growth";
    for (std::uint64_t n = whole_from; n < frames; ++n)
        EXPECT_TRUE(matches[n]) << "frame " << n << " was recorded after the pools grew";
    EXPECT_EQ(ctx.validation_messages(), 0u) << ctx.last_validation_message();
}

/// Issue 31's overflowing first frame, small: a box turned about two axes fills about 11,900 bricks of
/// 4^3 voxels on a 256^3 grid, where the default pools of branching 4 hold 4,095.
struct TurnedBox {
    TurnedBox() {
        grid.res = 256;
        grid.voxel_size = 1.0f / 256.0f;
        model = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f));
        model = glm::rotate(model, 0.35f, glm::vec3(0, 1, 0));
        model = glm::rotate(model, 0.25f, glm::vec3(1, 0, 0));
        const CpuVoxelization ref = voxelize_reference(cpu_instances(), grid);
        reference = ref.voxels;
    }
    std::vector<InstanceDesc> cpu_instances() const { return {{view_of(mesh), model}}; }
    /// The voxels of the tree of a fresh world after its first frame, blocking or recorded.
    std::vector<std::uint32_t> first_frame(gpu::Context& ctx, bool recorded, WorldFrame& frame) const {
        WorldDesc desc;
        desc.grid = grid;
        desc.method = VoxelizeMethod::Compute;
        auto world = VoxelWorld::create(ctx, desc);
        EXPECT_TRUE(world) << world.message();
        if (!world) return {};
        auto gpu_mesh = (*world)->upload(view_of(mesh));
        EXPECT_TRUE(gpu_mesh);
        const GpuInstance box{&*gpu_mesh, model};
        (*world)->set_static({&box, 1});
        if (recorded) {
            auto readback = gpu::Buffer::create(ctx, VoxelWorld::readback_bytes(), gpu::MemoryUse::Readback);
            EXPECT_TRUE(readback);
            ctx.begin_frame(1);
            Status status;
            EXPECT_TRUE(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
                status = (*world)->record(cmd, {}, 0.1f);
                gpu::barrier(ctx, cmd);
                (*world)->record_readback(cmd, readback->handle(), 0);
            }));
            EXPECT_TRUE(status) << status.message();
            auto done = (*world)->collect(readback->mapped());
            EXPECT_TRUE(done) << done.message();
            if (done) frame = *done;
            ctx.retire(1);
        } else {
            auto done = (*world)->step({}, 0.1f);
            EXPECT_TRUE(done) << done.message();
            if (done) frame = *done;
        }
        auto leaves = (*world)->tree().leaf_voxels();
        EXPECT_TRUE(leaves) << leaves.message();
        return leaves ? std::vector<std::uint32_t>(leaves->begin(), leaves->end())
                      : std::vector<std::uint32_t>{};
    }
    /// True when `voxels` equal the reference but for rounding on the boundary (diff_voxels).
    bool matches_reference(const std::vector<std::uint32_t>& voxels) const {
        const VoxelDiff diff = diff_voxels(voxels, reference);
        return unexplained_differences(diff, cpu_instances(), grid).empty() &&
               diff.missing.size() + diff.extra.size() < reference.size() / 1000;
    }

    GridDesc grid;
    Mesh mesh = make_box_mesh(glm::vec3(-0.3f), glm::vec3(0.3f));
    glm::mat4 model{1.0f};
    std::vector<std::uint32_t> reference;
};

TEST_F(WorldTest, firstFrameOfABoxThatOverflowsDefaultPoolsIsWholeAndTheSameEveryRun) {
    const TurnedBox box;
    std::set<std::uint32_t> bricks;
    for (std::uint32_t key : box.reference)
        bricks.insert(pack_voxel(unpack_voxel(key).x / 4, unpack_voxel(key).y / 4, unpack_voxel(key).z / 4));
    ASSERT_GT(bricks.size(), 4095u) << "the default pools would overflow";

    std::vector<std::uint32_t> runs[2];
    for (auto& run : runs) {
        WorldFrame frame;
        run = box.first_frame(ctx(), false, frame);
        EXPECT_EQ(frame.tree.exhausted, 0u);
        EXPECT_TRUE(frame.static_rebuilt);
        EXPECT_EQ(frame.tree.voxels, run.size());
        EXPECT_TRUE(box.matches_reference(run));
    }
    EXPECT_EQ(runs[0], runs[1]);
}

/// The same first frame recorded (frames in flight), which cannot be redone: the pools sized from the
/// box's mesh hold it whole. The context is the test's own, since begin_frame() is for good.
TEST(WorldRecorded, firstFrameOfABoxThatOverflowsDefaultPoolsIsWhole) {
    gpu::ContextDesc context_desc;
    context_desc.validation = true;
    auto context = gpu::Context::create(context_desc);
    ASSERT_TRUE(context) << context.message();
    const TurnedBox box;
    WorldFrame frame;
    const std::vector<std::uint32_t> voxels = box.first_frame(**context, true, frame);
    EXPECT_FALSE(frame.truncated);
    EXPECT_EQ(frame.tree.exhausted, 0u);
    EXPECT_GT(frame.pool_growths, 0u) << "grown from the estimate before the frame";
    EXPECT_TRUE(box.matches_reference(voxels));
    EXPECT_EQ((*context)->validation_messages(), 0u) << (*context)->last_validation_message();
}

} // namespace
} // namespace gust::test
