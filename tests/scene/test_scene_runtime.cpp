// SceneRuntime: meshes loaded once and shared, animated objects posed at the scene's clip time, load
// errors naming the object and file; and the example scenes in assets/scenes load and stay inside
// their domains (the valley's in its cascades).
#include "gust/scene/animated_mesh.hpp"
#include "gust/scene/primitives.hpp"
#include "gust/scene/scene_file.hpp"
#include "gust/scene/scene_runtime.hpp"
#include "scene_test_support.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using gust::test::kDesignExample;

const fs::path kAssets = GUST_ASSETS_DIR;

struct Box {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{std::numeric_limits<float>::lowest()};
    void add(glm::vec3 p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    bool overlaps(const Box& other) const {
        return glm::all(glm::lessThanEqual(min, other.max)) && glm::all(glm::lessThanEqual(other.min, max));
    }
};

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

gust::SceneDesc scene_ok(const fs::path& file) {
    gust::Result<gust::SceneDesc> scene = gust::load_scene(file);
    if (!scene.ok()) throw std::runtime_error(scene.message());
    return *scene;
}

gust::SceneRuntime runtime_ok(const gust::SceneDesc& scene) {
    gust::Result<gust::SceneRuntime> runtime = gust::SceneRuntime::load(scene);
    if (!runtime.ok()) throw std::runtime_error(runtime.message());
    return std::move(*runtime);
}

/// World-space positions of an object at time t.
std::vector<glm::vec3> world(gust::SceneRuntime& runtime, std::size_t object, double t) {
    const glm::mat4 model = runtime.model(object, t);
    std::vector<glm::vec3> out;
    for (const glm::vec3& p : runtime.positions(object, t))
        out.emplace_back(model * glm::vec4(p, 1.0f));
    return out;
}

Box world_box(gust::SceneRuntime& runtime, std::size_t object, double t) {
    Box box;
    for (const glm::vec3& p : world(runtime, object, t))
        box.add(p);
    return box;
}

Box domain_box(const gust::DomainDesc& domain) {
    const glm::vec3 half = glm::vec3(domain.cells) * domain.cell_size * 0.5f;
    return {domain.center - half, domain.center + half};
}

double last_key_time(const gust::SceneDesc& scene) {
    double last = 0.0;
    for (const gust::SceneObject& object : scene.objects) {
        if (!object.keyframes.empty()) last = std::max(last, object.keyframes.back().t);
    }
    return last;
}

double signed_volume(const gust::Mesh& mesh) {
    double volume = 0.0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const glm::dvec3 a = mesh.positions[mesh.indices[3 * t]];
        const glm::dvec3 b = mesh.positions[mesh.indices[3 * t + 1]];
        const glm::dvec3 c = mesh.positions[mesh.indices[3 * t + 2]];
        volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    return volume;
}

class SceneRuntimeTest : public testing::Test {
  protected:
    fs::path copy(const fs::path& from, const std::string& name) const {
        return dir_.write(name, read_file(from));
    }
    fs::path scene(const std::string& text) const { return dir_.write("scene.json", text); }
    gust::test::TempDir dir_;
};

// ---------------------------------------------------------------------------------------------------
// Loading and sharing

TEST_F(SceneRuntimeTest, loadsTheDesignExampleWithRealMeshes) {
    copy(kAssets / "scenes/wall.obj", "wall.obj");
    copy(kAssets / "scans/bunny.ply", "bunny.ply");
    const gust::SceneDesc desc = scene_ok(scene(kDesignExample));
    gust::SceneRuntime runtime = runtime_ok(desc);
    ASSERT_EQ(runtime.object_count(), 2u);
    EXPECT_EQ(runtime.mesh(0).triangle_count(), 12u);
    EXPECT_EQ(runtime.mesh(1).triangle_count(), 3674u);
    EXPECT_FALSE(runtime.deforms(0));
    EXPECT_FALSE(runtime.deforms(1));
    EXPECT_EQ(&runtime.positions(1, 1.0), &runtime.mesh(1).positions) << "rigid objects use the rest pose";
    EXPECT_EQ(runtime.model(1, 1.0), gust::object_matrix(desc.objects[1], 1.0));
    EXPECT_EQ(runtime.model(0, 5.0), desc.objects[0].transform.matrix());
}

TEST_F(SceneRuntimeTest, loadsEachMeshFileOnceForAllItsObjects) {
    copy(kAssets / "scans/bunny.ply", "bunny.ply");
    gust::SceneRuntime runtime = runtime_ok(scene_ok(scene(R"({"objects": [
        {"mesh": "bunny.ply"}, {"mesh": "./bunny.ply", "static": true}, {"mesh": "bunny.ply"}]})")));
    EXPECT_EQ(&runtime.mesh(0), &runtime.mesh(1));
    EXPECT_EQ(&runtime.mesh(0), &runtime.mesh(2));
}

TEST_F(SceneRuntimeTest, posesAnimatedObjectsAtOffsetPlusSpeedTimesSceneTime) {
    const fs::path fox = copy(kAssets / "characters/Fox.glb", "Fox.glb");
    gust::SceneRuntime runtime = runtime_ok(scene_ok(scene(R"({"objects": [
        {"mesh": "Fox.glb", "animation": {"clip": "Run", "speed": 2.0, "offset": 0.1, "loop": false}},
        {"mesh": "Fox.glb", "transform": {"scale": 0.01}}]})")));
    const gust::Result<gust::AnimatedMesh> animated = gust::AnimatedMesh::load(fox);
    ASSERT_TRUE(animated.ok()) << animated.message();
    const std::size_t run = *animated->find_clip("Run");

    EXPECT_TRUE(runtime.deforms(0));
    EXPECT_FALSE(runtime.deforms(1));
    EXPECT_EQ(runtime.mesh(0).positions, animated->rest_pose().positions);
    EXPECT_EQ(&runtime.mesh(0), &runtime.mesh(1)) << "the unanimated fox shares the animated one's rest pose";
    for (double t : {0.0, 0.13, 0.3, 50.0}) {
        std::vector<glm::vec3> expected;
        animated->pose(run, 0.1 + 2.0 * t, false, expected);
        EXPECT_EQ(runtime.positions(0, t), expected) << t;
        EXPECT_EQ(runtime.positions(1, t), runtime.mesh(1).positions) << t;
    }
    const std::vector<glm::vec3> start = runtime.positions(0, 0.0);
    EXPECT_NE(runtime.positions(0, 0.13), start);
    EXPECT_EQ(runtime.positions(0, 0.0).size(), runtime.mesh(0).positions.size());
}

// A looping clip's wrap from its end to its start is a jump (a teleport for the wind); a clip that holds
// its last key, and the frames between wraps, are motion.
TEST_F(SceneRuntimeTest, aLoopingClipJumpsWhereItWrapsAndNowhereElse) {
    const fs::path fox = copy(kAssets / "characters/Fox.glb", "Fox.glb");
    gust::SceneRuntime runtime = runtime_ok(scene_ok(scene(R"({"objects": [
        {"mesh": "Fox.glb", "animation": {"clip": "Walk", "speed": 1.4}},
        {"mesh": "Fox.glb", "animation": {"clip": "Walk", "loop": false}},
        {"mesh": "Fox.glb"}]})")));
    const gust::Result<gust::AnimatedMesh> animated = gust::AnimatedMesh::load(fox);
    ASSERT_TRUE(animated.ok()) << animated.message();
    const double duration = animated->clip_duration(*animated->find_clip("Walk"));
    const double dt = 1.0 / 30.0;
    int wraps = 0;
    for (int frame = 1; frame <= 300; ++frame) {
        const double t0 = (frame - 1) * dt, t1 = frame * dt;
        const bool wrapped = std::floor(1.4 * t1 / duration) != std::floor(1.4 * t0 / duration);
        EXPECT_EQ(runtime.jumps(0, t0, t1), wrapped) << frame;
        wraps += wrapped ? 1 : 0;
        EXPECT_FALSE(runtime.jumps(1, t0, t1)) << frame;
        EXPECT_FALSE(runtime.jumps(2, t0, t1)) << frame;
    }
    EXPECT_GT(wraps, 10) << "a 0.7 s clip at 1.4x wraps about twice a second";
}

// ---------------------------------------------------------------------------------------------------
// Errors

TEST_F(SceneRuntimeTest, reportsAMissingClipWithTheFilesClips) {
    const fs::path fox = copy(kAssets / "characters/Fox.glb", "Fox.glb");
    const fs::path file = scene(R"({"objects": [{"mesh": "Fox.glb", "animation": {"clip": "Walk"}},
                                                {"mesh": "Fox.glb", "animation": {"clip": "Trot"}}]})");
    const gust::Result<gust::SceneRuntime> runtime = gust::SceneRuntime::load(scene_ok(file));
    ASSERT_FALSE(runtime.ok());
    EXPECT_EQ(runtime.message(), file.string() + ": objects[1].animation.clip: no clip 'Trot' in " +
                                     fox.string() + " (clips: Survey, Walk, Run)");
}

TEST_F(SceneRuntimeTest, reportsAMeshThatFailsToLoadWithObjectAndFile) {
    copy(kAssets / "scans/bunny.ply", "bunny.ply");
    const fs::path broken = dir_.write("broken.obj", "");
    const fs::path file = scene(R"({"objects": [{"mesh": "bunny.ply"}, {"mesh": "broken.obj"}]})");
    const gust::Result<gust::SceneRuntime> runtime = gust::SceneRuntime::load(scene_ok(file));
    ASSERT_FALSE(runtime.ok());
    EXPECT_EQ(runtime.message(), file.string() + ": objects[1].mesh: " + broken.string() + ": empty file");
}

TEST_F(SceneRuntimeTest, reportsAnAnimatedMeshThatFailsToLoad) {
    const std::string fox = read_file(kAssets / "characters/Fox.glb");
    const fs::path truncated = dir_.write("Fox.glb", fox.substr(0, fox.size() / 2));
    const fs::path file = scene(R"({"objects": [{"mesh": "Fox.glb", "animation": {"clip": "Walk"}}]})");
    const gust::Result<gust::SceneRuntime> runtime = gust::SceneRuntime::load(scene_ok(file));
    ASSERT_FALSE(runtime.ok());
    EXPECT_EQ(runtime.message().rfind(
                  file.string() + ": objects[0].mesh: " + truncated.string() + ": file truncated", 0),
              0u)
        << runtime.message();
}

// ---------------------------------------------------------------------------------------------------
// Example scenes

class ExampleScene : public testing::TestWithParam<const char*> {};

TEST_P(ExampleScene, loadsAndKeepsEveryObjectInsideTheDomain) {
    const gust::SceneDesc desc = scene_ok(kAssets / "scenes" / GetParam());
    gust::SceneRuntime runtime = runtime_ok(desc);
    ASSERT_EQ(runtime.object_count(), desc.objects.size());
    const Box domain = domain_box(desc.domain);
    const double end = last_key_time(desc) + 1.0;
    for (std::size_t i = 0; i < runtime.object_count(); ++i) {
        const bool moves = !desc.objects[i].keyframes.empty() || runtime.deforms(i);
        for (double t = 0.0; t <= end; t += moves ? 0.1 : end) {
            const Box box = world_box(runtime, i, t);
            EXPECT_TRUE(glm::all(glm::greaterThanEqual(box.min, domain.min)) &&
                        glm::all(glm::lessThanEqual(box.max, domain.max)))
                << "object " << i << " (" << desc.objects[i].mesh.filename() << ") at t = " << t << " spans ("
                << box.min.x << ", " << box.min.y << ", " << box.min.z << ") to (" << box.max.x << ", "
                << box.max.y << ", " << box.max.z << ")";
        }
    }
}

INSTANTIATE_TEST_SUITE_P(AssetsScenes, ExampleScene,
                         testing::Values("fox_bunnies.json", "dragon_wall_arch.json"),
                         [](const testing::TestParamInfo<const char*>& param) {
                             std::string name = param.param;
                             return name.substr(0, name.find('.'));
                         });

TEST(ExampleScenes, boxMeshesAreClosedAndWoundOutward) {
    for (const char* name : {"ground.obj", "wall.obj", "arch.obj"}) {
        gust::SceneDesc desc;
        desc.objects.push_back({kAssets / "scenes" / name, true, {}, {}, std::nullopt});
        gust::SceneRuntime runtime = runtime_ok(desc);
        EXPECT_GT(signed_volume(runtime.mesh(0)), 0.0) << name;
        EXPECT_EQ(runtime.mesh(0).triangle_count() % 12, 0u) << name;
    }
}

TEST(ExampleScenes, foxWalksAmongTheBunniesWithoutTouchingThem) {
    const gust::SceneDesc desc = scene_ok(kAssets / "scenes/fox_bunnies.json");
    gust::SceneRuntime runtime = runtime_ok(desc);
    const std::size_t fox = runtime.object_count() - 1;
    ASSERT_TRUE(runtime.deforms(fox));
    std::vector<Box> bunnies;
    for (std::size_t i = 0; i < fox; ++i) {
        if (desc.objects[i].mesh.filename() == "bunny.ply") bunnies.push_back(world_box(runtime, i, 0.0));
    }
    ASSERT_EQ(bunnies.size(), 9u);
    const Box start = world_box(runtime, fox, 0.0);
    const Box end = world_box(runtime, fox, 4.0);
    EXPECT_GT(end.min.z - start.min.z, 5.0f) << "walks about 6 m along +z";
    for (double t = 0.0; t <= 4.0; t += 0.05) {
        const Box box = world_box(runtime, fox, t);
        EXPECT_GT(box.min.y, -0.05f) << "stays on the ground at t = " << t;
        for (const Box& bunny : bunnies)
            EXPECT_FALSE(box.overlaps(bunny)) << "t = " << t;
    }
}

TEST(ExampleScenes, dragonFliesThroughTheArchOpeningAndPastTheWall) {
    const gust::SceneDesc desc = scene_ok(kAssets / "scenes/dragon_wall_arch.json");
    gust::SceneRuntime runtime = runtime_ok(desc);
    const std::size_t dragon = 3;
    ASSERT_EQ(desc.objects[dragon].mesh.filename(), "dragon_res3.ply");
    std::size_t inside_arch = 0;
    for (double t = 0.0; t <= 3.0; t += 0.05) {
        for (const glm::vec3& p : world(runtime, dragon, t)) {
            // The arch's pillars and lintel occupy |x| <= 0.2: there the dragon must be in the opening.
            if (std::abs(p.x) <= 0.2f) {
                ++inside_arch;
                ASSERT_LT(std::abs(p.z), 1.0f) << "t = " << t;
                ASSERT_LT(p.y, 2.6f) << "t = " << t;
            }
            ASSERT_GT(p.z, -2.2f) << "clear of the wall at t = " << t;
            ASSERT_GT(p.y, 0.0f) << "above the ground at t = " << t;
        }
    }
    EXPECT_GT(inside_arch, 1000u) << "the dragon does pass through the arch";
}

Box cascade_box(const gust::DomainDesc& domain, std::uint32_t cascade) {
    const float cell = domain.cell_size * std::pow(float(domain.ratio), float(cascade));
    const glm::vec3 half = glm::vec3(domain.cells) * cell * 0.5f;
    return {domain.center - half, domain.center + half};
}

bool inside(const Box& box, const Box& outer) {
    return glm::all(glm::greaterThanEqual(box.min, outer.min)) &&
           glm::all(glm::lessThanEqual(box.max, outer.max));
}

TEST(ExampleScenes, valleyIsA500kTriangleKilometreOfTerrainInsideTheCoarsestCascade) {
    const gust::SceneDesc desc = scene_ok(kAssets / "scenes/valley.json");
    gust::SceneRuntime runtime = runtime_ok(desc);
    ASSERT_TRUE(desc.objects.at(0).terrain.has_value());
    EXPECT_TRUE(desc.objects[0].is_static);
    EXPECT_EQ(desc.objects[0].terrain->size, glm::vec2(1000.0f, 1000.0f));
    EXPECT_EQ(runtime.mesh(0).triangle_count(), 500000u);
    EXPECT_EQ(runtime.mesh(0).positions.size(), 501u * 501u);
    EXPECT_EQ(desc.domain.cells, glm::uvec3(32, 16, 32));
    EXPECT_EQ(desc.domain.cascades, 4u);
    EXPECT_EQ(desc.domain.ratio, 4u);
    EXPECT_DOUBLE_EQ(desc.dt, 0.05);
    const Box coarsest = cascade_box(desc.domain, desc.domain.cascades - 1);
    for (std::size_t i = 0; i < runtime.object_count(); ++i)
        EXPECT_TRUE(inside(world_box(runtime, i, 0.0), coarsest)) << "object " << i;
}

TEST(ExampleScenes, valleyVillageAndWalkingFoxStandOnTheGroundInsideTheFinestCascade) {
    const gust::SceneDesc desc = scene_ok(kAssets / "scenes/valley.json");
    gust::SceneRuntime runtime = runtime_ok(desc);
    const gust::TerrainDesc& terrain = desc.objects.at(0).terrain.value();
    const Box finest = cascade_box(desc.domain, 0);
    std::size_t buildings = 0;
    std::size_t trees = 0;
    for (std::size_t i = 1; i < runtime.object_count(); ++i) {
        const bool moves = !desc.objects[i].keyframes.empty();
        const std::string name = desc.objects[i].mesh.filename().string();
        if (name.starts_with("building")) ++buildings;
        if (name == "tree_detailed.glb") ++trees;
        for (double t = 0.0; t <= (moves ? desc.objects[i].keyframes.back().t : 0.0); t += 0.5) {
            const Box box = world_box(runtime, i, t);
            const glm::vec3 centre = (box.min + box.max) * 0.5f;
            const double ground = gust::terrain_height(terrain, centre.x, centre.z);
            // Sunk a little into the ground under its footprint (so no air passes beneath), never floating.
            EXPECT_LE(box.min.y, ground + 0.05) << name << " (object " << i << ") at t = " << t;
            EXPECT_GE(box.min.y, ground - 3.0) << name << " (object " << i << ") at t = " << t;
            if (name != "tree_detailed.glb") {
                EXPECT_TRUE(inside(box, finest)) << name << " (object " << i << ") at t = " << t;
            }
        }
    }
    EXPECT_GE(buildings, 4u);
    EXPECT_GE(trees, 10u);
    EXPECT_TRUE(runtime.deforms(runtime.object_count() - 1)) << "the Fox walks";
}

TEST(ExampleScenes, valleyWindCrossesARidgeUpwindOfTheVillage) {
    const gust::SceneDesc desc = scene_ok(kAssets / "scenes/valley.json");
    const gust::TerrainDesc& terrain = desc.objects.at(0).terrain.value();
    ASSERT_GT(glm::length(desc.ambient_velocity), 0.0f);
    const glm::vec2 upwind = -glm::normalize(glm::vec2(desc.ambient_velocity.x, desc.ambient_velocity.z));
    const double village = gust::terrain_height(terrain, 0.0, 0.0);
    double crest = village;
    double crest_distance = 0.0;
    for (double d = 0.0; d <= 450.0; d += 1.0) {
        const double h = gust::terrain_height(terrain, upwind.x * d, upwind.y * d);
        if (h > crest) {
            crest = h;
            crest_distance = d;
        }
    }
    EXPECT_GE(crest_distance, 150.0);
    EXPECT_LE(crest_distance, 250.0);
    EXPECT_GE(crest - village, 30.0);
    EXPECT_NEAR(glm::length(desc.domain.center - glm::vec3(0.0f, float(village), 0.0f)), 6.0f, 0.5f)
        << "the domain is centred on the village, a few metres above its ground";
}

} // namespace
