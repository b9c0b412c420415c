// The CPU reference voxelizer against hand-computed cases, brute force, closed-form voxel sets and
// OpenVDB's distance fields.
#include "gust/voxelizer/cpu_reference.hpp"
#include "support/mesh_gen.hpp"
#include "support/vdb_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <gtest/gtest.h>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace gust {
namespace {

using test::TestMesh;

std::vector<InstanceDesc> instances_of(const TestMesh& mesh, const glm::mat4& model = glm::mat4(1.0f)) {
    return {InstanceDesc{mesh.view(), model}};
}

GridDesc grid_of(glm::vec3 origin, float voxel_size, std::uint32_t res) {
    GridDesc grid;
    grid.origin = origin;
    grid.voxel_size = voxel_size;
    grid.res = res;
    return grid;
}

bool overlap(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, glm::dvec3 box_min, glm::dvec3 box_max) {
    const glm::dvec3 tri[3] = {a, b, c};
    return triangle_box_overlap(tri, box_min, box_max);
}

/// Every voxel of the grid tested against every triangle, reading triangles as the reference does.
std::vector<std::uint32_t> brute_force(const TestMesh& mesh, const GridDesc& grid, double grow = 0.0) {
    std::vector<std::uint32_t> keys;
    const glm::dvec3 origin(grid.origin);
    const double h = grid.voxel_size;
    for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
        glm::dvec3 tri[3];
        for (int c = 0; c < 3; ++c)
            tri[c] = (glm::dvec3(mesh.positions[mesh.indices[t + c]]) - origin) / h;
        if (glm::cross(tri[1] - tri[0], tri[2] - tri[0]) == glm::dvec3(0.0)) continue;
        for (std::uint32_t k = 0; k < grid.res; ++k) {
            for (std::uint32_t j = 0; j < grid.res; ++j) {
                for (std::uint32_t i = 0; i < grid.res; ++i) {
                    const glm::dvec3 lo = glm::dvec3(i, j, k) - grow;
                    if (triangle_box_overlap(tri, lo, lo + 1.0 + 2.0 * grow))
                        keys.push_back(pack_voxel(i, j, k));
                }
            }
        }
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return keys;
}

/// Sutherland-Hodgman clipping of the triangle by the box's six closed half-spaces: an independent
/// overlap test (non-empty remainder) to check the separating-axis test against.
bool overlap_by_clipping(const glm::dvec3 tri[3], const glm::dvec3& box_min, const glm::dvec3& box_max) {
    std::vector<glm::dvec3> polygon(tri, tri + 3);
    for (int axis = 0; axis < 3; ++axis) {
        for (const double sign : {1.0, -1.0}) {
            const double bound = sign > 0 ? box_min[axis] : -box_max[axis];
            std::vector<glm::dvec3> kept;
            for (std::size_t i = 0; i < polygon.size(); ++i) {
                const glm::dvec3& a = polygon[i];
                const glm::dvec3& b = polygon[(i + 1) % polygon.size()];
                const double da = sign * a[axis] - bound;
                const double db = sign * b[axis] - bound;
                if (da >= 0) kept.push_back(a);
                if ((da > 0 && db < 0) || (da < 0 && db > 0)) kept.push_back(a + (b - a) * (da / (da - db)));
            }
            polygon = std::move(kept);
            if (polygon.empty()) return false;
        }
    }
    return true;
}

std::vector<std::uint32_t> sorted_keys(std::vector<std::uint32_t> keys) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return keys;
}

/// Two triangles covering the square [-1, res + 1]^2 at height z (grid units, origin 0, h = 1).
TestMesh horizontal_square(float z, std::uint32_t res) {
    const float far = static_cast<float>(res) + 1.0f;
    TestMesh mesh;
    mesh.positions = {{-1.0f, -1.0f, z}, {far, -1.0f, z}, {far, far, z}, {-1.0f, far, z}};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    return mesh;
}

TEST(CpuReference, triangleBoxOverlapCountsTouchingAsOverlap) {
    // A triangle in the plane z = 1 lies on the top face of voxel k = 0 and the bottom face of k = 1.
    const glm::dvec3 a(-1, -1, 1), b(3, -1, 1), c(-1, 3, 1);
    EXPECT_TRUE(overlap(a, b, c, {0, 0, 0}, {1, 1, 1}));
    EXPECT_TRUE(overlap(a, b, c, {0, 0, 1}, {1, 1, 2}));
    EXPECT_FALSE(overlap(a, b, c, {0, 0, 2}, {1, 1, 3}));
    EXPECT_FALSE(overlap(a, b, c, {0, 0, 1 + 1e-12}, {1, 1, 2}));
    // Only the vertex (1,1,1) reaches the box [0,1]^3: every other point has a coordinate above 1.
    EXPECT_TRUE(overlap({1, 1, 1}, {2, 1.5, 1.2}, {1.5, 2, 1.7}, {0, 0, 0}, {1, 1, 1}));
    EXPECT_FALSE(overlap({1 + 1e-12, 1, 1}, {2, 1.5, 1.2}, {1.5, 2, 1.7}, {0, 0, 0}, {1, 1, 1}));
}

TEST(CpuReference, triangleBoxOverlapSeparatesByEdgeCrossAxis) {
    const glm::dvec3 box_min(0, 0, 0), box_max(1, 1, 1);
    // In the plane z = 0.5 (which cuts the box), the triangle x + y >= 3 beyond the corner x = y = 1:
    // bounding boxes overlap, only the axis (1,1,0) = z x edge separates.
    EXPECT_FALSE(overlap({2.5, 0.5, 0.5}, {0.5, 2.5, 0.5}, {2.5, 2.5, 0.5}, box_min, box_max));
    // Its edge moved onto x + y = 2 touches the box's vertical edge at (1, 1, 0.5).
    EXPECT_TRUE(overlap({2, 0, 0.5}, {0, 2, 0.5}, {2, 2, 0.5}, box_min, box_max));

    // A tilted triangle in the plane x + y + z = 2.9, which cuts the corner (1,1,1) off the box: the cut
    // is the small triangle with z >= 0.9, the triangle keeps z <= 0.5.
    const glm::dvec3 a(2.9, 0, 0), b(0, 2.9, 0), c(1.2, 1.2, 0.5);
    const glm::dvec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
    ASSERT_TRUE(glm::all(glm::lessThanEqual(lo, box_max)) && glm::all(glm::greaterThanEqual(hi, box_min)));
    EXPECT_FALSE(overlap(a, b, c, box_min, box_max));
    // Raised to reach z = 0.95 it meets the cut.
    EXPECT_TRUE(overlap(a, b, {0.975, 0.975, 0.95}, box_min, box_max));
}

TEST(CpuReference, triangleBoxOverlapHandlesZeroAreaTriangles) {
    const glm::dvec3 box_min(0, 0, 0), box_max(1, 1, 1);
    EXPECT_TRUE(overlap({-1, 0.5, 0.5}, {2, 0.5, 0.5}, {2, 0.5, 0.5}, box_min, box_max));
    EXPECT_TRUE(overlap({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, box_min, box_max));
    // A diagonal segment passing the corner (1,1,z) at distance 0.01 along (1,1,0).
    EXPECT_FALSE(overlap({2.01, 0.01, 0.5}, {0.01, 2.01, 0.5}, {1.01, 1.01, 0.5}, box_min, box_max));
}

TEST(CpuReference, triangleBoxOverlapMatchesPolygonClipping) {
    std::mt19937 engine(7);
    const auto coordinate = [&](double lo, double hi) {
        return lo + (hi - lo) * static_cast<double>(engine()) / 4294967296.0;
    };
    int overlapping = 0;
    for (int n = 0; n < 100000; ++n) {
        const double scale = n % 3 == 0 ? 0.3 : 2.0;
        glm::dvec3 tri[3];
        const glm::dvec3 centre(coordinate(-1, 2), coordinate(-1, 2), coordinate(-1, 2));
        for (glm::dvec3& v : tri) {
            v = centre + scale * glm::dvec3(coordinate(-1, 1), coordinate(-1, 1), coordinate(-1, 1));
        }
        const bool expected = overlap_by_clipping(tri, glm::dvec3(0), glm::dvec3(1));
        overlapping += expected;
        ASSERT_EQ(triangle_box_overlap(tri, glm::dvec3(0), glm::dvec3(1)), expected) << "case " << n;
    }
    // Both outcomes must be well represented for the comparison to mean anything.
    EXPECT_GT(overlapping, 10000);
    EXPECT_LT(overlapping, 90000);
}

TEST(CpuReference, referenceOccupiesBothVoxelsAroundATriangleOnAVoxelPlane) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 1.0f, 16);
    const TestMesh on_plane = horizontal_square(5.0f, grid.res);
    const CpuVoxelization both = voxelize_reference(instances_of(on_plane), grid);
    EXPECT_EQ(both.voxels.size(), 2u * 16 * 16);
    for (const std::uint32_t key : both.voxels) {
        const std::uint32_t k = unpack_voxel(key).z;
        EXPECT_TRUE(k == 4 || k == 5) << k;
    }
    const TestMesh mid_voxel = horizontal_square(5.5f, grid.res);
    const CpuVoxelization one = voxelize_reference(instances_of(mid_voxel), grid);
    EXPECT_EQ(one.voxels.size(), 16u * 16);
}

TEST(CpuReference, referenceMatchesBruteForceOnEveryVoxel) {
    // Power-of-two voxel size and an origin on its multiples keep grid-space coordinates exact.
    const GridDesc grid = grid_of({-0.75f, 0.5f, 0.25f}, 0.125f, 16);
    const TestMesh meshes[] = {test::random_soup(1, 300, grid), test::partly_outside(grid, 2, 100),
                               test::huge_triangles(grid), test::grid_aligned_boxes(grid, 6, 3)};
    for (const TestMesh& mesh : meshes) {
        EXPECT_EQ(voxelize_reference(instances_of(mesh), grid).voxels, brute_force(mesh, grid));
        EXPECT_EQ(voxelize_reference(instances_of(mesh), grid, 1e-3).voxels, brute_force(mesh, grid, 1e-3));
        EXPECT_EQ(voxelize_reference(instances_of(mesh), grid, -1e-3).voxels, brute_force(mesh, grid, -1e-3));
    }
}

TEST(CpuReference, referenceOccupiesBothSidesOfGridAlignedBoxFaces) {
    const GridDesc grid = grid_of({1.0f, -2.0f, 0.5f}, 0.25f, 32);
    const TestMesh boxes = test::grid_aligned_boxes(grid, 5, 11);
    // A closed voxel box meets the closed surface of box [lo, hi] (voxel planes) exactly when the voxel
    // lies in [lo - 1, hi] on every axis but not strictly inside, [lo + 1, hi - 2] on every axis.
    std::vector<std::uint32_t> expected;
    for (std::size_t b = 0; b < boxes.positions.size() / 8; ++b) {
        glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
        for (std::size_t v = 8 * b; v < 8 * b + 8; ++v) {
            const glm::ivec3 p = glm::ivec3(glm::round((boxes.positions[v] - grid.origin) / grid.voxel_size));
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
        }
        for (int k = std::max(lo.z - 1, 0); k <= std::min<int>(hi.z, grid.res - 1); ++k) {
            for (int j = std::max(lo.y - 1, 0); j <= std::min<int>(hi.y, grid.res - 1); ++j) {
                for (int i = std::max(lo.x - 1, 0); i <= std::min<int>(hi.x, grid.res - 1); ++i) {
                    const glm::ivec3 cell(i, j, k);
                    const bool interior = glm::all(glm::greaterThanEqual(cell, lo + 1)) &&
                                          glm::all(glm::lessThanEqual(cell, hi - 2));
                    if (!interior) expected.push_back(pack_voxel(i, j, k));
                }
            }
        }
    }
    EXPECT_EQ(voxelize_reference(instances_of(boxes), grid).voxels, sorted_keys(expected));
}

TEST(CpuReference, referenceMatchesPlaneSectionForHugeTriangles) {
    const GridDesc grid = grid_of({-3.0f, 1.0f, 2.0f}, 0.0625f, 64);
    const TestMesh huge = test::huge_triangles(grid);
    for (std::size_t t = 0; t < huge.indices.size(); t += 3) {
        TestMesh one;
        for (std::size_t c = 0; c < 3; ++c)
            one.positions.push_back(huge.positions[huge.indices[t + c]]);
        one.indices = {0, 1, 2};
        // Each triangle covers its plane's whole section of the grid, so the voxels are exactly those
        // whose box the plane meets: |n . centre - d| <= sum(|n_k|) / 2.
        glm::dvec3 v[3];
        for (int c = 0; c < 3; ++c)
            v[c] = (glm::dvec3(one.positions[c]) - glm::dvec3(grid.origin)) / 0.0625;
        const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
        const double d = glm::dot(n, v[0]);
        const double radius = 0.5 * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
        std::vector<std::uint32_t> expected;
        for (std::uint32_t k = 0; k < grid.res; ++k) {
            for (std::uint32_t j = 0; j < grid.res; ++j) {
                for (std::uint32_t i = 0; i < grid.res; ++i) {
                    if (std::abs(glm::dot(n, glm::dvec3(i, j, k) + 0.5) - d) <= radius) {
                        expected.push_back(pack_voxel(i, j, k));
                    }
                }
            }
        }
        EXPECT_EQ(voxelize_reference(instances_of(one), grid).voxels, sorted_keys(expected))
            << "triangle " << t;
    }
}

TEST(CpuReference, referenceCoversADiagonalPlaneAcrossTheLargestGrid) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 1.0f, kMaxRes);
    // The triangle {x, y, z >= -1024, x + y + z = 1536} contains the plane's whole section of the grid;
    // voxel (i,j,k) meets the plane exactly when i + j + k is in [1533, 1536].
    TestMesh plane;
    plane.positions = {
        {3584.0f, -1024.0f, -1024.0f}, {-1024.0f, 3584.0f, -1024.0f}, {-1024.0f, -1024.0f, 3584.0f}};
    plane.indices = {0, 1, 2};
    const CpuVoxelization result = voxelize_reference(instances_of(plane), grid);
    std::uint64_t expected = 0;
    for (std::int64_t i = 0; i < 1024; ++i) {
        for (std::int64_t j = 0; j < 1024; ++j) {
            const std::int64_t first = std::max<std::int64_t>(1533 - i - j, 0);
            const std::int64_t last = std::min<std::int64_t>(1536 - i - j, 1023);
            expected += static_cast<std::uint64_t>(std::max<std::int64_t>(last - first + 1, 0));
        }
    }
    EXPECT_EQ(result.voxels.size(), expected);
    const bool all_on_plane = std::all_of(result.voxels.begin(), result.voxels.end(), [](std::uint32_t key) {
        const glm::uvec3 c = unpack_voxel(key);
        return c.x + c.y + c.z >= 1533 && c.x + c.y + c.z <= 1536;
    });
    EXPECT_TRUE(all_on_plane);
}

TEST(CpuReference, referenceRejectsNonFiniteTriangles) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 0.0625f, 16);
    const test::BadTriangles bad = test::bad_triangles();
    const CpuVoxelization result = voxelize_reference(instances_of(bad.mesh), grid);
    EXPECT_EQ(result.triangles, bad.mesh.indices.size() / 3);
    EXPECT_EQ(result.rejected, bad.expected_rejected);

    // The voxels are those of the finite triangles alone (zero-area ones add nothing).
    TestMesh finite;
    finite.positions = bad.mesh.positions;
    std::uint64_t zero_area = 0;
    for (std::size_t t = 0; t < bad.mesh.indices.size(); t += 3) {
        glm::vec3 v[3];
        for (int c = 0; c < 3; ++c)
            v[c] = bad.mesh.positions[bad.mesh.indices[t + c]];
        const bool is_finite = std::all_of(v, v + 3, [](const glm::vec3& p) {
            return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
        });
        if (!is_finite) continue;
        zero_area += glm::cross(glm::dvec3(v[1] - v[0]), glm::dvec3(v[2] - v[0])) == glm::dvec3(0.0);
        finite.indices.insert(finite.indices.end(), bad.mesh.indices.begin() + static_cast<std::ptrdiff_t>(t),
                              bad.mesh.indices.begin() + static_cast<std::ptrdiff_t>(t + 3));
    }
    EXPECT_EQ(zero_area, bad.expected_zero_area);
    EXPECT_FALSE(result.voxels.empty());
    EXPECT_EQ(result.voxels, voxelize_reference(instances_of(finite), grid).voxels);

    // A non-finite model matrix rejects every triangle of its instance.
    glm::mat4 broken(1.0f);
    broken[3][0] = std::numeric_limits<float>::infinity();
    const CpuVoxelization all_rejected = voxelize_reference(instances_of(finite, broken), grid);
    EXPECT_EQ(all_rejected.rejected, finite.indices.size() / 3);
    EXPECT_TRUE(all_rejected.voxels.empty());
}

TEST(CpuReference, referenceRejectsOutOfRangeIndices) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 0.0625f, 16);
    test::BadTriangles bad = test::bad_triangles();
    bad.mesh.indices.insert(bad.mesh.indices.end(),
                            {0, 1, static_cast<std::uint32_t>(bad.mesh.positions.size())});
    const CpuVoxelization result = voxelize_reference(instances_of(bad.mesh), grid);
    EXPECT_EQ(result.rejected, bad.expected_rejected + 1);
}

TEST(CpuReference, referenceClipsToGrid) {
    const GridDesc grid = grid_of({0.5f, -1.0f, 0.25f}, 0.125f, 16);
    const TestMesh straddling = test::partly_outside(grid, 5, 200);
    const CpuVoxelization clipped = voxelize_reference(instances_of(straddling), grid);
    // The same triangles on a grid 8 voxels larger on every side, cut back to the small grid.
    const GridDesc larger = grid_of(grid.origin - 8.0f * grid.voxel_size, grid.voxel_size, grid.res + 16);
    std::vector<std::uint32_t> cut;
    std::size_t outside = 0;
    for (const std::uint32_t key : voxelize_reference(instances_of(straddling), larger).voxels) {
        const glm::uvec3 c = unpack_voxel(key);
        if (glm::all(glm::greaterThanEqual(c, glm::uvec3(8))) &&
            glm::all(glm::lessThan(c, glm::uvec3(8 + grid.res)))) {
            cut.push_back(pack_voxel(c.x - 8, c.y - 8, c.z - 8));
        } else {
            ++outside;
        }
    }
    EXPECT_GT(outside, 0u);
    EXPECT_EQ(clipped.voxels, cut);
}

TEST(CpuReference, referenceHonoursModelMatrixAndVertexStride) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 0.25f, 32);
    const TestMesh boxes = test::grid_aligned_boxes(grid_of(glm::vec3(0.0f), 0.25f, 12), 4, 9);
    // world = (2z + 0.5, -y + 7, x + 1): scale 2 and a signed permutation, exact in float.
    glm::mat4 model(0.0f);
    model[2][0] = 2.0f;
    model[1][1] = -1.0f;
    model[0][2] = 1.0f;
    model[3] = {0.5f, 7.0f, 1.0f, 1.0f};
    TestMesh moved = boxes;
    std::vector<float> interleaved; // position then a dummy normal: 24-byte stride
    for (glm::vec3& p : moved.positions) {
        interleaved.insert(interleaved.end(), {p.x, p.y, p.z, 0.0f, 1.0f, 0.0f});
        p = glm::vec3(model * glm::vec4(p, 1.0f));
    }
    MeshView strided = boxes.view();
    strided.positions = interleaved.data();
    strided.position_stride = 6 * sizeof(float);
    const std::vector<InstanceDesc> instances = {InstanceDesc{strided, model}};
    const CpuVoxelization result = voxelize_reference(instances, grid);
    EXPECT_FALSE(result.voxels.empty());
    EXPECT_EQ(result.voxels, voxelize_reference(instances_of(moved), grid).voxels);
}

TEST(CpuReference, referenceCountsTrianglesOfEveryInstance) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 0.125f, 16);
    const TestMesh soup = test::random_soup(4, 50, grid);
    const TestMesh boxes = test::grid_aligned_boxes(grid, 2, 4);
    const std::vector<InstanceDesc> both = {{soup.view(), glm::mat4(1.0f)}, {boxes.view(), glm::mat4(1.0f)}};
    const CpuVoxelization result = voxelize_reference(both, grid);
    EXPECT_EQ(result.triangles, 50u + 24u);
    std::vector<std::uint32_t> merged = voxelize_reference(instances_of(soup), grid).voxels;
    const std::vector<std::uint32_t> box_voxels = voxelize_reference(instances_of(boxes), grid).voxels;
    merged.insert(merged.end(), box_voxels.begin(), box_voxels.end());
    EXPECT_EQ(result.voxels, sorted_keys(merged));
}

TEST(CpuReference, referenceBoxGrowProbesNearTouches) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 1.0f, 16);
    const TestMesh above_face = horizontal_square(5.0001f, grid.res);
    EXPECT_EQ(voxelize_reference(instances_of(above_face), grid).voxels.size(), 256u);
    EXPECT_EQ(voxelize_reference(instances_of(above_face), grid, 1e-3).voxels.size(), 512u);
    EXPECT_EQ(voxelize_reference(instances_of(above_face), grid, -5e-5).voxels.size(), 256u);
    EXPECT_TRUE(voxelize_reference(instances_of(above_face), grid, -1e-3).voxels.empty());
    const TestMesh on_face = horizontal_square(5.0f, grid.res);
    EXPECT_TRUE(voxelize_reference(instances_of(on_face), grid, -1e-3).voxels.empty());
}

TEST(CpuReference, diffVoxelsSplitsMissingAndExtra) {
    const std::vector<std::uint32_t> candidate = {1, 2, 5, 9};
    const std::vector<std::uint32_t> reference = {2, 3, 5, 7};
    const VoxelDiff diff = diff_voxels(candidate, reference);
    EXPECT_EQ(diff.missing, (std::vector<std::uint32_t>{3, 7}));
    EXPECT_EQ(diff.extra, (std::vector<std::uint32_t>{1, 9}));
    EXPECT_TRUE(diff_voxels(reference, reference).missing.empty());
}

TEST(CpuReference, unexplainedDifferencesExcusesOnlyNearTouches) {
    const GridDesc grid = grid_of(glm::vec3(0.0f), 1.0f, 16);
    const TestMesh above_face = horizontal_square(5.0001f, grid.res);
    const auto instances = instances_of(above_face);
    const std::vector<std::uint32_t> reference = voxelize_reference(instances, grid).voxels;
    const auto unexplained = [&](std::vector<std::uint32_t> candidate) {
        return unexplained_differences(diff_voxels(sorted_keys(std::move(candidate)), reference), instances,
                                       grid);
    };
    // The plane is 1e-4 voxel above layer 4 and below layer 5's shrunk box.
    std::vector<std::uint32_t> with_layer_4 = reference;
    for (std::uint32_t j = 0; j < 16; ++j) {
        for (std::uint32_t i = 0; i < 16; ++i)
            with_layer_4.push_back(pack_voxel(i, j, 4));
    }
    EXPECT_TRUE(unexplained(with_layer_4).empty());
    std::vector<std::uint32_t> without_one = reference;
    without_one.erase(without_one.begin() + 17);
    EXPECT_TRUE(unexplained(without_one).empty());

    std::vector<std::uint32_t> with_layer_3 = reference;
    with_layer_3.push_back(pack_voxel(3, 4, 3));
    EXPECT_EQ(unexplained(with_layer_3), (std::vector<std::uint32_t>{pack_voxel(3, 4, 3)}));
    std::vector<std::uint32_t> outside_grid = reference;
    outside_grid.push_back(pack_voxel(16, 0, 5));
    EXPECT_EQ(unexplained(outside_grid), (std::vector<std::uint32_t>{pack_voxel(16, 0, 5)}));

    const TestMesh mid_voxel = horizontal_square(5.5f, grid.res);
    const auto mid_instances = instances_of(mid_voxel);
    std::vector<std::uint32_t> mid = voxelize_reference(mid_instances, grid).voxels;
    const std::uint32_t dropped = mid[40];
    mid.erase(mid.begin() + 40);
    const VoxelDiff diff = diff_voxels(mid, voxelize_reference(mid_instances, grid).voxels);
    EXPECT_EQ(unexplained_differences(diff, mid_instances, grid), (std::vector<std::uint32_t>{dropped}));
}

TEST(CpuReference, unexplainedDifferencesExcusesGrowthWithinTolerance) {
    const GridDesc grid = grid_of({-0.5f, -0.5f, -0.5f}, 0.0625f, 32);
    const TestMesh soup = test::random_soup(21, 800, grid);
    const auto instances = instances_of(soup);
    const std::vector<std::uint32_t> reference = voxelize_reference(instances, grid).voxels;
    const CpuVoxelization grown = voxelize_reference(instances, grid, 5e-4);
    const CpuVoxelization shrunk = voxelize_reference(instances, grid, -5e-4);
    const VoxelDiff grown_diff = diff_voxels(grown.voxels, reference);
    const VoxelDiff shrunk_diff = diff_voxels(shrunk.voxels, reference);
    EXPECT_TRUE(unexplained_differences(grown_diff, instances, grid).empty());
    EXPECT_TRUE(unexplained_differences(shrunk_diff, instances, grid).empty());
    // Growth by a twentieth of a voxel is far beyond rounding.
    const CpuVoxelization fat = voxelize_reference(instances, grid, 0.05);
    const VoxelDiff fat_diff = diff_voxels(fat.voxels, reference);
    ASSERT_FALSE(fat_diff.extra.empty());
    EXPECT_FALSE(unexplained_differences(fat_diff, instances, grid).empty());
}

struct VdbCase {
    std::string mesh;
    std::uint32_t res;
};

class CpuReferenceVsOpenVdb : public testing::TestWithParam<VdbCase> {};

// Occupied means the voxel box meets the surface, so the centre is within half a diagonal of it; and a
// surface point within half a voxel of the centre lies inside the box.
TEST_P(CpuReferenceVsOpenVdb, referenceAgreesWithDistanceToSurface) {
    const VdbCase& param = GetParam();
    const GridDesc grid = grid_of({-1.1f, -0.9f, -1.05f}, 2.2f / static_cast<float>(param.res), param.res);
    const TestMesh mesh = param.mesh == "soup" ? test::random_soup(param.res, 8 * param.res, grid)
                                               : test::icosphere(3, {0.02f, 0.13f, -0.07f}, 0.8f);
    const std::vector<std::uint32_t> voxels = voxelize_reference(instances_of(mesh), grid).voxels;
    ASSERT_FALSE(voxels.empty());

    const test::DistanceCheck check = test::check_against_distance_field(mesh, grid, voxels);
    for (const std::string& example : check.examples)
        ADD_FAILURE() << example;
    EXPECT_EQ(check.uncovered, 0u);
    EXPECT_EQ(check.too_far, 0u);
    EXPECT_GT(check.near_surface, voxels.size() / 10);
}

INSTANTIATE_TEST_SUITE_P(Meshes, CpuReferenceVsOpenVdb,
                         testing::Values(VdbCase{"soup", 37}, VdbCase{"soup", 64}, VdbCase{"icosphere", 37},
                                         VdbCase{"icosphere", 64}),
                         [](const testing::TestParamInfo<VdbCase>& test_case) {
                             return test_case.param.mesh + std::to_string(test_case.param.res);
                         });

} // namespace
} // namespace gust
