// A System of nested cascades (WindDomain::cascades, docs/solver.md "Cascades"): bad nests are refused, a
// query outside the finest cascade answers from a coarser one, the snapshot, the textures and the OpenVDB
// file hold every cascade, a ridge beyond the finest cascade shelters the player as one fine grid covering
// both does, and a wall in any cascade of any nest shelters the player as one grid of its cascade's cells
// does.
#include "host_vulkan.hpp"
#include "system_test_support.hpp"

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/context.hpp>
#include <span>
#if GUST_WITH_OPENVDB
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#endif

namespace gust::test {
namespace {

#include "gust_shaders/cascade_wind_comp.h"

TEST(Cascades, badNestsAreRefusedWithTheirReason) {
    struct Case {
        std::uint32_t cascades, ratio;
        float cell_size;
        const char* says;
    };
    for (const Case& c :
         {Case{0, 4, 1.0f, "domain.cascades must be 1..8"}, Case{9, 4, 1.0f, "domain.cascades must be 1..8"},
          Case{2, 3, 1.0f, "domain.ratio must be 2 or 4"}, Case{6, 4, 1.0f, "more than 1000 m"}}) {
        Watch watch;
        SystemDesc desc = small_desc(watch);
        desc.domain.cascades = c.cascades;
        desc.domain.ratio = c.ratio;
        desc.domain.cell_size = c.cell_size;
        std::unique_ptr<System> system;
        const Outcome created = System::create(desc, system);
        EXPECT_EQ(created.code(), ErrorCode::InvalidArgument) << c.says;
        EXPECT_NE(created.message().find(c.says), std::string::npos) << created.message();
        EXPECT_FALSE(system);
    }
}

/// Three cascades of 16x8x16 cells (1 m, 4 m, 16 m) around (0, 4, 0) with the snapshot on, on the host's
/// device when `host` is given; null (the test failed) when creation fails.
std::unique_ptr<System> three_cascades(Watch& watch, const HostDevice* host) {
    SystemDesc desc = small_desc(watch);
    desc.host = host;
    desc.domain.cascades = 3;
    desc.domain.ratio = 4;
    desc.snapshot = true;
    std::unique_ptr<System> system;
    const Outcome created = System::create(desc, system);
    EXPECT_TRUE(created) << created.message();
    return created ? std::move(system) : nullptr;
}

/// Three cascades of 16x8x16 cells (1 m, 4 m, 16 m) around (0, 4, 0), with the snapshot on, an ambient wind
/// of `ambient` and a fan 20 m out, beyond the finest cascade (16 m wide) but inside the next (64 m), stepped
/// 32 times.
/// On the host's device when `host` is given.
std::unique_ptr<System> fan_nest(Watch& watch, Vec3 ambient, const HostDevice* host = nullptr) {
    std::unique_ptr<System> system = three_cascades(watch, host);
    if (!system) return nullptr;
    const WindEmitter fan{.type = WindEmitterType::Directional,
                          .position = {20.0f, 4.0f, 0.0f},
                          .direction = {0.0f, 0.0f, 1.0f},
                          .radius = 6.0f,
                          .strength = 6.0f};
    EXPECT_TRUE(system->set_emitters({&fan, 1}));
    EXPECT_TRUE(system->set_ambient(ambient));
    for (int f = 0; f < 32; ++f)
        if (!system->step(0.1f)) return nullptr;
    return system;
}

/// The ambient wind of the nests below.
constexpr Vec3 kNestAmbient{1.0f, 0.0f, 0.5f};

/// One fan_nest the tests that only read from it share (each nest costs 10 s of lavapipe).
class FanNest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() { system_ = fan_nest(watch_, kNestAmbient); }
    static void TearDownTestSuite() { system_.reset(); }
    void SetUp() override { ASSERT_TRUE(system_); }
    void TearDown() override { EXPECT_EQ(watch_.errors, 0) << watch_.last; }
    static Watch watch_;
    static std::unique_ptr<System> system_;
};
Watch FanNest::watch_;
std::unique_ptr<System> FanNest::system_;

/// Along the fan's axis from the middle of fan_nest's finest cascade, through the finest one's blend zone
/// (5..8 m), the fan in the second cascade and its blend zone (20..32 m), to the third (to 128 m) and beyond
/// it, at y and z of the second cascade's cell centres, where the wind varies most between them.
std::vector<Vec3> line_through_the_nest() {
    std::vector<Vec3> points;
    for (float x = 0.25f; x < 160.0f; x += x < 40.0f ? 0.5f : 4.0f)
        points.push_back({x, 2.0f, 2.0f});
    return points;
}

/// Expects `got` within `tolerance(reference)` of `reference`, component by component, point by point.
template <class Tolerance>
void expect_near_each(std::span<const Vec3> points, std::span<const Vec3> got,
                      std::span<const Vec3> reference, Tolerance tolerance) {
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3 &g = got[i], &r = reference[i];
        const float t = tolerance(std::sqrt(r.x * r.x + r.y * r.y + r.z * r.z));
        EXPECT_NEAR(g.x, r.x, t) << "x = " << points[i].x;
        EXPECT_NEAR(g.y, r.y, t) << "x = " << points[i].x;
        EXPECT_NEAR(g.z, r.z, t) << "x = " << points[i].x;
    }
}

/// The min corner of cascade k of fan_nest.
Vec3 fan_nest_origin(int k) {
    const float h = std::pow(4.0f, float(k));
    return {-8.0f * h, 4.0f - 4.0f * h, -8.0f * h};
}

/// A frame's GPU time is every pass's: a coarser cascade's passes join the stats under "cascade_" in the
/// frames it steps, and only in those.
TEST(Cascades, aCoarserCascadesPassesAreTimedInTheFramesItSteps) {
    Watch watch;
    std::unique_ptr<System> system = three_cascades(watch, nullptr);
    ASSERT_TRUE(system);
    ASSERT_TRUE(system->set_ambient(kNestAmbient));
    int with = 0, without = 0;
    for (int f = 0; f < 8; ++f) {
        ASSERT_TRUE(system->step(0.1f));
        bool finest = false, coarser = false;
        for (const auto& [pass, ms] : system->stats().ms) {
            EXPECT_TRUE(std::isfinite(ms) && ms >= 0.0) << pass << " " << ms;
            finest |= pass == "wind_pressure";
            if (pass == "cascade_wind_pressure") {
                coarser = true;
                EXPECT_GT(ms, 0.0) << "frame " << f;
            }
        }
        EXPECT_TRUE(finest) << "the finest cascade steps every frame, frame " << f;
        ++(coarser ? with : without);
    }
    // The two coarser cascades take their first steps in frames 0 and 1; the second steps again every 4th.
    EXPECT_GE(with, 3);
    EXPECT_GE(without, 3);
    EXPECT_EQ(watch.errors, 0) << watch.last;
}

TEST_F(FanNest, aQueryBeyondTheFinestCascadeAnswersFromTheCoarserOnes) {
    const Vec3 points[] = {{20.0f, 4.0f, 0.0f}, {0.0f, 4.0f, 0.0f}, {120.0f, 4.0f, 0.0f}};
    std::array<Vec3, 3> wind{};
    ASSERT_TRUE(system_->query(points, wind));
    // The fan's core, between the second cascade's cell centres 2 m away on every axis (its cells are 4 m):
    // the cells' means of the jet read lower than its faces (WindReading::Solver) do.
    EXPECT_GT(wind[0].z - kNestAmbient.z, 1.2f) << "the fan blows in the second cascade";
    EXPECT_LT(std::abs(wind[1].z - kNestAmbient.z), 0.5f * (wind[0].z - kNestAmbient.z))
        << "the finest cascade lies beside the fan";
    EXPECT_LT(std::abs(wind[2].z - kNestAmbient.z), 0.5f)
        << "120 m out only the third cascade holds the point, far from the fan";
}

TEST_F(FanNest, theSnapshotAnswersFromEveryCascadeAsQueriesDo) {
    const Vec3 ambient = kNestAmbient;
    System* system = system_.get();
    const std::vector<Vec3> points = line_through_the_nest();
    std::vector<Vec3> sampled(points.size()), queried(points.size());
    ASSERT_TRUE(system->query(points, queried));
    ASSERT_TRUE(system->sample(points, sampled));
    // One wind at a point: both read the same half-float texels, blended alike (docs/api.md).
    expect_near_each(points, sampled, queried, [](float speed) { return 1e-4f * std::max(1.0f, speed); });
    float fan = 0.0f;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3& s = sampled[i];
        fan = std::max(fan, queried[i].z);
        if (points[i].x > 128.0f) {
            EXPECT_EQ(s.x, ambient.x) << "beyond every cascade, x = " << points[i].x;
            EXPECT_EQ(s.z, ambient.z) << "beyond every cascade, x = " << points[i].x;
        }
    }
    EXPECT_GT(fan, 2.0f + ambient.z) << "the fan blows in the second cascade, where the snapshot must see it";
}

TEST_F(FanNest, everyCascadeHasItsOwnTextureOverItsOwnGrid) {
    System* system = system_.get();
    const std::span<const WindTexture> textures = system->wind_textures();
    ASSERT_EQ(textures.size(), 3u);
    EXPECT_EQ(textures[0].image, system->wind_texture().image);
    for (int k = 0; k < 3; ++k) {
        const WindTexture& t = textures[std::size_t(k)];
        for (int j = 0; j < k; ++j)
            EXPECT_NE(t.image, textures[std::size_t(j)].image);
        EXPECT_EQ(t.extent[0], 16u);
        EXPECT_EQ(t.extent[1], 8u);
        EXPECT_EQ(t.extent[2], 16u);
        // Its grid's min corner maps to 0, its far corner (16x8x16 cells of 4^k m) to 1.
        const Vec3 lo = fan_nest_origin(k);
        const float h = std::pow(4.0f, float(k)), lo_[3] = {lo.x, lo.y, lo.z};
        const float hi[3] = {lo.x + 16.0f * h, lo.y + 8.0f * h, lo.z + 16.0f * h};
        for (int a = 0; a < 3; ++a) {
            EXPECT_NEAR(t.world_to_texture.m[a * 5] * lo_[a] + t.world_to_texture.m[12 + a], 0.0f, 1e-6f);
            EXPECT_NEAR(t.world_to_texture.m[a * 5] * hi[a] + t.world_to_texture.m[12 + a], 1.0f, 1e-6f);
        }
    }
    // Cascade k steps every 4^k frames: after 32 steps the finest's texture is from step 32, the second's
    // from its eighth step (at step 29 or later: a frame it shares with the third waits one), the third's
    // from step 17 or later.
    EXPECT_EQ(textures[0].frame, 32u);
    EXPECT_GE(textures[1].frame, 29u);
    EXPECT_LE(textures[1].frame, 32u);
    EXPECT_GE(textures[2].frame, 17u);
    EXPECT_LE(textures[2].frame, 32u);
}

/// What a host's compute shader reads through gust_wind.glsl (shaders/cascade_wind.comp) from three cascades'
/// `textures` at `points`, on the host's device; empty on failure, with the reason in `error`.
std::vector<Vec3> read_through_glsl(const HostDevice& host, std::span<const WindTexture> textures,
                                    Vec3 ambient, std::span<const Vec3> points, std::string& error) {
    gpu::HostDevice adopted;
    adopted.instance = host.instance;
    adopted.physical_device = host.physical_device;
    adopted.device = host.device;
    adopted.queue_family = host.queue_family;
    adopted.queue_index = host.queue_index;
    adopted.get_instance_proc_addr = host.get_instance_proc_addr;
    adopted.get_device_proc_addr =
        host.get_device_proc_addr ? host.get_device_proc_addr
                                  : reinterpret_cast<PFN_vkGetDeviceProcAddr>(
                                        host.get_instance_proc_addr(host.instance, "vkGetDeviceProcAddr"));
    auto ctx = gpu::Context::adopt(adopted);
    if (!ctx) {
        error = ctx.message();
        return {};
    }
    gpu::Context& c = **ctx;
    const auto load = [&](const char* name) { return adopted.get_device_proc_addr(host.device, name); };
    const auto create_set_layout =
        reinterpret_cast<PFN_vkCreateDescriptorSetLayout>(load("vkCreateDescriptorSetLayout"));
    const auto destroy_set_layout =
        reinterpret_cast<PFN_vkDestroyDescriptorSetLayout>(load("vkDestroyDescriptorSetLayout"));
    const auto create_pool = reinterpret_cast<PFN_vkCreateDescriptorPool>(load("vkCreateDescriptorPool"));
    const auto destroy_pool = reinterpret_cast<PFN_vkDestroyDescriptorPool>(load("vkDestroyDescriptorPool"));
    const auto allocate_sets =
        reinterpret_cast<PFN_vkAllocateDescriptorSets>(load("vkAllocateDescriptorSets"));
    const auto update_sets = reinterpret_cast<PFN_vkUpdateDescriptorSets>(load("vkUpdateDescriptorSets"));
    const auto bind_sets = reinterpret_cast<PFN_vkCmdBindDescriptorSets>(load("vkCmdBindDescriptorSets"));
    const gpu::Dispatch& vk = c.vk();
    const VkDevice device = host.device;

    // The inputs: the points, and the matrices and ambient wind as the shader's Frame block lays them out.
    struct Frame {
        float world_to_texture[3][16];
        float ambient[3];
    } frame{};
    for (std::size_t k = 0; k < 3; ++k)
        std::memcpy(frame.world_to_texture[k], textures[k].world_to_texture.m,
                    sizeof(frame.world_to_texture[k]));
    std::memcpy(frame.ambient, &ambient, sizeof(frame.ambient));
    auto point_buffer = gpu::Buffer::create(c, points.size_bytes(), gpu::MemoryUse::Upload);
    auto wind_buffer = gpu::Buffer::create(c, points.size_bytes(), gpu::MemoryUse::Readback);
    auto frame_buffer = gpu::Buffer::create(c, sizeof(frame), gpu::MemoryUse::Upload);
    if (!point_buffer || !wind_buffer || !frame_buffer) {
        error = "buffers";
        return {};
    }
    std::memcpy(point_buffer->mapped(), points.data(), points.size_bytes());
    std::memcpy(frame_buffer->mapped(), &frame, sizeof(frame));

    VkDescriptorSetLayoutBinding binding{0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 3,
                                         VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
    VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    set_info.bindingCount = 1;
    set_info.pBindings = &binding;
    VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
    VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0,
                             3 * sizeof(VkDeviceAddress) + sizeof(std::uint32_t)};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = 1;
    layout_info.pSetLayouts = &set_layout;
    layout_info.pushConstantRangeCount = 1;
    layout_info.pPushConstantRanges = &push;
    VkPipelineLayout layout = VK_NULL_HANDLE;
    VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    module_info.codeSize = sizeof(cascade_wind_comp);
    module_info.pCode = cascade_wind_comp;
    VkShaderModule module = VK_NULL_HANDLE;
    VkComputePipelineCreateInfo pipeline_info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    VkPipeline pipeline = VK_NULL_HANDLE;
    VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 3};
    VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool_info.maxSets = 1;
    pool_info.poolSizeCount = 1;
    pool_info.pPoolSizes = &size;
    VkDescriptorPool pool = VK_NULL_HANDLE;
    VkDescriptorSet set = VK_NULL_HANDLE;
    std::vector<Vec3> winds;
    if (create_set_layout(device, &set_info, nullptr, &set_layout) == VK_SUCCESS &&
        vk.vkCreatePipelineLayout(device, &layout_info, nullptr, &layout) == VK_SUCCESS &&
        vk.vkCreateShaderModule(device, &module_info, nullptr, &module) == VK_SUCCESS &&
        create_pool(device, &pool_info, nullptr, &pool) == VK_SUCCESS) {
        pipeline_info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
        pipeline_info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
        pipeline_info.stage.module = module;
        pipeline_info.stage.pName = "main";
        pipeline_info.layout = layout;
        VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
        allocate.descriptorPool = pool;
        allocate.descriptorSetCount = 1;
        allocate.pSetLayouts = &set_layout;
        if (vk.vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &pipeline) ==
                VK_SUCCESS &&
            allocate_sets(device, &allocate, &set) == VK_SUCCESS) {
            VkDescriptorImageInfo images[3];
            for (std::size_t k = 0; k < 3; ++k)
                images[k] = {textures[k].sampler, textures[k].view, textures[k].layout};
            VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
            write.dstSet = set;
            write.descriptorCount = 3;
            write.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
            write.pImageInfo = images;
            update_sets(device, 1, &write, 0, nullptr);
            struct {
                VkDeviceAddress points, winds, frame;
                std::uint32_t count;
            } constants{point_buffer->address(), wind_buffer->address(), frame_buffer->address(),
                        std::uint32_t(points.size())};
            const Status ran = c.submit_and_wait([&](VkCommandBuffer cmd) {
                vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline);
                bind_sets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 1, &set, 0, nullptr);
                vk.vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, push.size, &constants);
                vk.vkCmdDispatch(cmd, (std::uint32_t(points.size()) + 63) / 64, 1, 1);
                gpu::barrier(c, cmd);
            });
            if (ran) {
                winds.resize(points.size());
                std::memcpy(winds.data(), wind_buffer->mapped(), points.size_bytes());
            } else {
                error = ran.message();
            }
        } else {
            error = "the pipeline or its descriptor set";
        }
    } else {
        error = "the layouts, shader module or pool";
    }
    vk.vkDestroyPipeline(device, pipeline, nullptr);
    destroy_pool(device, pool, nullptr);
    vk.vkDestroyShaderModule(device, module, nullptr);
    vk.vkDestroyPipelineLayout(device, layout, nullptr);
    destroy_set_layout(device, set_layout, nullptr);
    return winds;
}

TEST(Cascades, aHostShaderReadsTheBlendedCascadesThroughTheGlslInclude) {
    HostVulkan host;
    ASSERT_TRUE(host.ok()) << host.error();
    Watch watch;
    const Vec3 ambient = kNestAmbient;
    const std::unique_ptr<System> system = fan_nest(watch, ambient, &host.device());
    ASSERT_TRUE(system);
    // From the finest cascade through both blend zones and the fan to beyond the coarsest, and far above.
    std::vector<Vec3> points = line_through_the_nest();
    points.push_back({-140.0f, 300.0f, 3.0f});
    std::string error;
    const std::vector<Vec3> read =
        read_through_glsl(host.device(), system->wind_textures(), ambient, points, error);
    ASSERT_EQ(read.size(), points.size()) << error;
    std::vector<Vec3> sampled(points.size());
    ASSERT_TRUE(system->sample(points, sampled));
    // The same texels and blend; the GPU's sampler weighs texels with 8-bit fractions (Vulkan's minimum).
    expect_near_each(points, read, sampled, [](float speed) { return 0.01f + 0.02f * speed; });
    float fan = 0.0f;
    for (const Vec3& g : read)
        fan = std::max(fan, g.z);
    EXPECT_GT(fan, 2.0f + ambient.z) << "the fan in the second cascade reaches the shader";
    EXPECT_EQ(read.back().x, ambient.x) << "beyond every cascade, the ambient wind";
    EXPECT_EQ(read.back().z, ambient.z);
    EXPECT_EQ(watch.errors, 0) << watch.last;
    EXPECT_EQ(host.messages(), 0);
}

#if GUST_WITH_OPENVDB
TEST_F(FanNest, theOpenVdbFileHoldsEveryCascadesGridsOnItsOwnCells) {
    System* system = system_.get();
    const std::filesystem::path path = std::filesystem::temp_directory_path() / "gust_cascades_export.vdb";
    ASSERT_TRUE(system->export_vdb(path.c_str()));
    openvdb::initialize();
    openvdb::io::File file(path.string());
    file.open();
    for (const char* name :
         {"occupancy", "solid", "velocity", "pressure", "solid_cascade1", "velocity_cascade1",
          "pressure_cascade1", "solid_cascade2", "velocity_cascade2", "pressure_cascade2"})
        EXPECT_TRUE(file.hasGrid(name)) << name;
    EXPECT_FALSE(file.hasGrid("velocity_cascade3"));
    std::array<openvdb::Vec3SGrid::Ptr, 3> velocity;
    for (int k = 0; k < 3; ++k)
        velocity[std::size_t(k)] = openvdb::gridPtrCast<openvdb::Vec3SGrid>(
            file.readGrid(k == 0 ? "velocity" : "velocity_cascade" + std::to_string(k)));
    file.close();
    std::filesystem::remove(path);
    for (int k = 0; k < 3; ++k) {
        const openvdb::Vec3SGrid& grid = *velocity[std::size_t(k)];
        const double h = std::pow(4.0, k);
        EXPECT_NEAR(grid.voxelSize().x(), h, 1e-6) << k;
        EXPECT_EQ(grid.activeVoxelCount(), 16u * 8u * 16u) << k;
        const openvdb::Vec3d c = grid.indexToWorld(openvdb::Coord(2, 3, 4));
        const Vec3 lo = fan_nest_origin(k);
        EXPECT_NEAR(c.x(), lo.x + 2.5 * h, 1e-4) << k;
        EXPECT_NEAR(c.y(), lo.y + 3.5 * h, 1e-4) << k;
        EXPECT_NEAR(c.z(), lo.z + 4.5 * h, 1e-4) << k;
    }
    // The second cascade's cell centred at (18, 2, 2) m, in its interior and beyond the finest cascade, holds
    // the velocity query answers there (from that cascade alone); the fan blows through it.
    const openvdb::Coord cell(12, 3, 8);
    const openvdb::Vec3s stored = velocity[1]->getConstAccessor().getValue(cell);
    const openvdb::Vec3d centre = velocity[1]->indexToWorld(cell);
    const Vec3 point{float(centre.x()), float(centre.y()), float(centre.z())};
    Vec3 queried;
    ASSERT_TRUE(system->query({&point, 1}, {&queried, 1}));
    EXPECT_GT(stored.z() - kNestAmbient.z, 1.0f);
    EXPECT_NEAR(stored.x(), queried.x, 0.02f);
    EXPECT_NEAR(stored.y(), queried.y, 0.02f);
    EXPECT_NEAR(stored.z(), queried.z, 0.02f);
}
#endif

#if GUST_WITH_OPENVDB
/// Cascade `grid` of an OpenVDB file at `path` read back.
openvdb::Vec3SGrid::Ptr read_velocity(const std::filesystem::path& path, const char* grid) {
    openvdb::initialize();
    openvdb::io::File file(path.string());
    file.open();
    auto velocity = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid(grid));
    file.close();
    return velocity;
}

TEST(Cascades, aFloorLaidUnderTheGroundKeepsTheFinestCascadesAirByTheGroundInEveryAnswer) {
    // Three cascades of 16x8x16 cells (1, 4 and 16 m) around (0, 4, 0): the finest's floor at y = 0 lies in
    // the ground, whose top is at 0.8 m, and a wall 4 m upwind shelters the air behind it. The air 0.7 m
    // above the ground lies within the finest cascade's last kCascadeBlendCells cells from its floor, but
    // the second cascade's 4 m cells there hold the ground: its wind resolves the wall and the ground
    // coarsely, so the finest cascade answers alone by the ground (docs/solver.md "Cascades").
    HostVulkan host;
    ASSERT_TRUE(host.ok()) << host.error();
    Watch watch;
    const std::unique_ptr<System> system = three_cascades(watch, &host.device());
    ASSERT_TRUE(system);
    const Box ground({-200.0f, -100.0f, -200.0f}, {200.0f, 0.8f, 200.0f});
    const Box wall({-4.0f, 0.0f, -5.0f}, {-3.0f, 4.5f, 5.0f});
    for (const Box* box : {&ground, &wall}) {
        MeshId mesh = 0;
        InstanceId id = 0;
        ASSERT_TRUE(system->create_mesh(box->desc(), mesh));
        ASSERT_TRUE(system->create_instance(mesh, Mat4{}, false, id));
    }
    const Vec3 ambient{3.0f, 0.0f, 0.0f};
    ASSERT_TRUE(system->set_ambient(ambient));
    for (int f = 0; f < 40; ++f)
        ASSERT_TRUE(system->step(0.1f));

    // The finest cascade's cell centres 0.7 m above the ground in the wall's lee, 1.5 cells from its floor
    // and more than kCascadeBlendCells from its other sides.
    std::vector<Vec3> points;
    for (float x = -1.5f; x <= 4.5f; x += 1.0f)
        points.push_back({x, 1.5f, 0.5f});
    std::vector<Vec3> queried(points.size()), sampled(points.size());
    ASSERT_TRUE(system->query(points, queried));
    ASSERT_TRUE(system->sample(points, sampled));
    const std::filesystem::path path = std::filesystem::temp_directory_path() / "gust_cascades_floor.vdb";
    ASSERT_TRUE(system->export_vdb(path.c_str()));
    const openvdb::Vec3SGrid::Ptr finest = read_velocity(path, "velocity");
    const openvdb::Vec3SGrid::Ptr second = read_velocity(path, "velocity_cascade1");
    std::filesystem::remove(path);
    ASSERT_TRUE(finest && second);
    float apart = 0.0f;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3& p = points[i];
        const openvdb::Vec3s own = finest->getConstAccessor().getValue(
            openvdb::Coord(int(std::floor(p.x + 8.0f)), int(std::floor(p.y)), int(std::floor(p.z + 8.0f))));
        const openvdb::Vec3s coarse = openvdb::tools::BoxSampler::sample(
            second->tree(), second->worldToIndex(openvdb::Vec3d(p.x, p.y, p.z)));
        apart = std::max(apart, float((own - coarse).length()));
        // Along the ground: the cell's velocity in the file is its faces' mean, as query's trilinear
        // answer at its centre; across it the file takes the open face above alone where query averages
        // it with the face below (the thin air over the ground at 0.8 m), so y is not compared.
        const float tolerance = 0.02f + 0.02f * float(own.length());
        EXPECT_NEAR(queried[i].x, own.x(), tolerance) << "x = " << p.x;
        EXPECT_NEAR(queried[i].z, own.z(), tolerance) << "x = " << p.x;
    }
    // A blend over 3 cells would take half of each there, and miss the finest's own by over 0.12 m/s.
    EXPECT_GT(apart, 0.25f) << "the second cascade's wind should differ there, or the test shows nothing";

    // The snapshot and a host's shader blend the same way, here and on a line up through the floor's blend.
    for (float y = 0.9f; y <= 6.0f; y += 0.25f)
        points.push_back({2.5f, y, 0.5f});
    queried.resize(points.size());
    sampled.resize(points.size());
    ASSERT_TRUE(system->query(points, queried));
    ASSERT_TRUE(system->sample(points, sampled));
    expect_near_each(points, sampled, queried, [](float speed) { return 0.25f + 0.1f * speed; });
    std::string error;
    const std::vector<Vec3> read =
        read_through_glsl(host.device(), system->wind_textures(), ambient, points, error);
    ASSERT_EQ(read.size(), points.size()) << error;
    expect_near_each(points, read, sampled, [](float speed) { return 0.01f + 0.02f * speed; });
    EXPECT_EQ(watch.errors, 0) << watch.last;
    EXPECT_EQ(host.messages(), 0);
}
#endif

TEST(Cascades, theFinestCascadeReadsTheCoarserWindBlendedInTimeBetweenItsSteps) {
    // Two cascades of ratio 4: the coarser steps every fourth frame. A fan 15 m upwind, beyond the finest
    // cascade (8 m), blows ever harder across the wind that carries its jet into the finest, so the coarser
    // cascade's field changes at each of its steps; inside the finest cascade past its blend zone (where its
    // own field answers alone), the answer must rise frame by frame, not in a staircase of the coarser steps:
    // the finest cascade's border reads the coarser wind blended in time. Beyond the finest cascade the
    // answer is the coarser cascade's texture, which changes at its steps (docs/api.md "One wind at a
    // point").
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.domain.cascades = 2;
    desc.domain.ratio = 4;
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(desc, system));
    ASSERT_TRUE(system->set_ambient({4.0f, 0.0f, 0.0f}));
    const Vec3 point[] = {{-4.5f, 4.0f, 0.5f}};
    std::vector<float> winds;
    for (int f = 0; f < 32; ++f) {
        const WindEmitter fan{.type = WindEmitterType::Directional,
                              .position = {-15.0f, 4.0f, 0.0f},
                              .direction = {0.0f, 0.0f, 1.0f},
                              .radius = 6.0f,
                              .strength = 0.25f * float(f)};
        ASSERT_TRUE(system->set_emitters({&fan, 1}));
        ASSERT_TRUE(system->step(0.1f));
        Vec3 wind[1];
        ASSERT_TRUE(system->query(point, wind));
        winds.push_back(wind[0].z);
    }
    // After the start: the largest change in one frame, against the largest over a coarser period.
    float step = 0.0f, period = 0.0f;
    for (std::size_t f = 12; f < winds.size(); ++f) {
        step = std::max(step, std::abs(winds[f] - winds[f - 1]));
        period = std::max(period, std::abs(winds[f] - winds[f - 4]));
    }
    EXPECT_GT(period, 0.1f) << "the wind rises";
    // A staircase puts a whole period's change into one frame (step = period); read in between, each frame
    // takes about a quarter of it.
    EXPECT_LT(step, 0.5f * period);
    EXPECT_EQ(watch.errors, 0) << watch.last;
}

TEST(Cascades, aNewAmbientWindReachesTheWholeNestInTheNextStep) {
    // A change of the far-field wind reaches incompressible air at once (docs/solver.md, "Ambient wind"): one
    // grid, and a nest of three cascades of ratio 4 whose coarser ones step every fourth and sixteenth
    // frame, follow it in the next step. Filled from the boundaries alone, one grid had moved 28 % of the way
    // after four steps, and the nest's middle 4 % after sixteen.
    for (std::uint32_t cascades : {1u, 3u}) {
        Watch watch;
        SystemDesc desc = small_desc(watch);
        desc.domain.cascades = cascades;
        desc.domain.ratio = 4;
        std::unique_ptr<System> system;
        ASSERT_TRUE(System::create(desc, system));
        ASSERT_TRUE(system->set_ambient({1.0f, 0.0f, 0.0f}));
        for (int f = 0; f < 8; ++f)
            ASSERT_TRUE(system->step(0.1f));
        ASSERT_TRUE(system->set_ambient({5.0f, 0.0f, 1.0f}));
        ASSERT_TRUE(system->step(0.1f));
        const Vec3 middle{0.0f, 4.0f, 0.0f};
        Vec3 wind;
        ASSERT_TRUE(system->query({&middle, 1}, {&wind, 1}));
        EXPECT_NEAR(wind.x, 5.0f, 0.1f) << cascades << " cascades";
        EXPECT_NEAR(wind.z, 1.0f, 0.05f) << cascades << " cascades";
        EXPECT_EQ(watch.errors, 0) << watch.last;
    }
}

TEST(Cascades, shiftingTheOriginMovesTheWindTheSolidsAndThePendingQueries) {
    // Two Systems of one scene; the second's world is rebased half-way by an offset of no whole cells.
    const Vec3 offset{37.3f, -2.5f, -12.9f};
    // Off the voxel planes, so that no face of it lies where rounding the shifted coordinates could flip a
    // voxel.
    const Box block({-1.8f, 0.1f, -0.9f}, {1.2f, 2.9f, 1.7f});
    std::unique_ptr<System> systems[2];
    Watch watch[2];
    for (int i = 0; i < 2; ++i) {
        SystemDesc desc = small_desc(watch[i]);
        desc.domain.cascades = 2;
        desc.domain.ratio = 2;
        ASSERT_TRUE(System::create(desc, systems[i]));
        MeshId mesh = 0;
        InstanceId id = 0;
        ASSERT_TRUE(systems[i]->create_mesh(block.desc(), mesh));
        ASSERT_TRUE(systems[i]->create_instance(mesh, Mat4{}, false, id));
        ASSERT_TRUE(systems[i]->set_ambient({4.0f, 0.0f, 1.0f}));
        const WindEmitter fan{.type = WindEmitterType::Directional,
                              .position = {-5.0f, 2.0f, 3.0f},
                              .direction = {0.0f, 1.0f, 0.0f},
                              .radius = 2.0f,
                              .strength = 5.0f};
        ASSERT_TRUE(systems[i]->set_emitters({&fan, 1}));
        for (int f = 0; f < 10; ++f)
            ASSERT_TRUE(systems[i]->step(0.1f));
    }
    const Vec3 points[] = {{3.0f, 1.5f, 0.5f}, {-5.0f, 2.0f, 3.0f}, {0.0f, 4.0f, -3.0f}, {14.0f, 4.0f, 0.0f}};
    QueryId asked[2] = {0, 0};
    for (int i = 0; i < 2; ++i)
        ASSERT_TRUE(systems[i]->query_async(points, asked[i]));
    ASSERT_TRUE(systems[1]->shift_origin(offset));
    for (int f = 0; f < 10; ++f)
        for (auto& system : systems)
            ASSERT_TRUE(system->step(0.1f));
    std::array<Vec3, 4> before[2], after[2];
    std::vector<Vec3> moved;
    for (const Vec3& p : points)
        moved.push_back({p.x + offset.x, p.y + offset.y, p.z + offset.z});
    for (int i = 0; i < 2; ++i) {
        ASSERT_TRUE(systems[i]->fetch(asked[i], before[i]));
        ASSERT_TRUE(systems[i]->query(i == 0 ? std::span<const Vec3>(points) : std::span<const Vec3>(moved),
                                      after[i]));
    }
    const auto distance = [](const Vec3& a, const Vec3& b) {
        return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
    };
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_LT(distance(before[0][k], before[1][k]), 0.02f) << "the pending query, point " << k;
        EXPECT_LT(distance(after[0][k], after[1][k]), 0.05f) << "point " << k;
    }
    // The fan still blows where it stood.
    EXPECT_GT(after[1][1].y, 1.0f);
    const Vec3 origin = systems[1]->domain_origin();
    EXPECT_NEAR(origin.x, systems[0]->domain_origin().x + offset.x, 1e-3f);
    EXPECT_NEAR(origin.z, systems[0]->domain_origin().z + offset.z, 1e-3f);
    Vec3 far = {1e30f, 0.0f, 0.0f};
    EXPECT_EQ(systems[1]->shift_origin(far).code(), ErrorCode::InvalidArgument);
    for (const Watch& w : watch)
        EXPECT_EQ(w.errors, 0) << w.last;
}

/// The mean wind along x at `points` over the second half of `steps` steps of `dt` (every `every`th), in an
/// ambient wind of `wind` m/s along x over the ground, with `walls` standing on it across the wind. A mean in
/// time: a lee eddy sheds, so one instant says little.
float mean_wind_x(const WindDomain& domain, const std::vector<Box>& walls, float wind, float dt, int steps,
                  int every, const std::vector<Vec3>& points) {
    Watch watch;
    SystemDesc desc;
    desc.validation = true;
    desc.domain = domain;
    desc.hooks = watching(watch);
    std::unique_ptr<System> system;
    const Outcome created = System::create(desc, system);
    EXPECT_TRUE(created) << created.message();
    if (!created) return 0.0f;
    std::vector<Box> solids = walls;
    solids.push_back(Box({-2000.0f, -500.0f, -2000.0f}, {2000.0f, 0.0f, 2000.0f}));
    for (const Box& b : solids) {
        MeshId mesh = 0;
        InstanceId id = 0;
        EXPECT_TRUE(system->create_mesh(b.desc(), mesh));
        EXPECT_TRUE(system->create_instance(mesh, Mat4{}, false, id));
    }
    EXPECT_TRUE(system->set_ambient({wind, 0.0f, 0.0f}));
    std::vector<Vec3> at(points.size());
    double sum = 0.0;
    int samples = 0;
    for (int s = 1; s <= steps; ++s) {
        const Outcome stepped = system->step(dt);
        EXPECT_TRUE(stepped) << stepped.message();
        if (!stepped) return 0.0f;
        if (2 * s <= steps || s % every != 0) continue;
        EXPECT_TRUE(system->query(points, at));
        for (const Vec3& w : at)
            sum += w.x;
        samples += int(at.size());
    }
    EXPECT_EQ(watch.errors, 0) << watch.last;
    return float(sum / double(samples));
}

/// A nest of `cascades` of `ratio` whose finest cascade has 32x16x16 cells of `cell_size` m (2 voxels a cell
/// along each axis), centred on `focus`: the nests of the shelter tests below.
WindDomain shelter_nest(float cell_size, Vec3 focus, std::uint32_t cascades, std::uint32_t ratio) {
    WindDomain d;
    d.cells[0] = 32;
    d.cells[1] = 16;
    d.cells[2] = 16;
    d.cell_size = cell_size;
    d.voxels_per_cell = 2;
    d.focus = focus;
    d.cascades = cascades;
    d.ratio = ratio;
    return d;
}

/// The mean wind along x over a 16x16 m patch 8 m above the ground around the player, over the second half of
/// `frames` frames (every eighth) of an 8 m/s wind, with a 32 m ridge 100 m upwind when `ridge` is set.
float wind_at_player(const WindDomain& domain, bool ridge, int frames) {
    std::vector<Box> walls;
    if (ridge) walls.push_back(Box({-108.0f, -10.0f, -600.0f}, {-92.0f, 32.0f, 600.0f}));
    std::vector<Vec3> points;
    for (float x = -8.0f; x <= 8.0f; x += 4.0f)
        for (float z = -8.0f; z <= 8.0f; z += 4.0f)
            points.push_back({x, 8.0f, z});
    return mean_wind_x(domain, walls, 8.0f, 0.25f, frames, 8, points);
}

TEST(Cascades, aRidgeBeyondTheFinestCascadeSheltersThePlayerAsOneFineGridDoes) {
    // The nest: 32x16x16 cells of 4 m (128 m along the wind) in one of 8 m (256 m), so the ridge, 100 m
    // upwind, lies in the coarser cascade only. The reference: one grid of 4 m cells holding both.
    const WindDomain nest = shelter_nest(4.0f, {0.0f, 24.0f, 0.0f}, 2, 2);
    WindDomain fine = nest;
    fine.cascades = 1;
    fine.cells[0] = 56;
    fine.cells[1] = 24;
    fine.focus = {-48.0f, 40.0f, 0.0f};
    WindDomain alone = nest;
    alone.cascades = 1;
    // 60 s, the mean over its second half: the wind crosses the reference grid twice before, as the lee eddy
    // settles (a mean over 20..40 s still put the two 23 % apart, over 30..60 s 3 %).
    constexpr int kFrames = 240;
    // Over flat ground the wind is the ambient one from the first step (8.000 m/s over 48 frames and over
    // 240, both grids, 2026-11-28), so a fifth of the frames measures it.
    const float reference =
        1.0f - wind_at_player(fine, true, kFrames) / wind_at_player(fine, false, kFrames / 5);
    const float nested =
        1.0f - wind_at_player(nest, true, kFrames) / wind_at_player(nest, false, kFrames / 5);
    // The ridge lies beyond this grid, so fewer frames show it cannot see it.
    const float single =
        1.0f - wind_at_player(alone, true, kFrames / 5) / wind_at_player(alone, false, kFrames / 5);
    RecordProperty("reference_shelter", std::to_string(reference));
    RecordProperty("nested_shelter", std::to_string(nested));
    EXPECT_GT(reference, 0.1f) << "the ridge should slow the wind at the player";
    EXPECT_NEAR(nested, reference, 0.2f * reference) << "reference " << reference << ", nested " << nested;
    EXPECT_LT(std::abs(single), 0.2f * reference) << "one cascade should not see the ridge at all";
}

constexpr float kShelterWind = 6.0f;

/// A nest and the cascade its obstacle lies in (beyond every finer one).
struct Placement {
    std::uint32_t cascades, ratio, obstacle;
};

std::string placement_name(const ::testing::TestParamInfo<Placement>& info) {
    const Placement& p = info.param;
    const char* where = p.obstacle == 0 ? "Finest" : p.obstacle + 1 == p.cascades ? "Coarsest" : "Middle";
    return std::to_string(p.cascades) + "CascadesOfRatio" + std::to_string(p.ratio) + "WallIn" + where;
}

class ShelterAcrossScales : public ::testing::TestWithParam<Placement> {};

// A wall 3 cells of its cascade high and 2 thick, 11 of its cells upwind of the player, across a 6 m/s wind:
// the nest's wind at the player (in the finest cascade, 2 to 4 m up) against one grid of the wall's cascade's
// cells over that cascade's extent, stepping that cascade's step (docs/solver.md "Cascades", "Fine to
// coarse"). Covers a wall in the finest, a middle and the coarsest cascade, ratio 2 and 4, 2 to 4 cascades.
TEST_P(ShelterAcrossScales, theNestsWindAtThePlayerIsWithinAFifthOfOneGridOfTheWallsCascade) {
    const Placement p = GetParam();
    const WindDomain nest = shelter_nest(1.0f, {0.0f, 7.0f, 0.0f}, p.cascades, p.ratio);
    const float h = std::pow(float(p.ratio), float(p.obstacle));
    WindDomain alone = nest;
    alone.cascades = 1;
    alone.cell_size = h;
    const std::vector<Box> wall = {Box({-12.0f * h, -1.0f, -2000.0f}, {-10.0f * h, 3.0f * h, 2000.0f})};
    std::vector<Vec3> player;
    for (float x = -2.0f; x <= 2.0f; x += 2.0f)
        for (float y = 2.0f; y <= 4.0f; y += 1.0f)
            player.push_back({x, y, 0.0f});
    // Three times the wind's way from the wall to the player before the mean's window, as long again in it;
    // the finest cascade at 1.5 cells a step.
    constexpr float kDt = 0.25f;
    const int steps = 2 * int(std::ceil(3.0f * 11.0f * h / kShelterWind / (kDt * h)));
    const float reference = mean_wind_x(alone, wall, kShelterWind, kDt * h, steps, 4, player);
    const float nested = mean_wind_x(nest, wall, kShelterWind, kDt, steps * int(h), 4, player);
    RecordProperty("reference", std::to_string(reference));
    RecordProperty("nested", std::to_string(nested));
    // Within a fifth of the shelter one grid gives (the open wind less its wind): in the wall's lee the wind
    // itself is a tenth of the open wind, which cells of another size cannot match within a fifth.
    EXPECT_LT(reference, 0.7f * kShelterWind) << "the wall should shelter the player";
    EXPECT_NEAR(nested, reference, 0.2f * (kShelterWind - reference))
        << "reference " << reference << ", nested " << nested;
}

INSTANTIATE_TEST_SUITE_P(Cascades, ShelterAcrossScales,
                         ::testing::Values(Placement{2, 4, 1}, Placement{3, 4, 1}, Placement{3, 2, 2},
                                           Placement{4, 2, 0}, Placement{2, 2, 0}),
                         placement_name);

} // namespace
} // namespace gust::test
