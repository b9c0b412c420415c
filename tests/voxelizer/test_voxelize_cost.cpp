// The cost model of `auto`: triangle sizes measured by hand, the work they give on a grid, the expected
// fragment count against the GPU's, and `auto` choosing a path without running the other.
#include "support/gpu_env.hpp"
#include "support/mesh_gen.hpp"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <gust/scene/import.hpp>
#include <gust/voxelizer/voxelize_cost.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <limits>
#include <string>

namespace gust::test {
namespace {

/// One right triangle in the z = 0 plane, legs 2 (x) and 1 (y).
TestMesh right_triangle() {
    TestMesh m;
    m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0}};
    m.indices = {0, 1, 2};
    return m;
}

TEST(MeshSizes, sumEachTriangleProjectedAlongItsDominantAxis) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    TestMesh m;
    m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0},   {0, 3, 0}, {0, 0, 1},
                   {1, 0, 0}, {0, 1, 1}, {nan, 0, 0}, {0, 4, 0}};
    m.indices = {0, 1, 2,  // in z = 0, projected on (x, y): 2 x 1
                 0, 3, 4,  // in x = 0, on (y, z): 3 x 1
                 0, 5, 6,  // normal (0, -1, 1): the tie goes to z, as the shaders break it; 1 x 1
                 7, 1, 2,  // rejected: counts nothing, wherever the vertex is
                 1, 7, 2,  // rejected
                 1, 2, 7,  // rejected
                 0, 2, 8}; // collinear: counts nothing, not even in the bounds
    const MeshSizes s = measure_mesh(m.view());
    EXPECT_EQ(s.triangles, 3u);
    EXPECT_DOUBLE_EQ(s.box_area, 2.0 + 3.0 + 1.0);
    EXPECT_DOUBLE_EQ(s.box_span, 3.0 + 4.0 + 2.0);
    EXPECT_DOUBLE_EQ(s.projected_area, 1.0 + 1.5 + 0.5);
    // area (|nx| + |ny| + |nz|) for unit n is half the cross product's L1 norm: 2/2, 3/2, (1 + 1)/2.
    EXPECT_DOUBLE_EQ(s.cube_area, 1.0 + 1.5 + 1.0);
    EXPECT_DOUBLE_EQ(s.extent, 3.0 + 4.0 + 3.0);
    EXPECT_EQ(s.lo, glm::vec3(0.0f));
    EXPECT_EQ(s.hi, glm::vec3(2.0f, 3.0f, 1.0f));
}

TEST(MeshSizes, ofAMeshWithoutCountableTrianglesAreEmpty) {
    const MeshSizes s = measure_mesh(MeshView{});
    EXPECT_EQ(s.triangles, 0u);
    const VoxelizeWork w = voxelize_work(s, glm::mat4(1.0f), GridDesc{});
    EXPECT_EQ(w.triangles, 0.0);
    EXPECT_EQ(w.columns, 0.0);
    EXPECT_EQ(w.fragments, 0.0);
}

/// A grid of 64^3 voxels of 0.5 from (-1, -1, -1).
GridDesc half_metre_grid() {
    GridDesc g;
    g.res = 64;
    g.voxel_size = 0.5f;
    g.origin = glm::vec3(-1.0f);
    return g;
}

TEST(MeshSizes, ofATriangleWhoseAreaOverflowsAFloatAreFiniteAndItsWorkIsTheGridsPart) {
    // Legs of 2e20: the cross product (8e40) passes a float's range, and an infinite area made a moving
    // mesh's first fragment and velocity lists larger than the device allows (`gust simulate` failed).
    TestMesh m;
    m.positions = {{-1e20f, 0.3f, -1e20f}, {1e20f, 0.3f, -1e20f}, {0.0f, 0.3f, 1e20f}};
    m.indices = {0, 1, 2};
    const MeshSizes s = measure_mesh(m.view());
    EXPECT_EQ(s.triangles, 1u);
    EXPECT_NEAR(s.projected_area, 2e40, 1e34) << "1e20 is a float: 100000002004087734272";
    EXPECT_TRUE(std::isfinite(s.cube_area) && std::isfinite(s.box_area));
    const VoxelizeWork w = voxelize_work(s, glm::mat4(1.0f), half_metre_grid());
    ASSERT_TRUE(std::isfinite(w.fragments));
    // The plane y = 0.3 crosses the 64 x 64 columns of the grid once: a few thousand fragments, not 2^29.
    EXPECT_LT(w.fragments, 4.0 * 64.0 * 64.0);
}

TEST(VoxelizeWork, followsTheTrianglesSizeInVoxels) {
    const TestMesh m = right_triangle();
    // Scaled by 2 on voxels of 0.5 the legs are 8 and 4 voxels: the compute path walks (8 + 1)(4 + 1)
    // columns; a pixel square meets the 16-voxel triangle grown by the square's half widths,
    // 16 + (8 + 4) + 1 (Minkowski sum); a voxel cube, 16 (|nz| = 1) + (8 + 4 + 0) + 1.
    const VoxelizeWork w = voxelize_work(measure_mesh(m.view()), glm::scale(glm::mat4(1.0f), glm::vec3(2.0f)),
                                         half_metre_grid());
    EXPECT_DOUBLE_EQ(w.triangles, 1.0);
    EXPECT_NEAR(w.columns, 45.0, 1e-9);
    EXPECT_NEAR(w.pixels, 29.0, 1e-9);
    EXPECT_NEAR(w.fragments, 29.0, 1e-9);
}

TEST(VoxelizeWork, countsOnlyThePartInsideTheGrid) {
    const TestMesh m = right_triangle();
    const MeshSizes s = measure_mesh(m.view());
    const glm::mat4 scaled = glm::scale(glm::mat4(1.0f), glm::vec3(2.0f));
    const VoxelizeWork inside = voxelize_work(s, scaled, half_metre_grid());
    // Moved 3 m (6 voxels) down x, the triangle spans grid x in [-4, 4]: grown by half a voxel, half of
    // [-4.5, 4.5] lies in the grid.
    const VoxelizeWork half = voxelize_work(
        s, glm::translate(glm::mat4(1.0f), glm::vec3(-3.0f, 0.0f, 0.0f)) * scaled, half_metre_grid());
    EXPECT_DOUBLE_EQ(half.triangles, 1.0) << "every triangle is still set up";
    EXPECT_NEAR(half.columns, 0.5 * inside.columns, 1e-9);
    EXPECT_NEAR(half.fragments, 0.5 * inside.fragments, 1e-9);
    const VoxelizeWork outside =
        voxelize_work(s, glm::translate(glm::mat4(1.0f), glm::vec3(1000.0f)) * scaled, half_metre_grid());
    EXPECT_EQ(outside.columns, 0.0);
    EXPECT_EQ(outside.pixels, 0.0);
    EXPECT_EQ(outside.fragments, 0.0);
}

TEST(VoxelizeWork, ofANonFiniteModelIsOnlyTheTriangles) {
    const TestMesh m = right_triangle();
    glm::mat4 model(1.0f);
    model[3][1] = std::numeric_limits<float>::infinity();
    const VoxelizeWork w = voxelize_work(measure_mesh(m.view()), model, half_metre_grid());
    EXPECT_DOUBLE_EQ(w.triangles, 1.0);
    EXPECT_EQ(w.columns, 0.0);
    EXPECT_EQ(w.fragments, 0.0);
}

using VoxelizeCostTest = GpuTest;

// On a GPU no measured row had the raster path faster (docs/cli.md, "How auto picks"), so auto takes the
// compute path even for a small mesh whose fixed costs the GPU fit puts in the raster path's favour; on a
// CPU device the model still sends few large triangles to the raster path.
TEST(CostModel, aGpuTakesTheComputePathWhereTheFitAloneWouldPickRaster) {
    gpu::DeviceInfo gpu_device, cpu_device;
    gpu_device.type = "discrete";
    cpu_device.type = "cpu";
    VoxelizeWork small;
    small.triangles = 12;
    small.pixels = 2000;
    small.columns = 2000;
    const PathCosts predicted = cost_model(gpu_device).predict(small);
    ASSERT_LT(predicted.raster_ms, predicted.compute_ms) << "the case the fit alone gets wrong";
    EXPECT_FALSE(cost_model(gpu_device).picks_raster(small));
    VoxelizeWork large_triangles;
    large_triangles.triangles = 12;
    large_triangles.pixels = 1e5;
    large_triangles.columns = 1e6;
    EXPECT_TRUE(cost_model(cpu_device).picks_raster(large_triangles));
    EXPECT_FALSE(cost_model(gpu_device).picks_raster(large_triangles));
}

TEST_F(VoxelizeCostTest, expectedFragmentsAreWithinFivePercentOfTheGpusCount) {
    struct Named {
        std::string name;
        TestMesh mesh;
        std::uint32_t res;
    };
    std::vector<Named> cases;
    cases.push_back({"sphere", icosphere(4, glm::vec3(0.0f), 1.0f), 96});
    for (const char* file : {"scans/dragon_res3.ply", "scans/bunny.ply"}) {
        auto loaded = load_mesh(std::string(GUST_ASSETS_DIR) + "/" + file);
        ASSERT_TRUE(loaded) << loaded.message();
        TestMesh m;
        m.positions = loaded->positions;
        m.indices = loaded->indices;
        cases.push_back({file, m, 160});
    }
    auto voxelizer = Voxelizer::create(ctx());
    ASSERT_TRUE(voxelizer);
    for (const Named& c : cases) {
        auto mesh = (*voxelizer)->upload(c.mesh.view());
        ASSERT_TRUE(mesh);
        const auto [lo, hi] = mesh_bounds(c.mesh.view());
        const GridDesc grid = grid_around(lo, hi, c.res);
        const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
        auto stats = (*voxelizer)->voxelize({&inst, 1}, grid, VoxelizeMethod::Compute);
        ASSERT_TRUE(stats) << stats.message();
        const double expected = voxelize_work(mesh->sizes(), inst.model, grid).fragments;
        EXPECT_NEAR(expected, double(stats->fragments), 0.05 * double(stats->fragments)) << c.name;
    }
}

TEST_F(VoxelizeCostTest, autoRunsOnePassOfThePathItPicksAndNothingElse) {
    const TestMesh sphere = icosphere(3, glm::vec3(0.0f), 1.0f);
    const auto [lo, hi] = mesh_bounds(sphere.view());
    for (std::uint32_t res : {16u, 200u}) {
        const GridDesc grid = grid_around(lo, hi, res);
        auto voxelizer = Voxelizer::create(ctx());
        ASSERT_TRUE(voxelizer);
        auto mesh = (*voxelizer)->upload(sphere.view());
        ASSERT_TRUE(mesh);
        const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
        const gpu::WorkCounts before = ctx().work();
        auto chosen = (*voxelizer)->voxelize({&inst, 1}, grid, VoxelizeMethod::Auto);
        ASSERT_TRUE(chosen) << chosen.message();
        const gpu::WorkCounts after_auto = ctx().work();
        ASSERT_NE(chosen->method, VoxelizeMethod::Auto);
        EXPECT_EQ(chosen->method,
                  cost_model(ctx().info()).picks_raster(voxelize_work(mesh->sizes(), inst.model, grid))
                      ? VoxelizeMethod::Raster
                      : VoxelizeMethod::Compute);
        auto named = (*voxelizer)->voxelize({&inst, 1}, grid, chosen->method);
        ASSERT_TRUE(named) << named.message();
        const gpu::WorkCounts after_named = ctx().work();
        EXPECT_EQ(chosen->retries, 0u);
        EXPECT_EQ(after_auto.submissions - before.submissions,
                  after_named.submissions - after_auto.submissions)
            << "auto submitted more than one pass of " << to_string(chosen->method) << " at " << res;
        EXPECT_EQ(after_auto.dispatches - before.dispatches, after_named.dispatches - after_auto.dispatches);
        EXPECT_EQ(after_auto.waits - before.waits, after_named.waits - after_auto.waits);
        EXPECT_EQ(chosen->fragments, named->fragments);
    }
}

TEST_F(VoxelizeCostTest, aDenseMeshFillsAListSizedFromItsTrianglesWithoutRedoingThePass) {
    // 5,120 triangles about 5 voxels across emit more fragments each than the six per triangle the list
    // was once sized to, so that a first call redid its pass.
    const TestMesh sphere = icosphere(4, glm::vec3(0.0f), 1.0f);
    const auto [lo, hi] = mesh_bounds(sphere.view());
    const GridDesc grid = grid_around(lo, hi, 160);
    for (VoxelizeMethod method : {VoxelizeMethod::Raster, VoxelizeMethod::Compute}) {
        VoxelizerDesc desc;
        desc.initial_capacity = 1;
        auto voxelizer = Voxelizer::create(ctx(), desc);
        ASSERT_TRUE(voxelizer);
        auto mesh = (*voxelizer)->upload(sphere.view());
        ASSERT_TRUE(mesh);
        const GpuInstance inst{&*mesh, glm::mat4(1.0f)};
        auto stats = (*voxelizer)->voxelize({&inst, 1}, grid, method);
        ASSERT_TRUE(stats) << stats.message();
        EXPECT_GT(stats->fragments, 6u * mesh->triangle_count());
        EXPECT_EQ(stats->retries, 0u) << to_string(method);
        EXPECT_LT(stats->capacity, 2 * stats->fragments) << "the first guess is near the need";
    }
}

} // namespace
} // namespace gust::test
