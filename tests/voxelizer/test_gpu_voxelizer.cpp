// The GPU paths against the CPU reference: equal sets, except voxels the surface touches within 1e-3 voxel.
#include "support/gpu_env.hpp"
#include "support/mesh_gen.hpp"
#include "support/vdb_check.hpp"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <gust/scene/import.hpp>
#include <gust/voxelizer/cpu_reference.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>

namespace gust::test {
namespace {

/// A test input: a mesh in world space and the grid it is voxelized on.
struct Case {
    TestMesh mesh;
    GridDesc grid;
};

TestMesh from_file(const std::string& relative) {
    auto mesh = load_mesh(std::string(GUST_ASSETS_DIR) + "/" + relative);
    EXPECT_TRUE(mesh) << mesh.message();
    TestMesh out;
    if (mesh) {
        out.positions = mesh->positions;
        out.indices = mesh->indices;
    }
    return out;
}

GridDesc fitted(const TestMesh& mesh, std::uint32_t res) {
    const auto [lo, hi] = mesh_bounds(mesh.view());
    return grid_around(lo, hi, res);
}

/// A grid whose voxel planes are exactly representable (power-of-two h, origin a multiple of h).
GridDesc exact_grid(std::uint32_t res) {
    GridDesc g;
    g.res = res;
    g.voxel_size = 0.0625f;
    g.origin = glm::vec3(-2.0f, -1.0f, -0.5f);
    return g;
}

Case make_case(const std::string& name, std::uint32_t res) {
    if (name == "bunny") {
        TestMesh m = from_file("scans/bunny.ply");
        return {m, fitted(m, res)};
    }
    if (name == "dragon_res3") {
        TestMesh m = from_file("scans/dragon_res3.ply");
        return {m, fitted(m, res)};
    }
    if (name == "fox") {
        TestMesh m = from_file("characters/Fox.glb");
        return {m, fitted(m, res)};
    }
    const GridDesc g = exact_grid(res);
    if (name == "soup") return {random_soup(res, 3000, g), g};
    if (name == "boxes") return {grid_aligned_boxes(g, 12, res), g};
    if (name == "huge") return {huge_triangles(g), g};
    if (name == "vast") return {vast_triangles(g), g};
    return {partly_outside(g, res, 400), g};
}

/// CPU reference results are shared between the two methods.
const CpuVoxelization& reference(const std::string& name, std::uint32_t res, const Case& c) {
    static std::map<std::pair<std::string, std::uint32_t>, CpuVoxelization> cache;
    auto key = std::make_pair(name, res);
    auto it = cache.find(key);
    if (it == cache.end()) {
        const InstanceDesc inst{c.mesh.view(), glm::mat4(1.0f)};
        it = cache.emplace(key, voxelize_reference({&inst, 1}, c.grid)).first;
    }
    return it->second;
}

std::vector<std::uint32_t> sorted_unique(std::vector<std::uint32_t> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

using Param = std::tuple<std::string, std::uint32_t, VoxelizeMethod>;

class MatchesReference : public GpuTestWithParam<Param> {};

TEST_P(MatchesReference, exceptWithinToleranceOfTouching) {
    const auto& [name, res, method] = GetParam();
    const Case c = make_case(name, res);
    ASSERT_FALSE(c.mesh.indices.empty());
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer) << voxelizer.message();
    auto mesh = (*voxelizer)->upload(c.mesh.view());
    ASSERT_TRUE(mesh) << mesh.message();
    const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
    auto stats = (*voxelizer)->voxelize({&inst, 1}, c.grid, method);
    ASSERT_TRUE(stats) << stats.message();
    auto fragments = (*voxelizer)->read_fragments();
    ASSERT_TRUE(fragments);
    EXPECT_EQ(fragments->size(), stats->fragments);
    const std::vector<std::uint32_t> gpu = sorted_unique(*fragments);

    const CpuVoxelization& ref = reference(name, res, c);
    ASSERT_FALSE(ref.voxels.empty());
    EXPECT_EQ(stats->rejected, ref.rejected);
    const VoxelDiff diff = diff_voxels(gpu, ref.voxels);
    const InstanceDesc cpu_inst{c.mesh.view(), glm::mat4(1.0f)};
    const auto bad = unexplained_differences(diff, {&cpu_inst, 1}, c.grid);
    EXPECT_TRUE(bad.empty()) << bad.size() << " voxels differ by more than 1e-3 voxel ("
                             << diff.missing.size() << " missing, " << diff.extra.size() << " extra, "
                             << ref.voxels.size() << " in the reference)";
}

std::string param_name(const ::testing::TestParamInfo<Param>& info) {
    return std::get<0>(info.param) + "_res" + std::to_string(std::get<1>(info.param)) + "_" +
           to_string(std::get<2>(info.param));
}

INSTANTIATE_TEST_SUITE_P(Meshes, MatchesReference,
                         ::testing::Combine(::testing::Values("bunny", "dragon_res3", "fox", "soup", "boxes",
                                                              "huge", "vast", "outside"),
                                            ::testing::Values(8u, 37u, 64u, 128u),
                                            ::testing::Values(VoxelizeMethod::Raster,
                                                              VoxelizeMethod::Compute)),
                         param_name);

// The largest grid: grid-aligned boxes and plane sections spanning all 1024^2 columns.
INSTANTIATE_TEST_SUITE_P(LargestGrid, MatchesReference,
                         ::testing::Combine(::testing::Values("boxes", "huge"), ::testing::Values(1024u),
                                            ::testing::Values(VoxelizeMethod::Raster,
                                                              VoxelizeMethod::Compute)),
                         param_name);

using DistanceParam = std::tuple<std::string, VoxelizeMethod>;

class AgreesWithOpenVdb : public GpuTestWithParam<DistanceParam> {};

TEST_P(AgreesWithOpenVdb, occupiesEveryVoxelNearTheSurfaceAndNoneFarFromIt) {
    const auto& [name, method] = GetParam();
    const Case c = make_case(name, 64);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer) << voxelizer.message();
    auto mesh = (*voxelizer)->upload(c.mesh.view());
    ASSERT_TRUE(mesh) << mesh.message();
    const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
    ASSERT_TRUE((*voxelizer)->voxelize({&inst, 1}, c.grid, method));
    const std::vector<std::uint32_t> voxels = sorted_unique(*(*voxelizer)->read_fragments());
    const DistanceCheck check = check_against_distance_field(c.mesh, c.grid, voxels);
    for (const std::string& example : check.examples)
        ADD_FAILURE() << example;
    EXPECT_EQ(check.uncovered, 0u);
    EXPECT_EQ(check.too_far, 0u);
    EXPECT_GT(check.near_surface, voxels.size() / 10);
}

INSTANTIATE_TEST_SUITE_P(Meshes, AgreesWithOpenVdb,
                         ::testing::Combine(::testing::Values("bunny", "dragon_res3", "soup"),
                                            ::testing::Values(VoxelizeMethod::Raster,
                                                              VoxelizeMethod::Compute)),
                         [](const ::testing::TestParamInfo<DistanceParam>& p) {
                             return std::get<0>(p.param) + "_" + to_string(std::get<1>(p.param));
                         });

using VoxelizerTest = GpuTest;

TEST_F(VoxelizerTest, tinyInitialCapacityStillYieldsTheFullSet) {
    // Huge triangles emit thousands of voxels each within the grid, but their bounding box lies almost
    // all outside it, so the first guess from their sizes (voxelize_work) falls far short.
    const GridDesc g = exact_grid(64);
    const TestMesh soup = huge_triangles(g);
    for (VoxelizeMethod method : {VoxelizeMethod::Raster, VoxelizeMethod::Compute}) {
        std::vector<std::uint32_t> sets[2];
        for (std::uint32_t capacity : {1u << 20, 1u}) {
            VoxelizerDesc desc;
            desc.initial_capacity = capacity;
            auto voxelizer = Voxelizer::create(ctx(), desc);
            ASSERT_TRUE(voxelizer) << voxelizer.message();
            auto mesh = (*voxelizer)->upload(soup.view());
            ASSERT_TRUE(mesh);
            const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
            auto stats = (*voxelizer)->voxelize({&inst, 1}, g, method);
            ASSERT_TRUE(stats) << stats.message();
            EXPECT_EQ(stats->retries, capacity == 1u ? 1u : 0u)
                << to_string(method) << " " << stats->fragments;
            EXPECT_GE(stats->capacity, stats->fragments);
            sets[capacity == 1u] = sorted_unique(*(*voxelizer)->read_fragments());
        }
        EXPECT_FALSE(sets[0].empty());
        EXPECT_EQ(sets[0], sets[1]) << to_string(method);
    }
}

TEST_F(VoxelizerTest, severalInstancesWithOwnTransformsMatchTheReference) {
    const GridDesc g = exact_grid(64);
    const TestMesh sphere = icosphere(2, glm::vec3(0.0f), 0.5f);
    const glm::mat4 models[3] = {
        glm::translate(glm::mat4(1.0f), glm::vec3(-1.0f, 0.5f, 0.5f)),
        glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0.8f, 1.0f, 1.2f)), glm::vec3(1.5f, 0.7f, 1.0f)),
        glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 2.0f, 2.5f)), 0.7f, glm::vec3(1, 1, 0))};
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(sphere.view());
    ASSERT_TRUE(mesh);
    std::vector<GpuInstance> gpu_instances;
    std::vector<InstanceDesc> cpu_instances;
    for (const glm::mat4& m : models) {
        gpu_instances.push_back({&*mesh, m});
        cpu_instances.push_back({sphere.view(), m});
    }
    const CpuVoxelization ref = voxelize_reference(cpu_instances, g);
    for (VoxelizeMethod method : {VoxelizeMethod::Raster, VoxelizeMethod::Compute, VoxelizeMethod::Auto}) {
        auto stats = (*voxelizer)->voxelize(gpu_instances, g, method);
        ASSERT_TRUE(stats) << stats.message();
        EXPECT_EQ(stats->triangles, 3 * sphere.indices.size() / 3);
        const VoxelDiff diff = diff_voxels(sorted_unique(*(*voxelizer)->read_fragments()), ref.voxels);
        EXPECT_TRUE(unexplained_differences(diff, cpu_instances, g).empty()) << to_string(method);
    }
}

// Faces on voxel planes touch the voxels on both sides, and the edges touch their diagonal neighbours:
// with exactly representable planes this is decided exactly, so both paths must give the reference's
// set with nothing excused. The raster path's dilation has to outlast the rasterizer's snapping to its
// sub-pixel grid here (an H100 lost edge neighbours when the margin was 1e-3 pixel).
TEST_F(VoxelizerTest, gridAlignedBoxesGiveEveryTouchedVoxelOnBothPaths) {
    const GridDesc g = exact_grid(48);
    const TestMesh boxes = grid_aligned_boxes(g, 12, 48);
    const std::vector<InstanceDesc> cpu_instances = {{boxes.view(), glm::mat4(1.0f)}};
    const CpuVoxelization ref = voxelize_reference(cpu_instances, g);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(boxes.view());
    ASSERT_TRUE(mesh);
    const GpuInstance instance{&*mesh, glm::mat4(1.0f)};
    for (VoxelizeMethod method : {VoxelizeMethod::Raster, VoxelizeMethod::Compute}) {
        auto stats = (*voxelizer)->voxelize({&instance, 1}, g, method);
        ASSERT_TRUE(stats) << stats.message();
        const VoxelDiff diff = diff_voxels(sorted_unique(*(*voxelizer)->read_fragments()), ref.voxels);
        EXPECT_TRUE(diff.missing.empty()) << to_string(method) << ": " << diff.missing.size() << " missing";
        EXPECT_TRUE(diff.extra.empty()) << to_string(method) << ": " << diff.extra.size() << " extra";
    }
}

TEST_F(VoxelizerTest, countsNonFiniteTrianglesAndSkipsZeroArea) {
    const BadTriangles bad = bad_triangles();
    GridDesc g;
    g.res = 16;
    g.voxel_size = 1.0f / 16.0f;
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(bad.mesh.view());
    ASSERT_TRUE(mesh) << mesh.message();
    const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
    const InstanceDesc cpu{bad.mesh.view(), glm::mat4(1.0f)};
    const CpuVoxelization ref = voxelize_reference({&cpu, 1}, g);
    for (VoxelizeMethod method : {VoxelizeMethod::Raster, VoxelizeMethod::Compute}) {
        auto stats = (*voxelizer)->voxelize({&inst, 1}, g, method);
        ASSERT_TRUE(stats) << stats.message();
        EXPECT_EQ(stats->rejected, bad.expected_rejected);
        const VoxelDiff diff = diff_voxels(sorted_unique(*(*voxelizer)->read_fragments()), ref.voxels);
        EXPECT_TRUE(unexplained_differences(diff, {&cpu, 1}, g).empty()) << to_string(method);
    }
}

TEST_F(VoxelizerTest, nonFiniteModelMatrixRejectsEveryTriangle) {
    const TestMesh sphere = icosphere(1, glm::vec3(0.5f), 0.3f);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(sphere.view());
    ASSERT_TRUE(mesh);
    glm::mat4 model(1.0f);
    model[3][0] = std::numeric_limits<float>::quiet_NaN();
    const GpuInstance inst{&*mesh, model};
    auto stats = (*voxelizer)->voxelize({&inst, 1}, exact_grid(16), VoxelizeMethod::Raster);
    ASSERT_TRUE(stats);
    EXPECT_EQ(stats->rejected, mesh->triangle_count());
    EXPECT_EQ(stats->fragments, 0u);
}

TEST_F(VoxelizerTest, rejectsIndexOutOfRange) {
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::uint32_t indices[3] = {0, 1, 3};
    MeshView view;
    view.positions = positions;
    view.vertex_count = 3;
    view.indices = indices;
    view.index_count = 3;
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(view);
    ASSERT_FALSE(mesh);
    EXPECT_NE(mesh.message().find("out of range"), std::string::npos);
    view.index_count = 2;
    EXPECT_FALSE((*voxelizer)->upload(view));
}

TEST_F(VoxelizerTest, emptyMeshGivesNoFragments) {
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(MeshView{});
    ASSERT_TRUE(mesh) << mesh.message();
    const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
    for (VoxelizeMethod method : {VoxelizeMethod::Raster, VoxelizeMethod::Compute, VoxelizeMethod::Auto}) {
        auto stats = (*voxelizer)->voxelize({&inst, 1}, exact_grid(8), method);
        ASSERT_TRUE(stats) << stats.message();
        EXPECT_EQ(stats->fragments, 0u);
        EXPECT_TRUE((*voxelizer)->read_fragments()->empty());
    }
}

TEST_F(VoxelizerTest, rejectsBadGrids) {
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    GridDesc g = exact_grid(7);
    EXPECT_FALSE((*voxelizer)->voxelize({}, g, VoxelizeMethod::Raster));
    g = exact_grid(1025);
    EXPECT_FALSE((*voxelizer)->voxelize({}, g, VoxelizeMethod::Raster));
    g = exact_grid(64);
    g.voxel_size = 0.0f;
    EXPECT_FALSE((*voxelizer)->voxelize({}, g, VoxelizeMethod::Raster));
    g.voxel_size = std::numeric_limits<float>::infinity();
    EXPECT_FALSE((*voxelizer)->voxelize({}, g, VoxelizeMethod::Raster));
    g = exact_grid(64);
    g.origin.y = std::numeric_limits<float>::quiet_NaN();
    auto r = (*voxelizer)->voxelize({}, g, VoxelizeMethod::Raster);
    ASSERT_FALSE(r);
    EXPECT_NE(r.message().find("origin"), std::string::npos);
}

TEST_F(VoxelizerTest, autoPicksOnePathAndMatches) {
    const GridDesc g = exact_grid(64);
    const TestMesh soup = random_soup(3, 1000, g);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(soup.view());
    ASSERT_TRUE(mesh);
    const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
    auto stats = (*voxelizer)->voxelize({&inst, 1}, g, VoxelizeMethod::Auto);
    ASSERT_TRUE(stats) << stats.message();
    EXPECT_NE(stats->method, VoxelizeMethod::Auto);
    auto again = (*voxelizer)->voxelize({&inst, 1}, g, VoxelizeMethod::Auto);
    ASSERT_TRUE(again);
    EXPECT_EQ(again->method, stats->method) << "the choice depends on the mesh, grid and device only";
    const InstanceDesc cpu{soup.view(), glm::mat4(1.0f)};
    const VoxelDiff diff =
        diff_voxels(sorted_unique(*(*voxelizer)->read_fragments()), voxelize_reference({&cpu, 1}, g).voxels);
    EXPECT_TRUE(unexplained_differences(diff, {&cpu, 1}, g).empty());
}

class CarriesSurfaceVelocity : public GpuTestWithParam<VoxelizeMethod> {};

TEST_P(CarriesSurfaceVelocity, ofATranslatedMesh) {
    const GridDesc g = exact_grid(32);
    const TestMesh sphere = icosphere(2, glm::vec3(0.0f), 0.4f);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(sphere.view());
    ASSERT_TRUE(mesh);
    const glm::vec3 before(-0.9f, 0.0f, 0.5f), after(-0.8f, 0.05f, 0.45f);
    const float dt = 0.02f;
    GpuInstance inst{&*mesh, glm::translate(glm::mat4(1.0f), after)};
    inst.prev_model = glm::translate(glm::mat4(1.0f), before);
    auto stats = (*voxelizer)->voxelize({&inst, 1}, g, GetParam(), dt);
    ASSERT_TRUE(stats) << stats.message();
    auto velocities = (*voxelizer)->read_velocities();
    ASSERT_TRUE(velocities) << velocities.message();
    ASSERT_EQ(velocities->size(), stats->fragments);
    ASSERT_GT(velocities->size(), 100u);
    const glm::vec3 expected = (after - before) / dt; // (5, 2.5, -2.5) m/s
    for (const glm::vec3& v : *velocities)
        ASSERT_LT(glm::length(v - expected), 0.01f) << v.x << "," << v.y << "," << v.z;
}

TEST_P(CarriesSurfaceVelocity, ofARotatingMeshAtTheSurfacePoint) {
    const GridDesc g = exact_grid(48);
    const glm::vec3 centre(-0.5f, 0.5f, 1.0f);
    const TestMesh sphere = icosphere(3, glm::vec3(0.0f), 0.6f);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(sphere.view());
    ASSERT_TRUE(mesh);
    const float dt = 0.01f, omega = 2.0f; // rad/s about +y
    GpuInstance inst{&*mesh,
                     glm::rotate(glm::translate(glm::mat4(1.0f), centre), omega * dt, glm::vec3(0, 1, 0))};
    inst.prev_model = glm::translate(glm::mat4(1.0f), centre);
    ASSERT_TRUE((*voxelizer)->voxelize({&inst, 1}, g, GetParam(), dt));
    const auto keys = *(*voxelizer)->read_fragments();
    const auto velocities = *(*voxelizer)->read_velocities();
    ASSERT_EQ(keys.size(), velocities.size());
    double worst = 0.0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        const glm::vec3 p = g.origin + (glm::vec3(unpack_voxel(keys[i])) + 0.5f) * g.voxel_size;
        const glm::vec3 r = p - centre;
        const glm::vec3 expected = glm::cross(glm::vec3(0.0f, omega, 0.0f), r);
        // The velocity is the surface's at a point within a voxel of the centre: |omega| h of slack.
        worst = std::max(worst, double(glm::length(velocities[i] - expected)));
    }
    EXPECT_LT(worst, 1.8 * omega * g.voxel_size);
}

// A rigid mesh that turns 1.5 rad in a frame while sliding along the turn's axis moves the air as that screw
// motion does at its surface now: ω × (q − c) + the slide, not along the chord from where the point was
// (0.91 times as fast and 43° off here).
TEST_P(CarriesSurfaceVelocity, ofARigidMeshTurningFarInAFrameAsItsScrewMotion) {
    const GridDesc g = exact_grid(48);
    const glm::vec3 centre(-0.5f, 0.5f, 1.0f), axis = glm::normalize(glm::vec3(1.0f, 2.0f, -0.5f));
    const TestMesh sphere = icosphere(3, glm::vec3(0.0f), 0.6f);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(sphere.view());
    ASSERT_TRUE(mesh);
    const float dt = 0.01f, turn = 1.5f, slide = 0.004f;
    GpuInstance inst{&*mesh, glm::rotate(glm::translate(glm::mat4(1.0f), centre + slide * axis), turn, axis)};
    inst.prev_model = glm::translate(glm::mat4(1.0f), centre);
    ASSERT_TRUE((*voxelizer)->voxelize({&inst, 1}, g, GetParam(), dt));
    const auto keys = *(*voxelizer)->read_fragments();
    const auto velocities = *(*voxelizer)->read_velocities();
    ASSERT_EQ(keys.size(), velocities.size());
    ASSERT_GT(keys.size(), 100u);
    const glm::vec3 omega = turn / dt * axis;
    double worst = 0.0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        const glm::vec3 p = g.origin + (glm::vec3(unpack_voxel(keys[i])) + 0.5f) * g.voxel_size;
        const glm::vec3 expected = glm::cross(omega, p - centre) + slide / dt * axis;
        worst = std::max(worst, double(glm::length(velocities[i] - expected)));
    }
    EXPECT_LT(worst, 1.8 * glm::length(omega) * g.voxel_size);
}

TEST_P(CarriesSurfaceVelocity, ofUpdatedVertexPositions) {
    const GridDesc g = exact_grid(32);
    TestMesh sphere = icosphere(2, glm::vec3(-0.5f, 0.4f, 0.6f), 0.3f);
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    auto mesh = (*voxelizer)->upload(sphere.view());
    ASSERT_TRUE(mesh);
    // A "pose" that stretches the sphere upwards: each vertex moves by 0.1 * its height above the centre.
    std::vector<glm::vec3> posed = sphere.positions;
    for (glm::vec3& p : posed)
        p.y += 0.1f * (p.y - 0.4f);
    ASSERT_TRUE((*voxelizer)->update_positions(*mesh, posed));
    const float dt = 0.05f;
    const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
    ASSERT_TRUE((*voxelizer)->voxelize({&inst, 1}, g, GetParam(), dt));
    const auto keys = *(*voxelizer)->read_fragments();
    const auto velocities = *(*voxelizer)->read_velocities();
    for (std::size_t i = 0; i < keys.size(); ++i) {
        const glm::vec3 p = g.origin + (glm::vec3(unpack_voxel(keys[i])) + 0.5f) * g.voxel_size;
        const float expected_vy = 0.1f * (p.y - 0.4f) / dt;
        ASSERT_NEAR(velocities[i].y, expected_vy, 0.1f * 1.8f * g.voxel_size / dt);
        ASSERT_NEAR(velocities[i].x, 0.0f, 1e-3f);
    }
    const std::vector<glm::vec3> wrong(3);
    EXPECT_FALSE((*voxelizer)->update_positions(*mesh, wrong));
}

INSTANTIATE_TEST_SUITE_P(Methods, CarriesSurfaceVelocity,
                         ::testing::Values(VoxelizeMethod::Raster, VoxelizeMethod::Compute),
                         [](const ::testing::TestParamInfo<VoxelizeMethod>& p) {
                             return to_string(p.param);
                         });

TEST_F(VoxelizerTest, rejectsNegativeOrNonFiniteFrameTime) {
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    EXPECT_FALSE((*voxelizer)->voxelize({}, exact_grid(8), VoxelizeMethod::Compute, -0.1f));
    EXPECT_FALSE((*voxelizer)->voxelize({}, exact_grid(8), VoxelizeMethod::Compute, std::nanf("")));
    EXPECT_FALSE((*voxelizer)->read_velocities());
}

} // namespace
} // namespace gust::test
