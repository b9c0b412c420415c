// The engine-facing C++ API (include/gust/gust.hpp), used as an engine would use it.
#include "host_vulkan.hpp"
#include "system_test_support.hpp"

#include <cmath>
#include <filesystem>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <limits>
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
    EXPECT_EQ(system_->record(VK_NULL_HANDLE).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system_->export_vdb(nullptr).code(), ErrorCode::InvalidArgument);
    ASSERT_TRUE(system_->step(0.05f));
}

TEST(SystemCreate, rejectsAnotherHeaderVersionAndBadDescriptions) {
    Watch watch;
    std::unique_ptr<System> system;
    SystemDesc desc = small_desc(watch);
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
    desc = small_desc(watch);
    desc.device = "no such device";
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::DeviceUnsupported);
    EXPECT_EQ(system, nullptr);
    EXPECT_EQ(watch.live, 0);
    EXPECT_EQ(library_version(), kHeaderVersion);
}

/// The same scene on gust's own device, on a device the test creates as a host, and with the host's
/// command buffer: the same wind.
TEST(SystemHostDevice, givesTheSameWindAsItsOwnDeviceInBothSubmissionModes) {
    const Vec3 points[] = {{-5.5f, 2.0f, 0.0f}, {-3.0f, 2.0f, 2.2f}, {3.0f, 3.5f, 1.0f}, {0.0f, 6.0f, -4.0f}};
    Vec3 wind[3][4];
    HostVulkan host;
    ASSERT_TRUE(host.ok()) << host.error();
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
            ASSERT_TRUE(system->step(0.05f));
            if (mode == 2) {
                System* s = system.get();
                ASSERT_TRUE(host.run(
                    [](VkCommandBuffer cmd, void* user) { static_cast<System*>(user)->record(cmd); }, s));
            }
        }
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

} // namespace
} // namespace gust::test
