// The engine-facing C++ API (include/gust/gust.hpp), used as an engine would use it.
#include "host_vulkan.hpp"
#include "system_test_support.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <limits>
#include <link.h>
#include <set>
#include <string>
#include <unistd.h>
#if GUST_WITH_OPENVDB
#include <openvdb/openvdb.h>
#endif
#include <vector>

namespace gust::test {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST_F(SystemTest, stepsASceneAndReportsTheTreeAndTheSolve) {
    run_scene(*system_, 3);
    const FrameStats& stats = system_->stats();
    EXPECT_EQ(stats.frame, 2u);
    EXPECT_GT(stats.fragments, 0u);
    EXPECT_GT(stats.voxels, 0u);
    EXPECT_GT(stats.nodes, 1u);
    EXPECT_TRUE(stats.converged);
    EXPECT_LE(stats.divergence_after, 1e-4f * stats.divergence_before);
    EXPECT_GT(watch_.allocations, 0) << "the allocation hook was not used";
    // A blocking step is the frame a host's command buffer would hold: recorded once, one submission and
    // one wait, the moving box's voxelization included.
    EXPECT_EQ(stats.submissions, 1u);
    EXPECT_EQ(stats.waits, 1u);
    EXPECT_GT(stats.dispatches, 10u);
    EXPECT_EQ(stats.pool_growths, 0u) << "the pools hold the scene";
    ASSERT_NE(system_->device_name(), nullptr);
    EXPECT_GT(std::strlen(system_->device_name()), 0u);
}

// Growth after an overflow without extra waits: two slabs across a 16 m x 16 m domain need about 8,192 leaf
// bricks where the tree starts with 4,096. The blocking step's frame then runs out, says so (a warning), and
// grows the pools for the next frames, each still one submission and one wait; within a few frames the tree
// holds both slabs whole, and keeps them.
TEST(SystemGrowth, aTreePoolThatRunsOutGrowsForTheNextFramesWithoutExtraWaits) {
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.domain.cells[0] = 64;
    desc.domain.cells[1] = 8;
    desc.domain.cells[2] = 64;
    desc.domain.cell_size = 0.25f;
    desc.domain.voxels_per_cell = 4;
    desc.domain.focus = {0.0f, 1.0f, 0.0f};
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(desc, system));
    const Box box(1.0f);
    MeshId mesh = 0;
    ASSERT_TRUE(system->create_mesh(box.desc(), mesh));
    for (const float y : {0.5f, 1.5f}) {
        Mat4 slab = translation(0.0f, y, 0.0f);
        slab.m[0] = 7.9f;
        slab.m[5] = 0.02f;
        slab.m[10] = 7.9f;
        InstanceId id = 0;
        ASSERT_TRUE(system->create_instance(mesh, slab, false, id));
    }
    std::vector<std::uint64_t> voxels;
    std::vector<std::uint32_t> exhausted, growths;
    for (int f = 0; f < 5; ++f) {
        ASSERT_TRUE(system->step(0.05f));
        const FrameStats& st = system->stats();
        EXPECT_EQ(st.submissions, 1u) << "frame " << f;
        EXPECT_EQ(st.waits, 1u) << "frame " << f;
        voxels.push_back(st.voxels);
        exhausted.push_back(st.exhausted);
        growths.push_back(st.pool_growths);
    }
    EXPECT_GT(exhausted.front(), 0u) << "the first frame needs more than the initial pools";
    EXPECT_GE(watch.warnings, 1) << "a partial frame is reported";
    EXPECT_EQ(exhausted.back(), 0u);
    for (int f = 0; f < 5; ++f)
        EXPECT_EQ(growths[f], exhausted[f] > 0 ? 1u : 0u)
            << "frame " << f << ": a frame that ran out grows once";
    EXPECT_EQ(voxels[3], voxels[4]) << "once grown, every frame holds the same slabs";
    EXPECT_GT(voxels[4], voxels[0]) << "the grown tree holds what the first frame lost";
    EXPECT_GT(voxels[4], 2u * 250u * 250u) << "both slabs, about 256 x 256 voxels each";
}

// Only what the wind reads is voxelized and kept in the tree: a box above the domain's top (y 0..8 m), inside
// the tree's power-of-b grid (64 voxels of 0.5 m from y = 0), adds no fragment and no voxel; moved into the
// domain it adds its surface.
TEST_F(SystemTest, surfaceBeyondTheWindDomainIsNotVoxelized) {
    MeshId mesh = 0;
    ASSERT_TRUE(system_->create_mesh(box_.desc(), mesh));
    InstanceId box = 0;
    ASSERT_TRUE(system_->create_instance(mesh, translation(0.0f, 12.0f, 0.0f), true, box));
    ASSERT_TRUE(system_->step(0.05f));
    EXPECT_EQ(system_->stats().fragments, 0u);
    EXPECT_EQ(system_->stats().voxels, 0u);
    ASSERT_TRUE(system_->set_transform(box, translation(0.0f, 4.0f, 0.0f), true));
    ASSERT_TRUE(system_->step(0.05f));
    EXPECT_GT(system_->stats().fragments, 0u);
    EXPECT_GT(system_->stats().voxels, 0u);
}

// The API's default is a game's fixed budget (WindSettings::cycles_per_step = 2): every step runs at most
// two V-cycles whatever the scene asks, reports honestly whether that met the tolerance, and the warm start
// carries the rest, so the divergence left falls from step to step while nothing changes.
TEST_F(SystemTest, theDefaultIsAFixedBudgetOfTwoVCyclesAStep) {
    ASSERT_EQ(WindSettings{}.cycles_per_step, 2u);
    SystemDesc desc = small_desc(watch_);
    desc.wind = WindSettings{};
    desc.wind.tolerance = 1e-7f; // tighter than two cycles reach, so the budget binds
    std::unique_ptr<System> budget;
    ASSERT_TRUE(System::create(desc, budget));
    MeshId mesh = 0;
    ASSERT_TRUE(budget->create_mesh(box_.desc(), mesh));
    InstanceId fixed = 0;
    ASSERT_TRUE(budget->create_instance(mesh, translation(-1.0f, 2.0f, 0.0f), false, fixed));
    ASSERT_TRUE(budget->set_ambient({3.0f, 0.0f, 0.0f}));
    std::vector<float> left;
    for (int f = 0; f < 6; ++f) {
        ASSERT_TRUE(budget->step(0.05f));
        const FrameStats& s = budget->stats();
        EXPECT_LE(s.cycles, 2u) << "frame " << f;
        EXPECT_EQ(s.converged, s.residual <= desc.wind.tolerance * s.divergence_before) << "frame " << f;
        left.push_back(s.divergence_after);
    }
    EXPECT_LT(left.back(), 0.5f * left[1]) << "the warm start carries what each step left";
}

// An instance created in motion (create_moving_instance) pushes still air in its first step, as its motion
// from `previous` says (0.5 m in 0.05 s: 10 m/s); one created and then moved (create_instance, set_transform)
// pushes none then, since it has no motion before its first step: the air stays still, without divergence.
TEST_F(SystemTest, anInstanceCreatedInMotionPushesTheAirInItsFirstStep) {
    const auto first_divergence = [&](System& system, bool in_motion) {
        MeshId mesh = 0;
        EXPECT_TRUE(system.create_mesh(box_.desc(), mesh));
        InstanceId box = 0;
        const Mat4 at = translation(0.5f, 4.0f, 0.0f), before = translation(0.0f, 4.0f, 0.0f);
        if (in_motion) {
            EXPECT_TRUE(system.create_moving_instance(mesh, at, before, box));
        } else {
            EXPECT_TRUE(system.create_instance(mesh, before, true, box));
            EXPECT_TRUE(system.set_transform(box, at));
        }
        EXPECT_TRUE(system.step(0.05f));
        return system.stats().divergence_before;
    };
    EXPECT_GT(first_divergence(*system_, true), 1.0f) << "1/s: a 10 m/s surface against air at rest";
    std::unique_ptr<System> placed;
    ASSERT_TRUE(System::create(small_desc(watch_), placed));
    EXPECT_LT(first_divergence(*placed, false), 1e-6f);

    const Mat4 nan = translation(kNaN, 0.0f, 0.0f);
    MeshId mesh = 0;
    ASSERT_TRUE(system_->create_mesh(box_.desc(), mesh));
    InstanceId id = 7;
    EXPECT_EQ(system_->create_moving_instance(mesh, Mat4{}, nan, id).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(id, 0u);
    EXPECT_EQ(system_->create_moving_instance(mesh, nan, Mat4{}, id).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->create_moving_instance(0, Mat4{}, Mat4{}, id).code(), ErrorCode::InvalidHandle);
}

// The Jacobi baseline (WindSettings::pressure) relaxes in blocks of 8 iterations up to max_iterations, which
// max_cycles (a bound on V-cycles) does not cap; it starts from zero every step, so 24 iterations leave the
// solve short of a tight tolerance.
TEST_F(SystemTest, theJacobiBaselineRunsUpToMaxIterationsInBlocksOfEight) {
    SystemDesc desc = small_desc(watch_);
    desc.wind.pressure = WindPressure::Jacobi;
    desc.wind.max_iterations = 24;
    desc.wind.max_cycles = 2;
    desc.wind.tolerance = 1e-7f;
    std::unique_ptr<System> jacobi;
    ASSERT_TRUE(System::create(desc, jacobi));
    run_scene(*jacobi, 2);
    const FrameStats& stats = jacobi->stats();
    EXPECT_EQ(stats.cycles, 24u);
    EXPECT_FALSE(stats.converged);
    EXPECT_LT(stats.divergence_after, stats.divergence_before);
}

// SystemDesc::pipeline_cache: the file is written when the System is destroyed (not before), and a System
// created from it runs as before.
TEST(SystemPipelineCache, isWrittenWhenTheSystemIsDestroyedAndServesTheNext) {
    const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                       ("gust_system_pipelines_" + std::to_string(::getpid()) + ".bin");
    std::filesystem::remove(file);
    for (int run = 0; run < 2; ++run) {
        Watch watch;
        SystemDesc desc = small_desc(watch);
        desc.pipeline_cache = file.c_str();
        std::unique_ptr<System> system;
        ASSERT_TRUE(System::create(desc, system));
        EXPECT_EQ(std::filesystem::exists(file), run > 0) << "run " << run;
        ASSERT_TRUE(system->step(0.05f));
        system.reset();
        EXPECT_EQ(watch.errors + watch.warnings, 0) << watch.last;
        ASSERT_TRUE(std::filesystem::is_regular_file(file)) << "run " << run;
        EXPECT_GT(std::filesystem::file_size(file), 0u);
    }
    std::filesystem::remove(file);
}

TEST_F(SystemTest, pointsOutsideTheDomainGetTheAmbientWindExactly) {
    run_scene(*system_, 2);
    const Vec3 points[] = {{100.0f, 4.0f, 0.0f}, {0.0f, -50.0f, 0.0f}, {0.0f, 4.0f, 1e6f}};
    Vec3 wind[3];
    ASSERT_TRUE(system_->query(points, wind));
    for (const Vec3& w : wind) {
        EXPECT_EQ(w.x, 3.0f);
        EXPECT_EQ(w.y, 0.0f);
        EXPECT_EQ(w.z, 0.0f);
    }
}

TEST_F(SystemTest, anEmptyDomainCarriesTheAmbientWind) {
    ASSERT_TRUE(system_->set_ambient({2.0f, 0.0f, 1.0f}));
    ASSERT_TRUE(system_->step(0.05f));
    const Vec3 points[] = {{0.0f, 4.0f, 0.0f}, {-5.5f, 1.2f, 6.1f}, {7.9f, 7.9f, -7.9f}};
    Vec3 wind[3];
    ASSERT_TRUE(system_->query(points, wind));
    for (const Vec3& w : wind) {
        EXPECT_NEAR(w.x, 2.0f, 1e-3f);
        EXPECT_NEAR(w.y, 0.0f, 1e-3f);
        EXPECT_NEAR(w.z, 1.0f, 1e-3f);
    }
}

TEST_F(SystemTest, theWindBendsAroundABoxAndSlowsBehindIt) {
    run_scene(*system_, 8);
    const Vec3 points[] = {{-5.5f, 2.0f, 0.0f}, {-3.0f, 2.0f, 2.2f}, {-3.0f, 5.0f, -6.0f}};
    Vec3 wind[3];
    ASSERT_TRUE(system_->query(points, wind));
    EXPECT_LT(std::abs(wind[0].x), 2.5f) << "air just upwind of the box is held back";
    EXPECT_GT(wind[1].x, wind[0].x) << "air beside the box moves faster than air in front of it";
}

TEST_F(SystemTest, asynchronousQueriesAreAnsweredByTheNextStep) {
    run_scene(*system_, 2);
    const Vec3 points[] = {{1.0f, 3.0f, 1.0f}, {-2.0f, 2.0f, 3.0f}};
    QueryId id = 0;
    ASSERT_TRUE(system_->query_async(points, id));
    Vec3 answer[2];
    EXPECT_EQ(system_->fetch(id, answer).code(), ErrorCode::NotReady);
    ASSERT_TRUE(system_->step(0.05f));
    Vec3 now[2];
    ASSERT_TRUE(system_->query(points, now));
    ASSERT_TRUE(system_->fetch(id, answer));
    for (int i = 0; i < 2; ++i) {
        EXPECT_EQ(answer[i].x, now[i].x);
        EXPECT_EQ(answer[i].y, now[i].y);
        EXPECT_EQ(answer[i].z, now[i].z);
    }
    EXPECT_EQ(system_->fetch(id, answer).code(), ErrorCode::InvalidHandle) << "an answer is fetched once";
}

TEST_F(SystemTest, windAtGivesDirectionSpeedAndGust) {
    ASSERT_TRUE(system_->set_ambient({0.0f, 0.0f, -4.0f}));
    ASSERT_TRUE(system_->step(0.05f));
    WindSample calm;
    ASSERT_TRUE(system_->wind_at({1.0f, 4.0f, 1.0f}, calm));
    EXPECT_NEAR(calm.speed, 4.0f, 1e-3f);
    EXPECT_NEAR(calm.direction.z, -1.0f, 1e-4f);
    EXPECT_NEAR(calm.gust, 0.0f, 1e-3f) << "uniform wind has no gust";
    const WindEmitter fan{WindEmitterType::Omni, {1.0f, 4.0f, 1.0f}, {1, 0, 0}, 3.0f, 8.0f, 1.0f, 0.0f};
    ASSERT_TRUE(system_->set_emitters({&fan, 1}));
    for (int i = 0; i < 5; ++i)
        ASSERT_TRUE(system_->step(0.05f));
    WindSample gusty;
    ASSERT_TRUE(system_->wind_at({2.5f, 4.0f, 1.0f}, gusty));
    EXPECT_GT(gusty.gust, 0.05f) << "beside a fan the wind varies from cell to cell";
}

TEST_F(SystemTest, theFocusScrollsTheDomainInWholeCells) {
    const Vec3 before = system_->domain_origin();
    ASSERT_TRUE(system_->set_focus({3.4f, 4.0f, -2.6f}));
    ASSERT_TRUE(system_->step(0.05f));
    const Vec3 after = system_->domain_origin();
    EXPECT_EQ(after.x - before.x, 3.0f);
    EXPECT_EQ(after.y - before.y, 0.0f);
    EXPECT_EQ(after.z - before.z, -3.0f);
    const Mat4& m = system_->wind_texture().world_to_texture;
    EXPECT_NEAR(m.m[0] * after.x + m.m[12], 0.0f, 1e-6f) << "the texture follows the domain";
}

TEST_F(SystemTest, theWindTextureCoversTheDomain) {
    ASSERT_TRUE(system_->step(0.05f));
    const WindTexture& t = system_->wind_texture();
    EXPECT_NE(t.image, VK_NULL_HANDLE);
    EXPECT_NE(t.view, VK_NULL_HANDLE);
    EXPECT_NE(t.sampler, VK_NULL_HANDLE);
    EXPECT_EQ(t.extent[0], 16u);
    EXPECT_EQ(t.extent[1], 8u);
    EXPECT_EQ(t.extent[2], 16u);
    const Vec3 lo = system_->domain_origin();
    const float hi[3] = {lo.x + 16.0f, lo.y + 8.0f, lo.z + 16.0f};
    const float lo_[3] = {lo.x, lo.y, lo.z};
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(t.world_to_texture.m[a * 5] * lo_[a] + t.world_to_texture.m[12 + a], 0.0f, 1e-6f);
        EXPECT_NEAR(t.world_to_texture.m[a * 5] * hi[a] + t.world_to_texture.m[12 + a], 1.0f, 1e-6f);
    }
}

#if GUST_WITH_OPENVDB
TEST_F(SystemTest, exportsTheFrameAsOpenVdb) {
    run_scene(*system_, 2);
    const std::filesystem::path path = std::filesystem::temp_directory_path() / "gust_plugin_export.vdb";
    ASSERT_TRUE(system_->export_vdb(path.c_str()));
    openvdb::initialize();
    openvdb::io::File file(path.string());
    file.open();
    for (const char* name : {"occupancy", "solid", "velocity", "pressure"})
        EXPECT_TRUE(file.hasGrid(name)) << name;
    file.close();
    std::filesystem::remove(path);
    EXPECT_EQ(system_->export_vdb("/nonexistent-dir/x.vdb").code(), ErrorCode::IoError);
}
#else
TEST_F(SystemTest, exportRefusesClearlyWhenBuiltWithoutOpenVdb) {
    run_scene(*system_, 1);
    const std::filesystem::path path = std::filesystem::temp_directory_path() / "gust_plugin_export.vdb";
    const Outcome exported = system_->export_vdb(path.c_str());
    EXPECT_EQ(exported.code(), ErrorCode::Unsupported);
    EXPECT_NE(exported.message().find("built without OpenVDB"), std::string::npos) << exported.message();
    EXPECT_FALSE(std::filesystem::exists(path)) << "nothing is written";
}
#endif

TEST_F(SystemTest, rejectsBadMeshesWithAClearError) {
    MeshId id = 0;
    MeshDesc d = box_.desc();
    d.positions = nullptr;
    EXPECT_EQ(system_->create_mesh(d, id).code(), ErrorCode::InvalidArgument);
    d = box_.desc();
    d.stride = 8;
    EXPECT_EQ(system_->create_mesh(d, id).code(), ErrorCode::InvalidArgument);
    std::vector<std::uint32_t> bad = box_.indices;
    bad[4] = 8;
    d = box_.desc();
    d.indices = bad.data();
    const Outcome out_of_range = system_->create_mesh(d, id);
    EXPECT_EQ(out_of_range.code(), ErrorCode::InvalidArgument);
    EXPECT_NE(out_of_range.message().find("8"), std::string::npos) << out_of_range.message();
    std::vector<float> nan = box_.positions;
    nan[5] = kNaN;
    d = box_.desc();
    d.positions = nan.data();
    EXPECT_EQ(system_->create_mesh(d, id).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(id, 0u);
}

TEST_F(SystemTest, rejectsBadHandlesTransformsAndVertexArrays) {
    MeshId mesh = 0, deforming = 0;
    ASSERT_TRUE(system_->create_mesh(box_.desc(), mesh));
    ASSERT_TRUE(system_->create_mesh(box_.desc(true), deforming));
    InstanceId instance = 0;
    Mat4 nan = translation(0, 0, 0);
    nan.m[13] = kNaN;
    EXPECT_EQ(system_->create_instance(mesh, nan, true, instance).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->create_instance(999, Mat4{}, true, instance).code(), ErrorCode::InvalidHandle);
    ASSERT_TRUE(system_->create_instance(mesh, Mat4{}, true, instance));
    EXPECT_EQ(system_->set_transform(instance, nan).code(), ErrorCode::InvalidArgument);
    Mat4 projective = translation(0, 0, 0);
    projective.m[3] = 1.0f;
    projective.m[15] = 0.0f;
    EXPECT_EQ(system_->set_transform(instance, projective).code(), ErrorCode::InvalidArgument)
        << "not affine";
    InstanceId refused = 0;
    EXPECT_EQ(system_->create_instance(mesh, projective, false, refused).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->destroy_mesh(mesh).code(), ErrorCode::InvalidHandle) << "a mesh in use stays";
    ASSERT_TRUE(system_->destroy_instance(instance));
    EXPECT_EQ(system_->destroy_instance(instance).code(), ErrorCode::InvalidHandle);
    EXPECT_EQ(system_->set_transform(instance, Mat4{}).code(), ErrorCode::InvalidHandle);
    ASSERT_TRUE(system_->destroy_mesh(mesh));
    EXPECT_EQ(system_->create_instance(mesh, Mat4{}, false, instance).code(), ErrorCode::InvalidHandle);

    EXPECT_EQ(system_->set_vertices(deforming, box_.positions.data(), 7).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->set_vertices(mesh, box_.positions.data(), 8).code(), ErrorCode::InvalidHandle);
    std::vector<float> moved = box_.positions;
    for (float& p : moved)
        p *= 1.5f;
    ASSERT_TRUE(system_->create_instance(deforming, Mat4{}, false, instance));
    ASSERT_TRUE(system_->set_vertices(deforming, moved.data(), 8));
    moved[0] = kNaN;
    EXPECT_EQ(system_->set_vertices(deforming, moved.data(), 8).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->set_vertices(deforming, VkBuffer(VK_NULL_HANDLE), 0, 8).code(),
              ErrorCode::InvalidArgument)
        << "buffers need a host device";
    ASSERT_TRUE(system_->step(0.05f));
    EXPECT_GT(system_->stats().voxels, 0u);
}

TEST_F(SystemTest, rejectsBadTimeStepsPointsAndEmittersAndKeepsWorking) {
    for (float dt : {0.0f, -0.01f, kNaN, std::numeric_limits<float>::infinity(), 1e9f})
        EXPECT_EQ(system_->step(dt).code(), ErrorCode::InvalidArgument) << dt;
    const Vec3 points[] = {{0, 0, 0}, {kNaN, 0, 0}};
    Vec3 wind[2];
    const Outcome nan_point = system_->query(points, wind);
    EXPECT_EQ(nan_point.code(), ErrorCode::InvalidArgument);
    EXPECT_NE(nan_point.message().find("point 1"), std::string::npos) << nan_point.message();
    EXPECT_EQ(system_->query({points, 1}, wind).code(), ErrorCode::InvalidArgument) << "wrong output size";
    QueryId id = 0;
    EXPECT_EQ(system_->query_async(points, id).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->fetch(12345, wind).code(), ErrorCode::InvalidHandle);
    WindEmitter bad{WindEmitterType::Vortex, {0, 0, 0}, {0, 1, 0}, 2.0f, kNaN, 1.0f, 0.0f};
    EXPECT_EQ(system_->set_emitters({&bad, 1}).code(), ErrorCode::InvalidArgument);
    bad.strength = 1.0f;
    bad.type = WindEmitterType(42);
    EXPECT_EQ(system_->set_emitters({&bad, 1}).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->set_ambient({kNaN, 0, 0}).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->set_focus({0, kNaN, 0}).code(), ErrorCode::InvalidArgument);
    // A focus the next step could not scroll to is refused at once, keeping the old one (it made every later
    // step fail).
    EXPECT_EQ(system_->set_focus({2e6f, 0, 0}).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->set_focus({0, 0, -1e30f}).code(), ErrorCode::InvalidArgument);
    // Far from the world's origin floats cannot place voxels (1 m cells here: 2^19 m), however it is reached.
    ASSERT_TRUE(system_->set_focus({0, 0, 524000.0f}));
    EXPECT_EQ(system_->set_focus({0, 0, 525000.0f}).code(), ErrorCode::InvalidArgument);
    ASSERT_TRUE(system_->set_focus({0, 4, 0}));
    EXPECT_EQ(system_->step(0.05f, VK_NULL_HANDLE).code(), ErrorCode::InvalidArgument) << "own-queue system";
    EXPECT_EQ(system_->export_vdb(nullptr).code(), ErrorCode::InvalidArgument);
    ASSERT_TRUE(system_->step(0.05f));
}

/// Paths of the shared objects the process holds.
std::set<std::string> loaded_objects() {
    std::set<std::string> names;
    dl_iterate_phdr(
        [](dl_phdr_info* info, std::size_t, void* out) {
            if (info->dlpi_name && info->dlpi_name[0] != '\0')
                static_cast<std::set<std::string>*>(out)->insert(info->dlpi_name);
            return 0;
        },
        &names);
    return names;
}

// The Vulkan loader unloads its drivers with the last instance, and glibc never gives back a library's
// static TLS: an NVIDIA driver loaded again and again ran out of it at the 30th System of one process, and
// vkCreateInstance found no driver. A System that goes leaves every library it brought loaded.
TEST(SystemCreate, aDestroyedSystemLeavesTheDriversItLoadedForTheNext) {
    Watch watch;
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(small_desc(watch), system));
    const std::set<std::string> living = loaded_objects();
    system.reset();
    const std::set<std::string> after = loaded_objects();
    for (const std::string& name : living)
        EXPECT_TRUE(after.count(name)) << name << " was unloaded with the System";
    ASSERT_TRUE(System::create(small_desc(watch), system));
    system.reset();
    EXPECT_EQ(loaded_objects(), after) << "the next System loads nothing again";
    EXPECT_EQ(watch.errors, 0) << watch.last;
}

TEST(SystemCreate, rejectsAnotherHeaderVersionAndBadDescriptions) {
    Watch watch;
    std::unique_ptr<System> system;
    SystemDesc desc = small_desc(watch);
    desc.domain.focus = {1e30f, 0.0f, 0.0f};
    const Outcome far = System::create(desc, system);
    EXPECT_EQ(far.code(), ErrorCode::InvalidArgument) << "a focus of 1e30 put every voxel in the wrong place";
    EXPECT_NE(far.message().find("domain.focus"), std::string::npos) << far.message();
    desc = small_desc(watch);
    desc.header_version = kHeaderVersion + (1u << 12);
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::VersionMismatch);
    desc = small_desc(watch);
    desc.domain.cells[1] = 4;
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc = small_desc(watch);
    desc.domain.branching = 3;
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc = small_desc(watch);
    desc.domain.focus.x = kNaN;
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc = small_desc(watch);
    desc.hooks.free = nullptr;
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc = small_desc(watch);
    desc.submission = Submission::HostCommands;
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument) << "host commands need a host";
    for (std::uint32_t frames : {0u, 9u}) {
        HostVulkan host;
        ASSERT_TRUE(host.ok()) << host.error();
        desc = small_desc(watch);
        desc.host = &host.device();
        desc.submission = Submission::HostCommands;
        desc.frames_in_flight = frames;
        EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument) << frames << " in flight";
    }
    desc = small_desc(watch);
    desc.wind.advection = WindAdvection(3);
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc = small_desc(watch);
    desc.wind.pressure = WindPressure(3);
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc = small_desc(watch);
    desc.wind.pressure = WindPressure::Jacobi;
    desc.wind.max_iterations = 0;
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc = small_desc(watch);
    desc.device = "no such device";
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::DeviceUnsupported);
    EXPECT_EQ(system, nullptr);
    desc = small_desc(watch);
    const HostDevice empty_host{};
    desc.host = &empty_host;
    const Outcome null_host = System::create(desc, system);
    EXPECT_EQ(null_host.code(), ErrorCode::InvalidArgument) << "null handles are bad arguments";
    EXPECT_NE(std::string(null_host.message()).find("must not be null"), std::string::npos)
        << null_host.message();
    EXPECT_EQ(system, nullptr);
    EXPECT_EQ(watch.live, 0);
    EXPECT_EQ(library_version(), kHeaderVersion);
}

/// The same scene on gust's own device, on a device the test creates as a host, and recorded into the
/// host's command buffers with two frames in flight: the same wind.
TEST(SystemHostDevice, givesTheSameWindAsItsOwnDeviceInBothSubmissionModes) {
    const Vec3 points[] = {{-5.5f, 2.0f, 0.0f}, {-3.0f, 2.0f, 2.2f}, {3.0f, 3.5f, 1.0f}, {0.0f, 6.0f, -4.0f}};
    Vec3 wind[3][4];
    HostVulkan host;
    ASSERT_TRUE(host.ok()) << host.error();
    ASSERT_TRUE(host.start_frames(2));
    for (int mode = 0; mode < 3; ++mode) {
        Watch watch;
        SystemDesc desc = small_desc(watch);
        desc.voxelize = VoxelizePath::Compute; // Auto may pick another path per run
        if (mode > 0) desc.host = &host.device();
        if (mode == 2) desc.submission = Submission::HostCommands;
        std::unique_ptr<System> system;
        const Outcome created = System::create(desc, system);
        ASSERT_TRUE(created) << created.message();
        Box box(1.0f);
        MeshId mesh = 0;
        InstanceId fixed = 0, moving = 0;
        ASSERT_TRUE(system->create_mesh(box.desc(), mesh));
        ASSERT_TRUE(system->create_instance(mesh, translation(-3.0f, 2.0f, 0.0f), false, fixed));
        ASSERT_TRUE(system->create_instance(mesh, translation(3.0f, 2.0f, 0.0f), true, moving));
        ASSERT_TRUE(system->set_ambient({3.0f, 0.0f, 0.0f}));
        for (int f = 0; f < 4; ++f) {
            ASSERT_TRUE(system->set_transform(moving, translation(3.0f, 2.0f, 0.5f * float(f))));
            if (mode < 2) {
                ASSERT_TRUE(system->step(0.05f));
                continue;
            }
            EXPECT_EQ(system->step(0.05f).code(), ErrorCode::InvalidArgument)
                << "host commands: step(dt, commands)";
            VkCommandBuffer commands = host.begin_frame();
            ASSERT_NE(commands, VK_NULL_HANDLE);
            const Outcome stepped = system->step(0.05f, commands);
            ASSERT_TRUE(host.submit_frame());
            ASSERT_TRUE(stepped) << stepped.message();
        }
        ASSERT_TRUE(host.finish_frames());
        ASSERT_TRUE(system->query(points, wind[mode]));
        system.reset();
        EXPECT_EQ(watch.errors, 0) << watch.last;
    }
    for (int mode = 1; mode < 3; ++mode)
        for (int i = 0; i < 4; ++i) {
            EXPECT_NEAR(wind[mode][i].x, wind[0][i].x, 1e-4f) << "mode " << mode << " point " << i;
            EXPECT_NEAR(wind[mode][i].y, wind[0][i].y, 1e-4f) << "mode " << mode << " point " << i;
            EXPECT_NEAR(wind[mode][i].z, wind[0][i].z, 1e-4f) << "mode " << mode << " point " << i;
        }
    EXPECT_EQ(host.messages(), 0);
}

/// A System recording into a host's frames, `frames` in flight.
class HostFrames : public ::testing::Test {
  protected:
    void start(std::uint32_t frames, bool snapshot = false) {
        ASSERT_TRUE(host_.ok()) << host_.error();
        ASSERT_TRUE(host_.start_frames(frames));
        SystemDesc desc = small_desc(watch_);
        desc.voxelize = VoxelizePath::Compute;
        desc.host = &host_.device();
        desc.submission = Submission::HostCommands;
        desc.frames_in_flight = frames;
        desc.snapshot = snapshot;
        const Outcome created = System::create(desc, system_);
        ASSERT_TRUE(created) << created.message();
    }
    /// Records one step into the next host frame and submits it.
    void frame() {
        VkCommandBuffer commands = host_.begin_frame();
        ASSERT_NE(commands, VK_NULL_HANDLE);
        const Outcome stepped = system_->step(0.05f, commands);
        ASSERT_TRUE(host_.submit_frame());
        ASSERT_TRUE(stepped) << stepped.message();
    }
    void TearDown() override {
        EXPECT_TRUE(host_.finish_frames());
        system_.reset();
        EXPECT_EQ(watch_.errors, 0) << watch_.last;
        EXPECT_EQ(host_.messages(), 0);
    }

    HostVulkan host_;
    Watch watch_;
    std::unique_ptr<System> system_;
};

// Destroying a System right after the engine submitted the frames it recorded: the destructor waits for the
// queue it was given, so nothing it destroys is still in use (45 validation errors, then a crash in the
// driver, before it waited).
TEST_F(HostFrames, destroyingTheSystemWithFramesInFlightWaitsForThem) {
    start(2);
    Box box(1.0f);
    MeshId mesh = 0;
    InstanceId instance = 0;
    ASSERT_TRUE(system_->create_mesh(box.desc(), mesh));
    ASSERT_TRUE(system_->create_instance(mesh, translation(0.0f, 2.0f, 0.0f), true, instance));
    ASSERT_TRUE(system_->set_ambient({2.0f, 0.0f, 1.0f}));
    frame();
    frame();
    system_.reset();
    EXPECT_EQ(host_.messages(), 0);
}

// With frames in flight the snapshot of frame n is published when its slot comes round again, as the stats:
// frames_in_flight steps later, without a wait.
TEST_F(HostFrames, theSnapshotArrivesFramesInFlightStepsLater) {
    start(2, true);
    ASSERT_TRUE(system_->set_ambient({2.0f, 0.0f, 1.0f}));
    const Vec3 points[] = {{0.0f, 4.0f, 0.0f}, {100.0f, 4.0f, 0.0f}};
    Vec3 out[2];
    SnapshotInfo info;
    frame();
    frame();
    EXPECT_EQ(system_->sample(points, out, info).code(), ErrorCode::NotReady);
    frame();
    ASSERT_TRUE(system_->sample(points, out, info));
    EXPECT_EQ(info.frame, 1u);
    EXPECT_FLOAT_EQ(out[1].x, 2.0f) << "outside the domain: the ambient wind";
    EXPECT_FLOAT_EQ(out[1].z, 1.0f);
    frame();
    ASSERT_TRUE(system_->sample(points, out, info));
    EXPECT_EQ(info.frame, 2u);
    EXPECT_TRUE(std::isfinite(out[0].x) && std::isfinite(out[0].y) && std::isfinite(out[0].z));
}

// An engine that asks and never fetches does not grow gust's memory for the rest of its session: an answer
// left 64 frames is dropped, with a warning, and its ticket is dead.
TEST_F(SystemTest, anAnswerNeverFetchedIsDroppedAfterSixtyFourFrames) {
    const Vec3 points[] = {{0.0f, 1.0f, 0.0f}};
    QueryId kept = 0, abandoned = 0;
    ASSERT_TRUE(system_->query_async(points, abandoned));
    for (int frame = 0; frame < 64; ++frame) {
        ASSERT_TRUE(system_->step(0.05f));
        if (frame == 62) {
            ASSERT_TRUE(system_->query_async(points, kept));
        }
    }
    EXPECT_EQ(watch_.warnings, 0) << "63 frames after its answer the ticket is still good";
    ASSERT_TRUE(system_->step(0.05f));
    EXPECT_GE(watch_.warnings, 1);
    Vec3 answer[1];
    EXPECT_EQ(system_->fetch(abandoned, answer).code(), ErrorCode::InvalidHandle);
    EXPECT_TRUE(system_->fetch(kept, answer));
    watch_.warnings = 0; // the one expected
}

TEST_F(HostFrames, statsAndAsyncAnswersArriveFramesInFlightStepsLater) {
    const std::uint32_t frames = 3;
    start(frames);
    Box box(1.0f);
    MeshId mesh = 0;
    InstanceId instance = 0;
    ASSERT_TRUE(system_->create_mesh(box.desc(), mesh));
    ASSERT_TRUE(system_->create_instance(mesh, translation(0.0f, 2.0f, 0.0f), true, instance));
    const Vec3 ambient{2.0f, 0.0f, 1.0f};
    ASSERT_TRUE(system_->set_ambient(ambient));
    const Vec3 points[] = {{500.0f, 0.0f, 0.0f}, {-4.0f, 2.0f, 0.0f}};
    QueryId id = 0;
    ASSERT_TRUE(system_->query_async(points, id));
    Vec3 answer[2];
    for (std::uint32_t step = 0; step < frames + 2; ++step) {
        frame();
        if (step < frames) {
            EXPECT_EQ(system_->fetch(id, answer).code(), ErrorCode::NotReady) << "after step " << step;
            EXPECT_EQ(system_->stats().voxels, 0u) << "no frame has completed by step " << step;
        } else {
            EXPECT_EQ(system_->stats().frame, step - frames)
                << "the frame recorded " << frames << " steps ago";
            EXPECT_GT(system_->stats().voxels, 0u);
        }
        if (step == frames) {
            ASSERT_TRUE(system_->fetch(id, answer));
            EXPECT_EQ(answer[0].x, ambient.x);
            EXPECT_EQ(answer[0].z, ambient.z);
            EXPECT_TRUE(std::isfinite(answer[1].x) && std::isfinite(answer[1].y) &&
                        std::isfinite(answer[1].z));
            EXPECT_GT(answer[1].x, 0.5f) << "the ambient wind blows through the domain";
        }
    }

    // Per-pass GPU timings come back with the frame's stats: the passes a blocking step on gust's own
    // queue times, in its order.
    std::unique_ptr<System> own;
    SystemDesc desc = small_desc(watch_);
    desc.voxelize = VoxelizePath::Compute;
    ASSERT_TRUE(System::create(desc, own));
    MeshId own_mesh = 0;
    ASSERT_TRUE(own->create_mesh(box.desc(), own_mesh));
    ASSERT_TRUE(own->create_instance(own_mesh, translation(0.0f, 2.0f, 0.0f), true, instance));
    ASSERT_TRUE(own->set_ambient(ambient));
    for (int step = 0; step < 2; ++step)
        ASSERT_TRUE(own->step(0.05f));
    std::vector<std::string> recorded, blocking;
    for (const auto& [pass, ms] : system_->stats().ms) {
        recorded.emplace_back(pass);
        EXPECT_TRUE(std::isfinite(ms) && ms >= 0.0) << pass << " " << ms;
    }
    for (const auto& [pass, ms] : own->stats().ms)
        blocking.emplace_back(pass);
    EXPECT_FALSE(blocking.empty());
    EXPECT_EQ(recorded, blocking);
}

/// Vertices staged for a frame are recorded into it by handle; the mesh is destroyed while that frame
/// still waits for submission. Without retiring by frame index, the submission would name a destroyed
/// buffer (the validation layer's error fails the test).
TEST_F(HostFrames, keepWhatARecordedFrameUsesUntilItCompletes) {
    start(2);
    Box box(1.0f);
    MeshDesc deforming = box.desc();
    deforming.deforming = true;
    MeshId mesh = 0;
    InstanceId instance = 0;
    ASSERT_TRUE(system_->create_mesh(deforming, mesh));
    ASSERT_TRUE(system_->create_instance(mesh, translation(0.0f, 2.0f, 0.0f), true, instance));
    frame();
    std::vector<float> bigger = box.positions;
    for (float& p : bigger)
        p *= 1.5f;
    ASSERT_TRUE(system_->set_vertices(mesh, bigger.data(), 8));
    VkCommandBuffer commands = host_.begin_frame();
    ASSERT_NE(commands, VK_NULL_HANDLE);
    ASSERT_TRUE(system_->step(0.05f, commands));
    ASSERT_TRUE(system_->destroy_instance(instance));
    ASSERT_TRUE(system_->destroy_mesh(mesh));
    ASSERT_TRUE(host_.submit_frame());
    for (int f = 0; f < 3; ++f)
        frame();
    EXPECT_EQ(system_->stats().voxels, 0u) << "the mesh is gone from the frames completed last";
}

// Bones with frames in flight: each recorded frame skins the palette set before it. The box's top follows
// joint 1, lifted a little more each frame; once the frames completed the tree holds the last pose, whose
// top face lies on a voxel plane (y = 4 m), so voxel layers 7 and 8 hold it (hand calculation).
TEST_F(HostFrames, bonesPoseTheMeshInEveryFrameInFlight) {
    start(2);
    Box box(1.0f);
    std::vector<std::uint16_t> joints(4 * 8, 0);
    std::vector<float> weights(4 * 8, 0.0f);
    for (int v = 0; v < 8; ++v) {
        joints[4 * v] = box.positions[3 * v + 1] > 0.0f ? 1 : 0;
        weights[4 * v] = 1.0f;
    }
    const MeshSkin skin{2, joints.data(), weights.data()};
    MeshDesc desc = box.desc(true);
    desc.skin = &skin;
    MeshId mesh = 0;
    InstanceId instance = 0;
    ASSERT_TRUE(system_->create_mesh(desc, mesh));
    ASSERT_TRUE(system_->create_instance(mesh, translation(0.0f, 2.0f, 0.0f), false, instance));
    for (int f = 1; f <= 4; ++f) {
        const Mat4 palette[2] = {Mat4{}, translation(0.0f, 0.25f * float(f), 0.0f)};
        ASSERT_TRUE(system_->set_bones(mesh, palette, 2));
        frame();
    }
    ASSERT_TRUE(host_.finish_frames());
    std::size_t count = 0;
    ASSERT_TRUE(system_->debug_voxels({}, count));
    std::vector<VoxelCoord> voxels(count);
    ASSERT_TRUE(system_->debug_voxels(voxels, count));
    ASSERT_FALSE(voxels.empty());
    std::uint32_t lowest = ~0u, highest = 0;
    for (const VoxelCoord& v : voxels) {
        lowest = std::min(lowest, v.j);
        highest = std::max(highest, v.j);
    }
    EXPECT_EQ(lowest, 1u) << "the bottom stays at y = 1 m";
    EXPECT_EQ(highest, 8u) << "the top follows the last palette to y = 4 m";
}

} // namespace
} // namespace gust::test
