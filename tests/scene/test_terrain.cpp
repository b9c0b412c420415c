// Generated terrain (make_terrain_mesh, terrain_height) and the "terrain" object of scene files: counts,
// heights checked against docs/scene-format.md's formulas worked by hand, winding, determinism, and
// terrains loaded from scene files into a SceneRuntime.
#include "gust/scene/primitives.hpp"
#include "gust/scene/scene_file.hpp"
#include "gust/scene/scene_runtime.hpp"
#include "scene_test_support.hpp"

#include <cmath>
#include <cstddef>
#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <stdexcept>
#include <string>

namespace {

/// The vertex of `mesh` (a terrain built by make_terrain_mesh) at grid point (i, j).
glm::vec3 vertex(const gust::Mesh& mesh, const gust::TerrainDesc& terrain, std::size_t i, std::size_t j) {
    return mesh.positions.at(j * (terrain.samples.x + 1) + i);
}

/// A 40 m × 40 m terrain of 8 × 8 quads: vertices every 5 m from −20 to 20, (0, 0) at grid point (4, 4).
gust::TerrainDesc grid_of_5m() {
    gust::TerrainDesc terrain;
    terrain.size = {40.0f, 40.0f};
    terrain.samples = {8u, 8u};
    return terrain;
}

gust::TerrainDesc noisy(std::uint32_t seed) {
    gust::TerrainDesc terrain;
    terrain.size = {200.0f, 100.0f};
    terrain.samples = {64u, 32u};
    terrain.noise = gust::TerrainNoise{3.0f, 40.0f, 4u, seed};
    return terrain;
}

TEST(TerrainMesh, hasSharedGridVerticesAndTwoTrianglesPerQuad) {
    gust::TerrainDesc terrain;
    terrain.size = {10.0f, 20.0f};
    terrain.samples = {5u, 4u};
    const gust::Mesh mesh = gust::make_terrain_mesh(terrain);
    EXPECT_EQ(mesh.name, "terrain");
    EXPECT_EQ(mesh.positions.size(), 6u * 5u);
    EXPECT_EQ(mesh.triangle_count(), 2u * 5u * 4u);
    for (std::uint32_t index : mesh.indices)
        ASSERT_LT(index, mesh.positions.size());
    EXPECT_EQ(vertex(mesh, terrain, 0, 0), glm::vec3(-5.0f, 0.0f, -10.0f)) << "centred at the origin";
    EXPECT_EQ(vertex(mesh, terrain, 5, 4), glm::vec3(5.0f, 0.0f, 10.0f));
    EXPECT_EQ(vertex(mesh, terrain, 1, 0), glm::vec3(-3.0f, 0.0f, -10.0f)) << "x runs fastest";
}

TEST(TerrainMesh, everyTriangleFacesUp) {
    gust::TerrainDesc terrain = noisy(1);
    terrain.features.push_back({{0.0f, 0.0f}, {0.0f, 0.0f}, 30.0f, 20.0f});
    const gust::Mesh mesh = gust::make_terrain_mesh(terrain);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const glm::vec3 a = mesh.positions[mesh.indices[3 * t]];
        const glm::vec3 b = mesh.positions[mesh.indices[3 * t + 1]];
        const glm::vec3 c = mesh.positions[mesh.indices[3 * t + 2]];
        ASSERT_GT(glm::cross(b - a, c - a).y, 0.0f) << "triangle " << t;
    }
}

TEST(TerrainMesh, aHillIsItsHeightAtTheCentreAndFallsToHeightOverEAtItsRadius) {
    gust::TerrainDesc terrain = grid_of_5m();
    terrain.base = 2.0f;
    terrain.features.push_back({{0.0f, 0.0f}, {0.0f, 0.0f}, 10.0f, 5.0f});
    const gust::Mesh mesh = gust::make_terrain_mesh(terrain);
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 4, 4).y, 12.0f);
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 5, 4).y, 2.0f + 10.0f * 0.36787944f) << "5 m away: 10 / e";
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 4, 6).y, 2.0f + 10.0f * 0.018315639f) << "10 m away: 10 / e^4";
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 0, 0).y, 2.0f) << "28 m away: 10 / e^32 is below a float's step";
}

TEST(TerrainMesh, aRidgeKeepsItsHeightAlongItsSegmentAndFallsOffAcrossAndBeyondIt) {
    gust::TerrainDesc terrain = grid_of_5m();
    terrain.features.push_back({{-10.0f, 0.0f}, {10.0f, 0.0f}, 6.0f, 4.0f});
    const gust::Mesh mesh = gust::make_terrain_mesh(terrain);
    for (std::size_t i = 2; i <= 6; ++i)
        EXPECT_FLOAT_EQ(vertex(mesh, terrain, i, 4).y, 6.0f) << "x = " << vertex(mesh, terrain, i, 4).x;
    // 5 m from the segment, across it or beyond its end: 6 · e^(−(5/4)²) = 6 · 0.2096114.
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 4, 5).y, 6.0f * 0.20961139f);
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 4, 3).y, 6.0f * 0.20961139f);
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 7, 4).y, 6.0f * 0.20961139f);
    // (15, 5): 5 m beyond the end and 5 m across, √50 m away: 6 · e^(−50/16) = 6 · 0.0439369.
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 7, 5).y, 6.0f * 0.043936934f);
}

TEST(TerrainMesh, featuresAddUpAndANegativeHeightDigs) {
    gust::TerrainDesc terrain = grid_of_5m();
    terrain.base = 10.0f;
    terrain.features.push_back({{0.0f, -20.0f}, {0.0f, 20.0f}, -4.0f, 5.0f}); // a valley along z
    terrain.features.push_back({{0.0f, 0.0f}, {0.0f, 0.0f}, 1.0f, 5.0f});     // a hill in it
    const gust::Mesh mesh = gust::make_terrain_mesh(terrain);
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 4, 4).y, 10.0f - 4.0f + 1.0f);
    // (0, −20): on the valley's segment, 20 m from the hill (e^−16 = 1.1e−7).
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 4, 0).y, 10.0f - 4.0f + 1.1253517e-7f);
    // (5, −20): 5 m from the valley's segment, √425 m from the hill (e^−17 = 4.1e−8).
    EXPECT_FLOAT_EQ(vertex(mesh, terrain, 5, 0).y, 10.0f - 4.0f * 0.36787944f + 4.1399377e-8f);
}

TEST(TerrainMesh, theSameDescriptionBuildsTheSameMeshAndTheHeightsAreTerrainHeight) {
    const gust::TerrainDesc terrain = noisy(7);
    const gust::Mesh a = gust::make_terrain_mesh(terrain);
    const gust::Mesh b = gust::make_terrain_mesh(terrain);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.indices, b.indices);
    for (const glm::vec3& p : a.positions)
        ASSERT_EQ(p.y, static_cast<float>(gust::terrain_height(terrain, p.x, p.z)));
}

TEST(TerrainMesh, noiseStaysWithinItsAmplitudeAndEachSeedGivesAnotherLandscape) {
    const gust::Mesh seven = gust::make_terrain_mesh(noisy(7));
    const gust::Mesh eight = gust::make_terrain_mesh(noisy(8));
    std::size_t differ = 0;
    float low = 0.0f;
    float high = 0.0f;
    for (std::size_t v = 0; v < seven.positions.size(); ++v) {
        low = std::min(low, seven.positions[v].y);
        high = std::max(high, seven.positions[v].y);
        if (seven.positions[v].y != eight.positions[v].y) ++differ;
    }
    EXPECT_GE(low, -3.0f);
    EXPECT_LE(high, 3.0f);
    EXPECT_GT(high - low, 1.5f) << "the noise does make hills and hollows";
    EXPECT_GT(differ, seven.positions.size() * 9 / 10);
}

TEST(TerrainMesh, noiseIsSmoothBetweenNeighbouringVertices) {
    gust::TerrainDesc terrain = noisy(3);
    terrain.noise->octaves = 1;
    const gust::Mesh mesh = gust::make_terrain_mesh(terrain);
    // One octave of wavelength 40 m and amplitude 3 m: smoothstep's steepest slope is 1.5 lattice values
    // (each within ±1) per cell, so at most 3 · 2 · 1.5 / 40 m per metre, times a 3.125 m step.
    const float step = 200.0f / 64.0f;
    for (std::size_t j = 0; j <= 32; ++j) {
        for (std::size_t i = 0; i < 64; ++i)
            ASSERT_LE(std::abs(vertex(mesh, terrain, i + 1, j).y - vertex(mesh, terrain, i, j).y),
                      3.0f * 2.0f * 1.5f / 40.0f * step + 1e-4f);
    }
}

// ---------------------------------------------------------------------------------------------------
// Scene files

class TerrainScene : public testing::Test {
  protected:
    gust::SceneDesc load_ok(const std::string& text) {
        const gust::Result<gust::SceneDesc> scene = gust::load_scene(dir_.write("scene.json", text));
        if (!scene.ok()) throw std::runtime_error(scene.message());
        return *scene;
    }
    gust::test::TempDir dir_;
};

TEST_F(TerrainScene, readsEveryKeyAndFeatureType) {
    const gust::SceneDesc scene = load_ok(R"({"objects": [{"static": true,
      "transform": {"translate": [0, -5, 0]},
      "terrain": {"size": [300, 200.5], "samples": [30, 20], "base": -2.5,
                  "features": [{"type": "hill", "center": [10, -20], "height": 15, "radius": 40},
                               {"type": "ridge", "from": [-100, 0], "to": [100, 50], "height": -3, "width": 12},
                               {"type": "valley", "from": [0, -90], "to": [0, 90], "depth": 8, "width": 60}],
                  "noise": {"amplitude": 1.5, "wavelength": 25, "octaves": 3, "seed": 4000000000}}}]})");
    ASSERT_EQ(scene.objects.size(), 1u);
    const gust::SceneObject& object = scene.objects[0];
    EXPECT_TRUE(object.mesh.empty());
    EXPECT_TRUE(object.is_static);
    EXPECT_EQ(object.transform.translate, glm::vec3(0, -5, 0));
    ASSERT_TRUE(object.terrain.has_value());
    const gust::TerrainDesc& terrain = *object.terrain;
    EXPECT_EQ(terrain.size, glm::vec2(300.0f, 200.5f));
    EXPECT_EQ(terrain.samples, glm::uvec2(30u, 20u));
    EXPECT_EQ(terrain.base, -2.5f);
    ASSERT_EQ(terrain.features.size(), 3u);
    EXPECT_EQ(terrain.features[0].from, glm::vec2(10, -20));
    EXPECT_EQ(terrain.features[0].to, glm::vec2(10, -20)) << "a hill is a point";
    EXPECT_EQ(terrain.features[0].height, 15.0f);
    EXPECT_EQ(terrain.features[0].width, 40.0f);
    EXPECT_EQ(terrain.features[1].from, glm::vec2(-100, 0));
    EXPECT_EQ(terrain.features[1].to, glm::vec2(100, 50));
    EXPECT_EQ(terrain.features[1].height, -3.0f) << "a ridge may dig a trench";
    EXPECT_EQ(terrain.features[1].width, 12.0f);
    EXPECT_EQ(terrain.features[2].height, -8.0f) << "a valley digs by its depth";
    EXPECT_EQ(terrain.features[2].width, 60.0f);
    ASSERT_TRUE(terrain.noise.has_value());
    EXPECT_EQ(terrain.noise->amplitude, 1.5f);
    EXPECT_EQ(terrain.noise->wavelength, 25.0f);
    EXPECT_EQ(terrain.noise->octaves, 3u);
    EXPECT_EQ(terrain.noise->seed, 4000000000u);
}

TEST_F(TerrainScene, anEmptyTerrainIsAFlat100MetreSquareOf100By100Quads) {
    const gust::SceneDesc scene = load_ok(R"({"objects": [{"terrain": {"noise": {}}}]})");
    const gust::TerrainDesc& terrain = scene.objects.at(0).terrain.value();
    EXPECT_EQ(terrain.size, glm::vec2(100.0f, 100.0f));
    EXPECT_EQ(terrain.samples, glm::uvec2(100u, 100u));
    EXPECT_EQ(terrain.base, 0.0f);
    EXPECT_TRUE(terrain.features.empty());
    ASSERT_TRUE(terrain.noise.has_value());
    EXPECT_EQ(terrain.noise->amplitude, 1.0f);
    EXPECT_EQ(terrain.noise->wavelength, 50.0f);
    EXPECT_EQ(terrain.noise->octaves, 4u);
    EXPECT_EQ(terrain.noise->seed, 0u);
    EXPECT_FALSE(scene.objects[0].is_static);
}

TEST_F(TerrainScene, theRuntimeGeneratesEachTerrainAndMovesItLikeAMesh) {
    const gust::SceneDesc scene = load_ok(R"({"objects": [
      {"terrain": {"size": [10, 10], "samples": [2, 3], "base": 1}, "static": true},
      {"terrain": {"size": [4, 4], "samples": [1, 1]},
       "keyframes": [{"t": 0, "translate": [0, 0, 0]}, {"t": 1, "translate": [2, 0, 0]}]}]})");
    gust::Result<gust::SceneRuntime> runtime = gust::SceneRuntime::load(scene);
    ASSERT_TRUE(runtime.ok()) << runtime.message();
    ASSERT_EQ(runtime->object_count(), 2u);
    EXPECT_EQ(runtime->mesh(0).triangle_count(), 12u);
    EXPECT_EQ(runtime->mesh(0).positions.size(), 12u);
    EXPECT_EQ(runtime->mesh(0).positions[0], glm::vec3(-5.0f, 1.0f, -5.0f));
    EXPECT_EQ(runtime->mesh(1).triangle_count(), 2u);
    EXPECT_FALSE(runtime->deforms(1));
    EXPECT_EQ(runtime->positions(1, 0.5), runtime->mesh(1).positions);
    EXPECT_EQ(glm::vec3(runtime->model(1, 0.5)[3]), glm::vec3(1.0f, 0.0f, 0.0f));
}

} // namespace
