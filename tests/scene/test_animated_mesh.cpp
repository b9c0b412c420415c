// glTF animation playback: the two skinned characters, the 2-joint simple_skin file with hand-computed
// poses, synthetic files for each interpolation mode and for exact identities, and broken skins/clips.
#include "gust/scene/animated_mesh.hpp"
#include "gust/scene/import.hpp"
#include "scene_test_support.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using gust::test::GltfWriter;
using gust::test::json;
using gust::test::kTriangle;

const fs::path kAssets = GUST_ASSETS_DIR;
const fs::path kModels = GUST_ASSIMP_MODELS_DIR;
const fs::path kFox = kAssets / "characters/Fox.glb";
const fs::path kCesiumMan = kAssets / "characters/CesiumMan.glb";
const fs::path kSimpleSkin = kModels / "glTF2/simple_skin/simple_skin.gltf";

constexpr int kFloat = 5126;
constexpr int kUnsignedShort = 5123;

gust::AnimatedMesh load_ok(const fs::path& path) {
    gust::Result<gust::AnimatedMesh> mesh = gust::AnimatedMesh::load(path);
    if (!mesh.ok()) throw std::runtime_error(mesh.message());
    return *mesh;
}

void expect_failure(const fs::path& path, const std::string& reason) {
    gust::Result<gust::AnimatedMesh> mesh = gust::AnimatedMesh::load(path);
    ASSERT_FALSE(mesh.ok()) << path << " loaded";
    EXPECT_EQ(mesh.message().rfind(path.string() + ": ", 0), 0u)
        << "starts with the path: " << mesh.message();
    EXPECT_NE(mesh.message().find(reason), std::string::npos)
        << "says '" << reason << "': " << mesh.message();
}

struct Box {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{std::numeric_limits<float>::lowest()};
    glm::vec3 extent() const { return max - min; }
};

Box bounds(const std::vector<glm::vec3>& points) {
    Box box;
    for (const glm::vec3& p : points) {
        box.min = glm::min(box.min, p);
        box.max = glm::max(box.max, p);
    }
    return box;
}

float max_distance(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    float d = 0.0f;
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
        d = std::max(d, glm::length(a[i] - b[i]));
    return d;
}

std::vector<glm::vec3> pose(const gust::AnimatedMesh& mesh, std::size_t clip, double t, bool loop = true) {
    std::vector<glm::vec3> out;
    mesh.pose(clip, t, loop, out);
    return out;
}

void expect_near(glm::vec3 actual, glm::vec3 expected, float tolerance) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

// A posed character keeps roughly its size: every bounding-box extent within a factor of 2 of the bind
// pose's (a wrong joint order or matrix convention scatters or collapses the mesh), and the box centre
// within one bind-pose diagonal.
void expect_plausible_pose(const std::vector<glm::vec3>& posed, const std::vector<glm::vec3>& bind) {
    const Box a = bounds(posed);
    const Box b = bounds(bind);
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_LT(a.extent()[axis], 2.0f * b.extent()[axis]) << "axis " << axis;
        EXPECT_GT(a.extent()[axis], 0.5f * b.extent()[axis]) << "axis " << axis;
    }
    EXPECT_LT(glm::length((a.min + a.max) - (b.min + b.max)) / 2.0f, glm::length(b.extent()));
}

// ---------------------------------------------------------------------------------------------------
// Characters

TEST(AnimatedMesh, restPoseOfFoxEqualsLoadMesh) {
    const gust::AnimatedMesh fox = load_ok(kFox);
    const gust::Result<gust::Mesh> mesh = gust::load_mesh(kFox);
    ASSERT_TRUE(mesh.ok()) << mesh.message();
    EXPECT_EQ(fox.rest_pose().name, "Fox.glb");
    EXPECT_EQ(fox.rest_pose().positions, mesh->positions);
    EXPECT_EQ(fox.rest_pose().indices, mesh->indices);
}

TEST(AnimatedMesh, foxHasItsThreeNamedClips) {
    const gust::AnimatedMesh fox = load_ok(kFox);
    EXPECT_TRUE(fox.skinned());
    EXPECT_EQ(fox.clip_names(), (std::vector<std::string>{"Survey", "Walk", "Run"}));
    ASSERT_EQ(fox.find_clip("Walk"), std::optional<std::size_t>(1));
    EXPECT_FALSE(fox.find_clip("walk").has_value());
    for (std::size_t clip = 0; clip < 3; ++clip) {
        EXPECT_GT(fox.clip_duration(clip), 0.1) << clip;
        EXPECT_LT(fox.clip_duration(clip), 10.0) << clip;
    }
    EXPECT_EQ(fox.clip_duration(3), 0.0);
}

TEST(AnimatedMesh, foxPoseAtEveryClipStartIsPlausible) {
    const gust::AnimatedMesh fox = load_ok(kFox);
    for (std::size_t clip = 0; clip < 3; ++clip) {
        SCOPED_TRACE(fox.clip_names()[clip]);
        const std::vector<glm::vec3> posed = pose(fox, clip, 0.0);
        ASSERT_EQ(posed.size(), fox.rest_pose().positions.size());
        expect_plausible_pose(posed, fox.rest_pose().positions);
    }
}

TEST(AnimatedMesh, foxRestPoseReproducesTheBindPose) {
    // Fox's inverse bind matrices invert its joints' rest placement, so the rest pose (no clip) is
    // the bind pose up to float rounding of the matrices (the fox is about 150 units long).
    const gust::AnimatedMesh fox = load_ok(kFox);
    EXPECT_LT(max_distance(pose(fox, 99, 0.0), fox.rest_pose().positions), 1e-3f);
}

TEST(AnimatedMesh, foxWalkMovesItsVerticesOverTime) {
    const gust::AnimatedMesh fox = load_ok(kFox);
    const std::size_t walk = *fox.find_clip("Walk");
    const double quarter = fox.clip_duration(walk) / 4;
    const std::vector<glm::vec3> a = pose(fox, walk, 0.0);
    const std::vector<glm::vec3> b = pose(fox, walk, quarter);
    // Legs swing by a sizeable fraction of the fox's 150-unit length.
    EXPECT_GT(max_distance(a, b), 5.0f);
    expect_plausible_pose(b, fox.rest_pose().positions);
}

TEST(AnimatedMesh, loopingWrapsAtTheClipDuration) {
    const gust::AnimatedMesh fox = load_ok(kFox);
    for (std::size_t clip = 0; clip < 3; ++clip) {
        const double d = fox.clip_duration(clip);
        for (double t : {0.0, 0.37, d * 0.9}) {
            EXPECT_LT(max_distance(pose(fox, clip, t), pose(fox, clip, t + d)), 1e-4f) << clip << " " << t;
            EXPECT_LT(max_distance(pose(fox, clip, t), pose(fox, clip, t - 3 * d)), 1e-4f)
                << clip << " " << t;
        }
    }
}

TEST(AnimatedMesh, withoutLoopHoldsTheEndKeys) {
    const gust::AnimatedMesh fox = load_ok(kFox);
    const std::size_t run = *fox.find_clip("Run");
    const double d = fox.clip_duration(run);
    EXPECT_EQ(pose(fox, run, d + 2.5, false), pose(fox, run, d, false));
    EXPECT_EQ(pose(fox, run, -1.0, false), pose(fox, run, 0.0, false));
}

TEST(AnimatedMesh, nonFiniteTimeIsTakenAsZero) {
    const gust::AnimatedMesh fox = load_ok(kFox);
    EXPECT_EQ(pose(fox, 1, std::numeric_limits<double>::quiet_NaN()), pose(fox, 1, 0.0));
    EXPECT_EQ(pose(fox, 1, std::numeric_limits<double>::infinity()), pose(fox, 1, 0.0));
}

TEST(AnimatedMesh, cesiumManHasOneUnnamedClipAndPlausiblePoses) {
    const gust::AnimatedMesh man = load_ok(kCesiumMan);
    EXPECT_TRUE(man.skinned());
    EXPECT_EQ(man.clip_names(), (std::vector<std::string>{"clip0"}));
    const double d = man.clip_duration(0);
    EXPECT_GT(d, 0.5);
    const std::vector<glm::vec3>& rest = man.rest_pose().positions;
    const std::vector<glm::vec3> start = pose(man, 0, 0.0);
    const std::vector<glm::vec3> later = pose(man, 0, d / 3);
    // At rest the arms are spread (a T pose, 1.14 m across); walking they hang (about 0.5 m), so the
    // walking poses are compared with each other, and with the rest pose in height only.
    expect_plausible_pose(later, start);
    EXPECT_NEAR(bounds(start).extent().y, bounds(rest).extent().y, 0.15f);
    // A stride moves feet and arms by a good fraction of the 1.5 m figure.
    EXPECT_GT(max_distance(start, later), 0.1f);
    EXPECT_LT(max_distance(pose(man, 0, 0.4), pose(man, 0, 0.4 + d)), 1e-4f);
    EXPECT_LT(max_distance(pose(man, 0, 0.4), pose(man, 0, 0.4 + 5 * d)), 1e-4f);
}

TEST(AnimatedMesh, cesiumManStandsYUpAtRestAndPosedThoughItsRawDataIsZUp) {
    // The Z_UP node above the skeleton is part of the joints' global transforms and the inverse bind
    // matrices do not undo it, so (as in every glTF viewer) the figure stands along +y at rest (clip 1
    // does not exist) and walking, though its raw POSITION data is Z-up.
    const gust::AnimatedMesh man = load_ok(kCesiumMan);
    const gust::Result<gust::Mesh> mesh = gust::load_mesh(kCesiumMan);
    ASSERT_TRUE(mesh.ok()) << mesh.message();
    EXPECT_EQ(man.rest_pose().positions, mesh->positions);
    EXPECT_EQ(pose(man, 1, 0.0), man.rest_pose().positions);
    for (const std::vector<glm::vec3>& posed : {pose(man, 0, 0.0), man.rest_pose().positions}) {
        const Box box = bounds(posed);
        EXPECT_GT(box.extent().y, 1.4f);
        EXPECT_LT(box.extent().z, 1.2f);
        EXPECT_GT(box.min.y, -0.1f) << "feet at the origin";
    }
}

// ---------------------------------------------------------------------------------------------------
// simple_skin.gltf: joints 1 (translation (0,1,0)) and 2 (its child, rotation animated about z), both
// with inverse bind matrix translate(-0.5,-1,0); vertices (x, y) for x in {0,1}, y in {0,0.5,..,2}
// weighted (1 - y/2) to joint 1 and y/2 to joint 2.

// The file's POSITION data: vertex i is (i % 2, 0.5 · (i / 2), 0).
std::vector<glm::vec3> simple_skin_raw() {
    std::vector<glm::vec3> raw;
    for (int i = 0; i < 10; ++i)
        raw.emplace_back(float(i % 2), 0.5f * float(i / 2), 0.0f);
    return raw;
}

glm::vec3 simple_skin_vertex(glm::vec3 p, double degrees) {
    const double a = glm::radians(degrees);
    const double w2 = p.y / 2.0;
    // Joint 1: T(0,1,0)·T(-0.5,-1,0) = T(-0.5,0,0). Joint 2: T(0,1,0)·Rz(a)·T(-0.5,-1,0).
    const glm::dvec2 first(p.x - 0.5, p.y);
    const glm::dvec2 local(p.x - 0.5, p.y - 1.0);
    const glm::dvec2 second(local.x * std::cos(a) - local.y * std::sin(a),
                            local.x * std::sin(a) + local.y * std::cos(a) + 1.0);
    const glm::dvec2 blended = (1.0 - w2) * first + w2 * second;
    return {static_cast<float>(blended.x), static_cast<float>(blended.y), 0.0f};
}

TEST(AnimatedMesh, simpleSkinMatchesHandComputedPosesAtKeysAndBetween) {
    const gust::AnimatedMesh skin = load_ok(kSimpleSkin);
    ASSERT_EQ(skin.clip_names().size(), 1u);
    EXPECT_DOUBLE_EQ(skin.clip_duration(0), 5.5);
    const std::vector<glm::vec3> raw = simple_skin_raw();
    ASSERT_EQ(skin.rest_pose().positions.size(), raw.size());
    // Vertex 6 is (0, 1.5, 0), weights 0.25 / 0.75. At t = 1 joint 2 is turned 90 degrees:
    // 0.25·(-0.5, 1.5) + 0.75·(-0.5, 0.5) = (-0.5, 0.75).
    const std::vector<glm::vec3> at_key = pose(skin, 0, 1.0);
    expect_near(at_key[6], {-0.5f, 0.75f, 0.0f}, 1e-5f);
    // Keys at 0.5 and 1.0: the file rounds 45 degrees to the quaternion (0, 0, 0.383, 0.924), whose
    // angle is 2·atan2(0.383, 0.924) = 45.03 degrees; 90 degrees is (0, 0, 0.707, 0.707). Halfway, slerp
    // gives the mean angle.
    const double first = glm::degrees(2.0 * std::atan2(0.383, 0.924));
    const std::vector<glm::vec3> between = pose(skin, 0, 0.75);
    for (std::size_t v = 0; v < raw.size(); ++v) {
        SCOPED_TRACE(v);
        expect_near(at_key[v], simple_skin_vertex(raw[v], 90.0), 1e-5f);
        expect_near(between[v], simple_skin_vertex(raw[v], (first + 90.0) / 2.0), 1e-5f);
    }
}

TEST(AnimatedMesh, simpleSkinRestPoseIsTheSkinWithItsJointsAtRest) {
    // Both joints sit at (0, 1, 0) at rest while their inverse bind matrices take off (0.5, 1, 0), so
    // the figure a viewer shows (and load_mesh returns) is the raw data moved by -0.5 along x: x in
    // [-0.5, 0.5], as the glTF tutorial's picture of this file shows it.
    const gust::AnimatedMesh skin = load_ok(kSimpleSkin);
    const gust::Result<gust::Mesh> mesh = gust::load_mesh(kSimpleSkin);
    ASSERT_TRUE(mesh.ok());
    EXPECT_EQ(skin.rest_pose().positions, mesh->positions);
    const std::vector<glm::vec3> raw = simple_skin_raw();
    ASSERT_EQ(mesh->positions.size(), raw.size());
    for (std::size_t v = 0; v < raw.size(); ++v)
        expect_near(mesh->positions[v], raw[v] - glm::vec3(0.5f, 0.0f, 0.0f), 1e-6f);
}

// ---------------------------------------------------------------------------------------------------
// Synthetic files

class AnimatedMeshFile : public testing::Test {
  protected:
    fs::path write(const std::string& name, GltfWriter& gltf) { return dir_.write(name, gltf.text()); }
    gust::test::TempDir dir_;
};

// A triangle skinned to two joint nodes with weights 0.25 / 0.75 on every vertex.
struct SkinnedTriangle {
    GltfWriter gltf;
    std::vector<glm::vec3> positions = {{0.3f, -1.7f, 2.9f}, {1.1f, 0.2f, -0.4f}, {-5.5f, 3.25f, 0.1f}};
    int joint_a = -1;
    int joint_b = -1;

    explicit SkinnedTriangle(std::vector<std::uint16_t> joints = {0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0},
                             std::vector<float> weights = {0.25f, 0.75f, 0, 0, 0.25f, 0.75f, 0, 0, 0.25f,
                                                           0.75f, 0, 0}) {
        const int position_accessor = gltf.add_positions(positions);
        const int joints_accessor = gltf.add_data(joints, kUnsignedShort, "VEC4");
        const int weights_accessor = gltf.add_data(weights, kFloat, "VEC4");
        const int mesh = gltf.add_mesh(json::array({{{"attributes",
                                                      {{"POSITION", position_accessor},
                                                       {"JOINTS_0", joints_accessor},
                                                       {"WEIGHTS_0", weights_accessor}}}}}));
        joint_a = gltf.add_node(json::object());
        joint_b = gltf.add_node(json::object());
        gltf.doc()["nodes"][static_cast<std::size_t>(joint_a)]["children"] = {joint_b};
        gltf.doc()["skins"] = json::array({{{"joints", {joint_a, joint_b}}}});
        // The mesh node's own transform must be ignored for a skinned mesh.
        gltf.add_root(gltf.add_node({{"mesh", mesh}, {"skin", 0}, {"translation", {4, 5, 6}}}));
        gltf.add_root(joint_a);
    }

    /// A clip on `node`'s `path` with the given key times, values (flattened) and interpolation.
    void add_clip(const std::string& name, int node, const std::string& path, const std::vector<float>& times,
                  const std::vector<float>& values, const std::string& interpolation = "LINEAR") {
        const int input = gltf.add_data(times, kFloat, "SCALAR");
        const int output = gltf.add_data(values, kFloat, path == "rotation" ? "VEC4" : "VEC3");
        if (!gltf.doc().contains("animations")) gltf.doc()["animations"] = json::array();
        gltf.doc()["animations"].push_back(
            {{"name", name},
             {"samplers", {{{"input", input}, {"output", output}, {"interpolation", interpolation}}}},
             {"channels", {{{"sampler", 0}, {"target", {{"node", node}, {"path", path}}}}}}});
    }
};

TEST_F(AnimatedMeshFile, skinningWithIdentityJointsReproducesTheBindPoseExactly) {
    SkinnedTriangle file;
    // Identity keys in every channel type, so the channel path runs and still yields identity joints.
    file.add_clip("still", file.joint_b, "rotation", {0, 1}, {0, 0, 0, 1, 0, 0, 0, 1});
    file.add_clip("still_t", file.joint_a, "translation", {0, 1}, {0, 0, 0, 0, 0, 0});
    const gust::AnimatedMesh mesh = load_ok(write("identity.gltf", file.gltf));
    EXPECT_TRUE(mesh.skinned());
    EXPECT_EQ(mesh.rest_pose().positions, file.positions);
    for (std::size_t clip : {0u, 1u, 2u}) { // clip 2 does not exist: the rest pose
        for (double t : {0.0, 0.5, 3.0}) {
            EXPECT_EQ(pose(mesh, clip, t), mesh.rest_pose().positions) << clip << " " << t;
        }
    }
}

TEST_F(AnimatedMeshFile, skinningWithExplicitIdentityInverseBindMatricesReproducesTheBindPoseExactly) {
    SkinnedTriangle file;
    const std::vector<float> identities = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1,
                                           1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    file.gltf.doc()["skins"][0]["inverseBindMatrices"] = file.gltf.add_data(identities, kFloat, "MAT4");
    const gust::AnimatedMesh mesh = load_ok(write("ibm.gltf", file.gltf));
    EXPECT_EQ(pose(mesh, 0, 0.0), mesh.rest_pose().positions);
}

TEST_F(AnimatedMeshFile, translatedJointMovesItsShareOfEachVertex) {
    SkinnedTriangle file;
    file.add_clip("slide", file.joint_b, "translation", {0, 2}, {0, 0, 0, 8, 0, 0});
    const gust::AnimatedMesh mesh = load_ok(write("slide.gltf", file.gltf));
    const std::vector<glm::vec3> posed = pose(mesh, 0, 1.0);
    // Halfway: joint b is at (4,0,0) and carries 0.75 of each vertex.
    for (std::size_t v = 0; v < 3; ++v)
        expect_near(posed[v], mesh.rest_pose().positions[v] + glm::vec3(3, 0, 0), 1e-5f);
}

TEST_F(AnimatedMeshFile, normalisesWeightsThatDoNotSumToOne) {
    SkinnedTriangle file({0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0},
                         {0.1f, 0.3f, 0, 0, 0.1f, 0.3f, 0, 0, 0.1f, 0.3f, 0, 0});
    file.add_clip("slide", file.joint_b, "translation", {0, 1}, {0, 0, 0, 4, 0, 0});
    const gust::AnimatedMesh mesh = load_ok(write("weights.gltf", file.gltf));
    const std::vector<glm::vec3> posed = pose(mesh, 0, 1.0, false);
    expect_near(posed[0], mesh.rest_pose().positions[0] + glm::vec3(3, 0, 0), 1e-5f);
}

TEST_F(AnimatedMeshFile, stepHoldsEachKeyUntilTheNext) {
    SkinnedTriangle file;
    file.add_clip("step", file.joint_a, "translation", {0, 1, 2}, {0, 0, 0, 0, 2, 0, 0, 6, 0}, "STEP");
    const gust::AnimatedMesh mesh = load_ok(write("step.gltf", file.gltf));
    const glm::vec3 p = mesh.rest_pose().positions[1];
    expect_near(pose(mesh, 0, 0.99)[1], p, 1e-6f);
    expect_near(pose(mesh, 0, 1.0)[1], p + glm::vec3(0, 2, 0), 1e-6f);
    expect_near(pose(mesh, 0, 1.5)[1], p + glm::vec3(0, 2, 0), 1e-6f);
}

TEST_F(AnimatedMeshFile, cubicSplineFollowsTheHermiteCurveWithScaledTangents) {
    SkinnedTriangle file;
    // Keys at 0 and 2 with value 0; out-tangent (1,0,0) at the first key. Per glTF, tangents are
    // scaled by the key interval (2): x(s) = (s^3 - 2 s^2 + s) · 2 · 1, so x = 0.25 at s = 0.5.
    file.add_clip("cubic", file.joint_a, "translation", {0, 2},
                  {0, 0, 0, /**/ 0, 0, 0, /**/ 1, 0, 0, /**/ 0, 0, 0, /**/ 0, 0, 0, /**/ 0, 0, 0},
                  "CUBICSPLINE");
    const gust::AnimatedMesh mesh = load_ok(write("cubic.gltf", file.gltf));
    expect_near(pose(mesh, 0, 1.0)[2], mesh.rest_pose().positions[2] + glm::vec3(0.25f, 0, 0), 1e-6f);
    expect_near(pose(mesh, 0, 2.0, false)[2], mesh.rest_pose().positions[2], 1e-6f);
}

TEST_F(AnimatedMeshFile, animatesRigidNodesAndKeepsTheirRestPoseExact) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(gust::test::triangle_primitive(gltf.add_positions(kTriangle)));
    const double s = std::sqrt(0.5);
    const int child = gltf.add_node({{"mesh", mesh}, {"translation", {0.1, 0.2, 0.3}}});
    const int parent = gltf.add_node({{"children", {child}},
                                      {"translation", {10, 0, 0}},
                                      {"rotation", {0, 0, s, s}},
                                      {"scale", {2, 2, 2}}});
    gltf.add_root(parent);
    const int input = gltf.add_data(std::vector<float>{0, 1}, kFloat, "SCALAR");
    const int output = gltf.add_data(std::vector<float>{0, 0, 0, 0, 0, 4}, kFloat, "VEC3");
    gltf.doc()["animations"] = {
        {{"samplers", {{{"input", input}, {"output", output}}}},
         {"channels", {{{"sampler", 0}, {"target", {{"node", child}, {"path", "translation"}}}}}}}};
    const gust::AnimatedMesh animated = load_ok(write("rigid.gltf", gltf));
    EXPECT_FALSE(animated.skinned());
    EXPECT_EQ(pose(animated, 1, 0.0), animated.rest_pose().positions) << "rest pose, bit for bit";
    // At t = 0.5 the child is at (0,0,2) locally: the parent scales by 2 and turns x to y, z stays.
    const std::vector<glm::vec3> posed = pose(animated, 0, 0.5);
    expect_near(posed[0], {10, 0, 4}, 1e-5f);
    expect_near(posed[1], {10, 2, 4}, 1e-5f);
}

/// bone_skin's bind positions moved by `palette` as a GPU skinner does (linear blend of four influences).
std::vector<glm::vec3> skin_on_bones(const gust::AnimatedMesh::BoneSkin& skin,
                                     const std::vector<glm::mat4>& palette) {
    std::vector<glm::vec3> out;
    for (std::size_t v = 0; v < skin.bind.size(); ++v) {
        glm::vec4 p(0.0f);
        for (std::size_t i = 4 * v; i < 4 * v + 4; ++i)
            p += skin.weights[i] * (palette[skin.joints[i]] * glm::vec4(skin.bind[v], 1.0f));
        out.emplace_back(p);
    }
    return out;
}

// The bone palette poses the characters as pose() does, up to float rounding, through a walk cycle; every
// vertex has four influences in range whose weights sum to 1.
TEST(AnimatedMesh, bonePalettesPoseTheCharactersAsPoseDoes) {
    for (const fs::path& path : {kFox, kCesiumMan}) {
        SCOPED_TRACE(path.string());
        const gust::AnimatedMesh mesh = load_ok(path);
        const gust::Result<gust::AnimatedMesh::BoneSkin> skin = mesh.bone_skin();
        ASSERT_TRUE(skin.ok()) << skin.message();
        ASSERT_EQ(skin->bind.size(), mesh.rest_pose().positions.size());
        ASSERT_EQ(skin->joints.size(), 4 * skin->bind.size());
        ASSERT_EQ(skin->weights.size(), 4 * skin->bind.size());
        for (std::size_t v = 0; v < skin->bind.size(); ++v) {
            float sum = 0.0f;
            for (std::size_t i = 4 * v; i < 4 * v + 4; ++i) {
                ASSERT_LT(skin->joints[i], skin->joint_count);
                sum += skin->weights[i];
            }
            ASSERT_NEAR(sum, 1.0f, 1e-5f) << "vertex " << v;
        }
        const float size = glm::length(bounds(mesh.rest_pose().positions).extent());
        for (double t : {0.0, 0.37, 1.1, 2.5}) {
            std::vector<glm::mat4> palette;
            mesh.bone_palette(0, t, true, palette);
            ASSERT_EQ(palette.size(), skin->joint_count);
            EXPECT_LT(max_distance(skin_on_bones(*skin, palette), pose(mesh, 0, t)), 1e-5f * size) << t;
        }
    }
}

// A rigidly animated node and a fixed one get palette entries of their own: the file's every vertex follows.
TEST_F(AnimatedMeshFile, bonePalettesPlaceRigidNodesToo) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(gust::test::triangle_primitive(gltf.add_positions(kTriangle)));
    const int node = gltf.add_node({{"mesh", mesh}, {"translation", {0.1, 0.2, 0.3}}});
    gltf.add_root(node);
    const int input = gltf.add_data(std::vector<float>{0, 1}, kFloat, "SCALAR");
    const int output = gltf.add_data(std::vector<float>{0, 0, 0, 0, 0, 4}, kFloat, "VEC3");
    gltf.doc()["animations"] = {
        {{"samplers", {{{"input", input}, {"output", output}}}},
         {"channels", {{{"sampler", 0}, {"target", {{"node", node}, {"path", "translation"}}}}}}}};
    const gust::AnimatedMesh animated = load_ok(write("rigid_bones.gltf", gltf));
    const gust::Result<gust::AnimatedMesh::BoneSkin> skin = animated.bone_skin();
    ASSERT_TRUE(skin.ok()) << skin.message();
    EXPECT_EQ(skin->joint_count, 2u) << "the node's entry and the identity";
    std::vector<glm::mat4> palette;
    animated.bone_palette(0, 0.5, true, palette);
    EXPECT_LT(max_distance(skin_on_bones(*skin, palette), pose(animated, 0, 0.5)), 1e-6f);
}

TEST_F(AnimatedMeshFile, restPoseOfAStaticSceneIsItsBindPoseExactly) {
    const gust::AnimatedMesh palm = load_ok(kAssets / "foliage/PalmTree/PalmTree.gltf");
    EXPECT_FALSE(palm.skinned());
    EXPECT_EQ(pose(palm, 0, 0.0), palm.rest_pose().positions);
}

// ---------------------------------------------------------------------------------------------------
// Broken files

TEST_F(AnimatedMeshFile, rejectsJointIndexOutOfRange) {
    SkinnedTriangle file({0, 1, 0, 0, 0, 5, 0, 0, 0, 1, 0, 0});
    expect_failure(write("joint.gltf", file.gltf),
                   "JOINTS_0 of mesh 0 primitive 0: vertex 1 uses joint 5 but its "
                   "skin has 2 joints");
}

TEST_F(AnimatedMeshFile, ignoresJointIndexOutOfRangeWithZeroWeight) {
    SkinnedTriangle file({0, 1, 9, 0, 0, 1, 0, 0, 0, 1, 0, 0});
    EXPECT_TRUE(gust::AnimatedMesh::load(write("unused.gltf", file.gltf)).ok());
}

TEST_F(AnimatedMeshFile, rejectsNonFiniteWeight) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    SkinnedTriangle file({0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0},
                         {0.25f, 0.75f, 0, 0, 0.25f, 0.75f, 0, 0, nan, 1, 0, 0});
    expect_failure(write("nan.gltf", file.gltf), "WEIGHTS_0 of mesh 0 primitive 0: vertex 2 has weight nan");
}

TEST_F(AnimatedMeshFile, rejectsNegativeWeight) {
    SkinnedTriangle file({0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0},
                         {-0.25f, 1.25f, 0, 0, 0.25f, 0.75f, 0, 0, 0, 1, 0, 0});
    expect_failure(write("negative.gltf", file.gltf), "vertex 0 has weight -0.25");
}

TEST_F(AnimatedMeshFile, rejectsFloatJointIndices) {
    SkinnedTriangle file;
    file.gltf.doc()["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] =
        file.gltf.add_data(std::vector<float>(12, 0.0f), kFloat, "VEC4");
    expect_failure(write("floatjoints.gltf", file.gltf), "must be unsigned byte or short VEC4");
}

TEST_F(AnimatedMeshFile, rejectsSkinWithMissingJointNode) {
    SkinnedTriangle file;
    file.gltf.doc()["skins"][0]["joints"] = {0, 42};
    expect_failure(write("missingjoint.gltf", file.gltf), "skin 0 refers to missing joint node 42");
}

TEST_F(AnimatedMeshFile, rejectsTooFewInverseBindMatrices) {
    SkinnedTriangle file;
    const std::vector<float> one = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    file.gltf.doc()["skins"][0]["inverseBindMatrices"] = file.gltf.add_data(one, kFloat, "MAT4");
    expect_failure(write("fewibm.gltf", file.gltf), "skin 0 has 1 inverse bind matrices for 2 joints");
}

TEST_F(AnimatedMeshFile, rejectsDecreasingKeyTimes) {
    SkinnedTriangle file;
    file.add_clip("back", file.joint_a, "translation", {0, 2, 1}, {0, 0, 0, 1, 0, 0, 2, 0, 0});
    expect_failure(write("decreasing.gltf", file.gltf),
                   "animation 'back' channel 0 sampler 0 key times decrease at key 2");
}

TEST_F(AnimatedMeshFile, rejectsOutputCountMismatch) {
    SkinnedTriangle file;
    file.add_clip("short", file.joint_a, "translation", {0, 1}, {0, 0, 0, 1, 0, 0}, "CUBICSPLINE");
    expect_failure(write("cubiccount.gltf", file.gltf),
                   "has 2 output values for 2 keys (CUBICSPLINE needs 3 per key)");
}

TEST_F(AnimatedMeshFile, rejectsUnknownInterpolation) {
    SkinnedTriangle file;
    file.add_clip("odd", file.joint_a, "translation", {0, 1}, {0, 0, 0, 1, 0, 0}, "SMOOTH");
    expect_failure(write("smooth.gltf", file.gltf), "unknown interpolation 'SMOOTH'");
}

TEST_F(AnimatedMeshFile, rejectsAChannelWithoutATargetOrPathAndASkinWithoutJoints) {
    // glTF requires them; tinygltf dropped such a channel (the clip froze without a word) and failed on
    // such a skin without saying why.
    SkinnedTriangle file;
    file.add_clip("nopath", file.joint_a, "translation", {0, 1}, {0, 0, 0, 1, 0, 0});
    file.gltf.doc()["animations"][0]["channels"][0]["target"].erase("path");
    expect_failure(write("nopath.gltf", file.gltf), "/animations/0/channels/0/target/path is required");
    SkinnedTriangle no_target;
    no_target.add_clip("notarget", no_target.joint_a, "translation", {0, 1}, {0, 0, 0, 1, 0, 0});
    no_target.gltf.doc()["animations"][0]["channels"][0].erase("target");
    expect_failure(write("notarget.gltf", no_target.gltf), "/animations/0/channels/0/target is required");
    SkinnedTriangle no_joints;
    no_joints.gltf.doc()["skins"][0].erase("joints");
    expect_failure(write("nojoints.gltf", no_joints.gltf), "/skins/0/joints is required");
}

TEST_F(AnimatedMeshFile, rejectsAnUnknownTargetPathAndSkipsMorphWeightsAndAnExtensionsPointer) {
    // An unknown path was skipped, so a typo left the clip frozen without a word.
    SkinnedTriangle typo;
    typo.add_clip("move", typo.joint_a, "colour", {0, 1}, {0, 0, 0, 1, 0, 0});
    expect_failure(write("colour.gltf", typo.gltf),
                   "animation 'move' channel 0 has unknown target path 'colour'");
    SkinnedTriangle pointer;
    pointer.add_clip("move", pointer.joint_a, "pointer", {0, 1}, {0, 0, 0, 1, 0, 0});
    expect_failure(write("pointer.gltf", pointer.gltf), "has unknown target path 'pointer'");
    pointer.gltf.doc()["extensionsUsed"] = {"KHR_animation_pointer"};
    EXPECT_EQ(load_ok(write("pointer_used.gltf", pointer.gltf)).clip_names(),
              std::vector<std::string>{"move"});
    SkinnedTriangle weights;
    weights.add_clip("blend", weights.joint_a, "weights", {0, 1}, {0, 0, 0, 1, 0, 0});
    EXPECT_EQ(load_ok(write("weights.gltf", weights.gltf)).clip_names(), std::vector<std::string>{"blend"});
}

TEST_F(AnimatedMeshFile, rejectsAnimatedMatrixNode) {
    SkinnedTriangle file;
    file.gltf.doc()["nodes"][static_cast<std::size_t>(file.joint_a)]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0,
                                                                                  0, 0, 1, 0, 0, 0, 0, 1};
    file.add_clip("m", file.joint_a, "translation", {0, 1}, {0, 0, 0, 1, 0, 0});
    expect_failure(write("matrix.gltf", file.gltf),
                   "which has a matrix (glTF allows animating TRS nodes only)");
}

TEST_F(AnimatedMeshFile, rejectsNonGltfMeshes) {
    expect_failure(kAssets / "scans/bunny.ply", "animation needs a glTF file (.gltf or .glb), not '.ply'");
}

TEST_F(AnimatedMeshFile, rejectsMissingFileLikeLoadMesh) {
    expect_failure(dir_.path() / "absent.glb", "file not found");
}

TEST_F(AnimatedMeshFile, rejectsBrokenGltfLikeLoadMesh) {
    expect_failure(kModels / "glTF2/RecursiveNodes/RecursiveNodes.gltf", "node cycle at node 0");
}

// ---------------------------------------------------------------------------------------------------
// Corrupted files: never a crash, and either a load that poses or a message naming the file.

TEST_F(AnimatedMeshFile, survivesRandomCorruptionOfFox) {
    std::ifstream in(kFox, std::ios::binary);
    const std::string fox{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    std::mt19937 random(7);
    std::uniform_int_distribution<std::size_t> offset(0, fox.size() - 1);
    std::uniform_int_distribution<int> byte(0, 255);
    std::size_t loaded = 0;
    for (int round = 0; round < 200; ++round) {
        std::string bytes = fox;
        for (int k = 0; k < 1 + round % 8; ++k)
            bytes[offset(random)] = static_cast<char>(byte(random));
        const fs::path file = dir_.write("Fox.glb", bytes);
        const gust::Result<gust::AnimatedMesh> mesh = gust::AnimatedMesh::load(file);
        if (!mesh.ok()) {
            EXPECT_EQ(mesh.message().rfind(file.string() + ": ", 0), 0u) << mesh.message();
            continue;
        }
        ++loaded;
        std::vector<glm::vec3> out;
        for (std::size_t clip = 0; clip <= mesh->clip_names().size(); ++clip)
            mesh->pose(clip, 0.3, true, out);
        EXPECT_EQ(out.size(), mesh->rest_pose().positions.size());
    }
    EXPECT_GT(loaded, 0u) << "most flips land in vertex data and still load";
}

} // namespace
