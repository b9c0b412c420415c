// Scene files: docs/design.md's core example, the documented extensions and defaults, transform and
// keyframe math, and every kind of bad file failing with its file, key path and reason.
#include "gust/scene/domain_grid.hpp"
#include "gust/scene/scene_file.hpp"
#include "scene_test_support.hpp"

#include <cmath>
#include <filesystem>
#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <random>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using gust::test::kDesignExample;

void expect_vec3(glm::vec3 actual, glm::vec3 expected, float tolerance = 0.0f) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

void expect_matrix(const glm::mat4& actual, const glm::mat4& expected, float tolerance) {
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r)
            EXPECT_NEAR(actual[c][r], expected[c][r], tolerance) << "column " << c << " row " << r;
    }
}

glm::vec3 apply(const glm::mat4& m, glm::vec3 p) {
    return glm::vec3(m * glm::vec4(p, 1.0f));
}

// A folder with placeholder mesh files: load_scene checks only that they exist.
class SceneFile : public testing::Test {
  protected:
    SceneFile() {
        for (const char* name : {"wall.obj", "bunny.ply", "fox.glb", "man.GLTF"})
            dir_.write(name, "placeholder");
    }

    gust::SceneDesc load_ok(const std::string& text) {
        const gust::Result<gust::SceneDesc> scene = gust::load_scene(dir_.write("scene.json", text));
        if (!scene.ok()) throw std::runtime_error(scene.message());
        return *scene;
    }

    gust::test::TempDir dir_;
};

// ---------------------------------------------------------------------------------------------------
// The core format and its extensions

TEST_F(SceneFile, readsTheDesignExampleAsWritten) {
    const gust::SceneDesc scene = load_ok(kDesignExample);
    EXPECT_EQ(scene.file, dir_.path() / "scene.json");
    EXPECT_DOUBLE_EQ(scene.dt, 0.02);
    expect_vec3(scene.domain.center, {0, 8, 0});
    EXPECT_EQ(scene.domain.cells, glm::uvec3(32, 16, 32));
    EXPECT_EQ(scene.domain.cell_size, 1.0f);
    EXPECT_EQ(scene.domain.voxels_per_cell, 4u);
    EXPECT_EQ(scene.domain.branching, 4u);
    EXPECT_EQ(scene.domain.hysteresis, 8u) << "default";
    EXPECT_EQ(scene.domain.cascades, 1u) << "default";
    EXPECT_EQ(scene.domain.ratio, 4u) << "default";
    expect_vec3(scene.ambient_velocity, {4, 0, 0});

    ASSERT_EQ(scene.objects.size(), 2u);
    const gust::SceneObject& wall = scene.objects[0];
    EXPECT_EQ(wall.mesh, dir_.path() / "wall.obj");
    EXPECT_TRUE(wall.mesh.is_absolute());
    EXPECT_TRUE(wall.is_static);
    expect_vec3(wall.transform.translate, {0, 0, 0});
    expect_vec3(wall.transform.rotate_deg, {0, 30, 0});
    EXPECT_EQ(wall.transform.scale, 1.0f);
    EXPECT_TRUE(wall.keyframes.empty());
    EXPECT_FALSE(wall.animation.has_value());

    const gust::SceneObject& bunny = scene.objects[1];
    EXPECT_EQ(bunny.mesh, dir_.path() / "bunny.ply");
    EXPECT_FALSE(bunny.is_static);
    ASSERT_EQ(bunny.keyframes.size(), 2u);
    EXPECT_EQ(bunny.keyframes[0].t, 0.0);
    expect_vec3(bunny.keyframes[0].transform.translate, {-10, 2, 0});
    EXPECT_EQ(bunny.keyframes[1].t, 2.0);
    expect_vec3(bunny.keyframes[1].transform.translate, {10, 2, 0});
    expect_vec3(bunny.keyframes[1].transform.rotate_deg, {0, 180, 0});
    EXPECT_EQ(bunny.keyframes[1].transform.scale, 1.0f);

    ASSERT_EQ(scene.emitters.size(), 1u);
    const gust::EmitterDesc& omni = scene.emitters[0];
    EXPECT_EQ(omni.type, "omni");
    expect_vec3(omni.position, {0, 2, 5});
    EXPECT_EQ(omni.radius, 3.0f);
    EXPECT_EQ(omni.strength, 8.0f);
    expect_vec3(omni.direction, {1, 0, 0});
    EXPECT_EQ(omni.falloff, 1.0f);
}

TEST_F(SceneFile, anEmptyObjectIsTheDefaultScene) {
    const gust::SceneDesc scene = load_ok("{}");
    const gust::DomainDesc defaults;
    EXPECT_EQ(scene.dt, 0.02);
    EXPECT_EQ(scene.domain.cells, defaults.cells);
    EXPECT_EQ(scene.domain.cell_size, defaults.cell_size);
    EXPECT_EQ(scene.domain.voxels_per_cell, 4u);
    EXPECT_EQ(scene.domain.branching, 4u);
    EXPECT_EQ(scene.domain.hysteresis, 8u);
    expect_vec3(scene.ambient_velocity, {0, 0, 0});
    EXPECT_TRUE(scene.objects.empty());
    EXPECT_TRUE(scene.emitters.empty());
}

TEST_F(SceneFile, readsTheExtensions) {
    const gust::SceneDesc scene = load_ok(R"({
      "domain": { "hysteresis": 0, "branching": 8, "voxels_per_cell": 2, "cells": [8, 256, 16.0] },
      "objects": [
        { "mesh": "fox.glb", "animation": { "clip": "Walk", "speed": -1.5, "loop": false, "offset": 0.25 } },
        { "mesh": "man.GLTF", "animation": { "clip": "clip0" } },
        { "mesh": "sub/../fox.glb", "transform": { "scale": 0.01 } }
      ],
      "emitters": [
        { "type": "directional", "direction": [0, 0, -2], "strength": -3.5 },
        { "type": "vortex", "direction": [3, 4, 0], "falloff": 0, "radius": 0.5 },
        { "type": "motor", "falloff": 2.5 }
      ]
    })");
    EXPECT_EQ(scene.domain.hysteresis, 0u);
    EXPECT_EQ(scene.domain.branching, 8u);
    EXPECT_EQ(scene.domain.voxels_per_cell, 2u);
    EXPECT_EQ(scene.domain.cells, glm::uvec3(8, 256, 16));
    ASSERT_EQ(scene.objects.size(), 3u);
    ASSERT_TRUE(scene.objects[0].animation.has_value());
    EXPECT_EQ(scene.objects[0].animation->clip, "Walk");
    EXPECT_EQ(scene.objects[0].animation->speed, -1.5);
    EXPECT_FALSE(scene.objects[0].animation->loop);
    EXPECT_EQ(scene.objects[0].animation->offset, 0.25);
    ASSERT_TRUE(scene.objects[1].animation.has_value());
    EXPECT_EQ(scene.objects[1].animation->speed, 1.0);
    EXPECT_TRUE(scene.objects[1].animation->loop);
    EXPECT_EQ(scene.objects[1].animation->offset, 0.0);
    EXPECT_EQ(scene.objects[2].mesh, dir_.path() / "fox.glb") << "normalised";
    EXPECT_EQ(scene.objects[2].transform.scale, 0.01f);
    ASSERT_EQ(scene.emitters.size(), 3u);
    expect_vec3(scene.emitters[0].direction, {0, 0, -1});
    EXPECT_EQ(scene.emitters[0].strength, -3.5f);
    expect_vec3(scene.emitters[1].direction, {0.6f, 0.8f, 0}, 1e-7f);
    EXPECT_EQ(scene.emitters[1].falloff, 0.0f);
    EXPECT_EQ(scene.emitters[1].radius, 0.5f);
    EXPECT_EQ(scene.emitters[2].falloff, 2.5f);
}

TEST_F(SceneFile, readsMovingMotorsAndSolverSettings) {
    const gust::SceneDesc scene = load_ok(R"({
      "emitters": [{"type": "motor", "shape": "cone", "length": 3, "direction": [0, 0, 2],
                    "path": [{"t": 0, "position": [0, 1, 0]}, {"t": 2, "position": [4, 1, 0]}]}],
      "solver": {"advection": "semi_lagrangian", "pressure": "jacobi", "tolerance": 1e-3,
                 "max_cycles": 5, "max_iterations": 100, "vorticity": 0.5, "viscosity": 0.01}})");
    const gust::EmitterDesc& motor = scene.emitters[0];
    EXPECT_EQ(motor.shape, "cone");
    EXPECT_EQ(motor.length, 3.0f);
    expect_vec3(motor.direction, {0, 0, 1});
    expect_vec3(gust::emitter_position(motor, -1.0), {0, 1, 0});
    expect_vec3(gust::emitter_position(motor, 0.5), {1, 1, 0});
    expect_vec3(gust::emitter_position(motor, 9.0), {4, 1, 0});
    EXPECT_EQ(scene.solver.advection, "semi_lagrangian");
    EXPECT_EQ(scene.solver.pressure, "jacobi");
    EXPECT_EQ(scene.solver.tolerance, 1e-3f);
    EXPECT_EQ(scene.solver.max_cycles, 5u);
    EXPECT_EQ(scene.solver.max_iterations, 100u);
    EXPECT_EQ(scene.solver.vorticity, 0.5f);
    EXPECT_EQ(scene.solver.viscosity, 0.01f);
}

TEST_F(SceneFile, pressureSolverAndAdvectionNamesMapOntoTheSystemsSettings) {
    EXPECT_EQ(gust::system_desc(load_ok("{}")).wind.pressure, gust::WindPressure::MultigridPCG);
    const std::pair<const char*, gust::WindPressure> names[] = {{"mgpcg", gust::WindPressure::MultigridPCG},
                                                                {"multigrid", gust::WindPressure::Multigrid},
                                                                {"jacobi", gust::WindPressure::Jacobi}};
    for (const auto& [name, solver] : names) {
        const gust::SceneDesc scene = load_ok(std::string(R"({"solver": {"pressure": ")") + name + "\"}}");
        EXPECT_EQ(gust::system_desc(scene).wind.pressure, solver) << name;
    }
    const std::pair<const char*, gust::WindAdvection> advections[] = {
        {"maccormack", gust::WindAdvection::MacCormack},
        {"semi_lagrangian", gust::WindAdvection::SemiLagrangian},
        {"none", gust::WindAdvection::None}};
    for (const auto& [name, advection] : advections) {
        const gust::SceneDesc scene = load_ok(std::string(R"({"solver": {"advection": ")") + name + "\"}}");
        EXPECT_EQ(gust::system_desc(scene).wind.advection, advection) << name;
    }
}

// The System centres its domain on the focus: the scene's center, so its min corner is the scene's
// center − cells·cell_size/2; the rest of the domain and the numerics are the file's.
TEST_F(SceneFile, describesTheSystemThatRunsIt) {
    const gust::SceneDesc scene = load_ok(R"({
      "domain": {"center": [1, 2, 3], "cells": [16, 8, 24], "cell_size": 0.5, "voxels_per_cell": 2,
                 "branching": 2, "hysteresis": 3, "cascades": 3, "ratio": 2},
      "solver": {"tolerance": 0.001, "max_cycles": 5, "cycles_per_step": 4, "max_iterations": 100,
                 "vorticity": 0.5, "viscosity": 0.01}})");
    const gust::SystemDesc desc = gust::system_desc(scene);
    EXPECT_EQ(desc.domain.cells[0], 16u);
    EXPECT_EQ(desc.domain.cells[1], 8u);
    EXPECT_EQ(desc.domain.cells[2], 24u);
    EXPECT_EQ(desc.domain.cell_size, 0.5f);
    EXPECT_EQ(desc.domain.voxels_per_cell, 2u);
    EXPECT_EQ(desc.domain.branching, 2u);
    EXPECT_EQ(desc.domain.hysteresis, 3u);
    EXPECT_EQ(desc.domain.cascades, 3u);
    EXPECT_EQ(desc.domain.ratio, 2u);
    EXPECT_EQ(desc.domain.focus.x, 1.0f);
    EXPECT_EQ(desc.domain.focus.y, 2.0f);
    EXPECT_EQ(desc.domain.focus.z, 3.0f);
    EXPECT_EQ(desc.wind.tolerance, 1e-3f);
    EXPECT_EQ(desc.wind.max_cycles, 5u);
    EXPECT_EQ(desc.wind.cycles_per_step, 4u);
    EXPECT_EQ(desc.wind.max_iterations, 100u);
    EXPECT_EQ(desc.wind.vorticity, 0.5f);
    EXPECT_EQ(desc.wind.viscosity, 0.01f);
    EXPECT_EQ(gust::system_desc(load_ok("{}")).domain.hysteresis, 8u);
}

TEST_F(SceneFile, resolvesAbsoluteMeshPathsAsGiven) {
    const fs::path wall = dir_.path() / "wall.obj";
    const gust::SceneDesc scene = load_ok(R"({"objects": [{"mesh": ")" + wall.string() + R"("}]})");
    EXPECT_EQ(scene.objects[0].mesh, wall);
}

TEST_F(SceneFile, resolvesMeshPathsAgainstTheSceneFilesFolder) {
    dir_.write("meshes/rock.obj", "placeholder");
    const fs::path file =
        dir_.write("levels/one/scene.json", R"({"objects": [{"mesh": "../../meshes/rock.obj"}]})");
    const gust::Result<gust::SceneDesc> scene = gust::load_scene(file);
    ASSERT_TRUE(scene.ok()) << scene.message();
    EXPECT_EQ(scene->objects[0].mesh, dir_.path() / "meshes/rock.obj");
}

// ---------------------------------------------------------------------------------------------------
// Transforms and keyframes

TEST(Transform, rotatesAboutWorldAxesXFirstThenYThenZ) {
    gust::Transform transform;
    // +y: Rx(90) takes it to +z, Ry(90) takes +z to +x, Rz(0) leaves it. Rotating y first would give +z.
    transform.rotate_deg = {90, 90, 0};
    expect_vec3(apply(transform.matrix(), {0, 1, 0}), {1, 0, 0}, 1e-6f);
    // +x: Rx leaves it, Ry(90) takes it to -z, Rz(90) leaves -z.
    transform.rotate_deg = {90, 90, 90};
    expect_vec3(apply(transform.matrix(), {1, 0, 0}), {0, 0, -1}, 1e-6f);
    // +z: Rx(90) to -y, Ry leaves it, Rz(90) takes -y to +x.
    expect_vec3(apply(transform.matrix(), {0, 0, 1}), {1, 0, 0}, 1e-6f);
}

TEST(Transform, matchesTheHandComputedMatrixTranslateRzRyRxScale) {
    gust::Transform transform;
    transform.translate = {1, -2, 3};
    transform.rotate_deg = {30, -45, 60};
    transform.scale = 2.5f;
    const double x = glm::radians(30.0);
    const double y = glm::radians(-45.0);
    const double z = glm::radians(60.0);
    // Column-major rotations about the world axes.
    const glm::dmat3 rx(1, 0, 0, 0, std::cos(x), std::sin(x), 0, -std::sin(x), std::cos(x));
    const glm::dmat3 ry(std::cos(y), 0, -std::sin(y), 0, 1, 0, std::sin(y), 0, std::cos(y));
    const glm::dmat3 rz(std::cos(z), std::sin(z), 0, -std::sin(z), std::cos(z), 0, 0, 0, 1);
    const glm::dmat3 linear = rz * ry * rx * 2.5;
    glm::mat4 expected{glm::mat3(linear)};
    expected[3] = glm::vec4(1, -2, 3, 1);
    expect_matrix(transform.matrix(), expected, 1e-6f);
}

TEST(Transform, quarterTurnsLeaveNoResidue) {
    gust::Transform transform;
    transform.rotate_deg = {0, 90, 0};
    const glm::mat4 m = transform.matrix();
    EXPECT_LT(std::abs(m[0][0]), 1e-15f);
    EXPECT_LT(std::abs(m[2][2]), 1e-15f);
}

gust::SceneObject keyed_object() {
    gust::SceneObject object;
    object.keyframes.resize(3);
    object.keyframes[0].t = 1.0;
    object.keyframes[0].transform.translate = {0, 0, 0};
    object.keyframes[1].t = 2.0;
    object.keyframes[1].transform.translate = {10, 0, 0};
    object.keyframes[1].transform.rotate_deg = {0, 90, 0};
    object.keyframes[1].transform.scale = 3.0f;
    object.keyframes[2].t = 4.0;
    object.keyframes[2].transform.translate = {10, 4, 0};
    object.keyframes[2].transform.rotate_deg = {0, 270, 0};
    return object;
}

TEST(ObjectMatrix, interpolatesEachComponentLinearlyInTime) {
    const gust::SceneObject object = keyed_object();
    gust::Transform expected;
    expected.translate = {2.5f, 0, 0};
    expected.rotate_deg = {0, 22.5f, 0};
    expected.scale = 1.5f;
    expect_matrix(gust::object_matrix(object, 1.25), expected.matrix(), 1e-5f);
    // Degrees interpolate as numbers: 90 to 270 passes through 180, not the short way through 0.
    expected.translate = {10, 2, 0};
    expected.rotate_deg = {0, 180, 0};
    expected.scale = 2.0f;
    expect_matrix(gust::object_matrix(object, 3.0), expected.matrix(), 1e-5f);
}

TEST(ObjectMatrix, isExactlyTheKeyAtEachKeyTime) {
    const gust::SceneObject object = keyed_object();
    for (const gust::Keyframe& key : object.keyframes)
        EXPECT_EQ(gust::object_matrix(object, key.t), key.transform.matrix()) << key.t;
}

TEST(ObjectMatrix, holdsTheEndKeysOutsideTheirRange) {
    const gust::SceneObject object = keyed_object();
    EXPECT_EQ(gust::object_matrix(object, -5.0), object.keyframes[0].transform.matrix());
    EXPECT_EQ(gust::object_matrix(object, 0.999), object.keyframes[0].transform.matrix());
    EXPECT_EQ(gust::object_matrix(object, 4.001), object.keyframes[2].transform.matrix());
    EXPECT_EQ(gust::object_matrix(object, 1e9), object.keyframes[2].transform.matrix());
    EXPECT_EQ(gust::object_matrix(object, std::nan("")), object.keyframes[0].transform.matrix());
}

TEST(ObjectMatrix, aSingleKeyframeHoldsForAllTime) {
    gust::SceneObject object;
    object.keyframes.resize(1);
    object.keyframes[0].t = 3.0;
    object.keyframes[0].transform.translate = {1, 2, 3};
    for (double t : {-1.0, 0.0, 3.0, 7.5})
        EXPECT_EQ(gust::object_matrix(object, t), object.keyframes[0].transform.matrix()) << t;
}

TEST(ObjectMatrix, usesTheTransformWithoutKeyframes) {
    gust::SceneObject object;
    object.transform.translate = {4, 5, 6};
    object.transform.rotate_deg = {10, 20, 30};
    object.transform.scale = 0.5f;
    EXPECT_EQ(gust::object_matrix(object, 0.0), object.transform.matrix());
    EXPECT_EQ(gust::object_matrix(object, 99.0), object.transform.matrix());
}

TEST_F(SceneFile, readsTeleportKeysAndTheSolidSpeedLimit) {
    const gust::SceneDesc scene = load_ok(R"({"solver": {"max_solid_speed": 12.5},
      "objects": [{"mesh": "bunny.ply", "keyframes": [
        {"t": 0, "translate": [-10, 0, 0]}, {"t": 1, "translate": [10, 0, 0], "teleport": true}]}]})");
    EXPECT_FALSE(scene.objects[0].keyframes[0].teleport);
    EXPECT_TRUE(scene.objects[0].keyframes[1].teleport);
    EXPECT_EQ(gust::system_desc(scene).wind.max_solid_speed, 12.5f);
    EXPECT_EQ(gust::system_desc(load_ok("{}")).wind.max_solid_speed, 50.0f);
    EXPECT_EQ(gust::system_desc(load_ok("{}")).wind.advection, gust::WindAdvection::MacCormack);
}

// Scene files are for tools: the solve runs to the tolerance unless the file names a budget.
TEST_F(SceneFile, readsAFixedBudgetOfVCyclesAndDefaultsToTheTolerance) {
    EXPECT_EQ(gust::system_desc(load_ok(R"({"solver": {"cycles_per_step": 3}})")).wind.cycles_per_step, 3u);
    EXPECT_EQ(gust::system_desc(load_ok("{}")).wind.cycles_per_step, 0u);
}

// A "teleport" key holds its predecessor's placement until its own time, then jumps: no frame sees the
// move as motion.
TEST(ObjectMatrix, aTeleportKeyHoldsThePreviousKeyUntilItsTime) {
    gust::SceneObject object;
    object.keyframes.resize(2);
    object.keyframes[0].transform.translate = {-10, 0, 0};
    object.keyframes[1].t = 1.0;
    object.keyframes[1].transform.translate = {10, 0, 0};
    object.keyframes[1].teleport = true;
    EXPECT_EQ(gust::object_matrix(object, 0.5), object.keyframes[0].transform.matrix());
    EXPECT_EQ(gust::object_matrix(object, 0.999), object.keyframes[0].transform.matrix());
    EXPECT_EQ(gust::object_matrix(object, 1.0), object.keyframes[1].transform.matrix());
}

// A jump is a teleport key, or a segment shorter than the frame that ends within it; keys a frame or more
// apart are motion, whatever the distance.
TEST(ObjectJumps, aTeleportKeyOrASegmentShorterThanAFrameIsAJump) {
    gust::SceneObject object;
    object.keyframes.resize(4);
    object.keyframes[1].t = 1.0;
    object.keyframes[2].t = 1.001; // 20 m within a millisecond
    object.keyframes[2].transform.translate = {20, 0, 0};
    object.keyframes[3].t = 3.0;
    object.keyframes[3].teleport = true;
    const double dt = 0.02;
    int jumps = 0;
    for (int frame = 1; frame < 200; ++frame) {
        const double t = frame * dt;
        const bool jump = gust::object_jumps(object, t - dt, t);
        jumps += jump ? 1 : 0;
        if (jump) {
            EXPECT_TRUE(std::abs(t - 1.02) < 1e-9 || std::abs(t - 3.0) < 1e-9) << t;
        }
    }
    EXPECT_EQ(jumps, 2);
    gust::SceneObject per_frame;
    for (int k = 0; k < 10; ++k) {
        per_frame.keyframes.emplace_back();
        per_frame.keyframes.back().t = k * dt;
        per_frame.keyframes.back().transform.translate = {float(k), 0, 0}; // 50 m/s, but motion
    }
    for (int frame = 1; frame < 10; ++frame)
        EXPECT_FALSE(gust::object_jumps(per_frame, (frame - 1) * dt, frame * dt)) << frame;
}

TEST_F(SceneFile, designExampleBunnyCrossesTheWindAtHalfTime) {
    const gust::SceneDesc scene = load_ok(kDesignExample);
    // t = 1 s: halfway from (-10,2,0) to (10,2,0), turned 90 degrees about y.
    const glm::mat4 m = gust::object_matrix(scene.objects[1], 1.0);
    expect_vec3(apply(m, {0, 0, 0}), {0, 2, 0}, 1e-5f);
    expect_vec3(apply(m, {1, 0, 0}), {0, 2, -1}, 1e-5f);
}

// ---------------------------------------------------------------------------------------------------
// Bad files

struct BadScene {
    const char* name;
    std::string text;
    std::string message; ///< expected after "<file>: "; "$DIR" stands for the scene's folder
};

std::ostream& operator<<(std::ostream& out, const BadScene& bad) {
    return out << bad.name;
}

class RejectsBadScene : public testing::TestWithParam<BadScene> {};

TEST_P(RejectsBadScene, withFileKeyPathAndReason) {
    gust::test::TempDir dir;
    for (const char* name : {"wall.obj", "bunny.ply", "fox.glb"})
        dir.write(name, "placeholder");
    fs::create_directories(dir.path() / "folder.obj");
    const fs::path file = dir.write("scene.json", GetParam().text);
    const gust::Result<gust::SceneDesc> scene = gust::load_scene(file);
    ASSERT_FALSE(scene.ok());
    std::string expected = GetParam().message;
    if (const std::size_t at = expected.find("$DIR"); at != std::string::npos) {
        expected.replace(at, 4, dir.path().string());
    }
    const std::string prefix = file.string() + ": ";
    ASSERT_EQ(scene.message().rfind(prefix, 0), 0u) << scene.message();
    EXPECT_EQ(scene.message().substr(prefix.size(), expected.size()), expected) << scene.message();
}

std::string deep_nesting() {
    std::string text = R"({"objects": )";
    for (int i = 0; i < 100; ++i)
        text += "[";
    for (int i = 0; i < 100; ++i)
        text += "]";
    return text + "}";
}

std::string too_many_features() {
    std::string features;
    for (int i = 0; i < 65; ++i)
        features += std::string(i == 0 ? "" : ", ") +
                    R"({"type": "hill", "center": [0, 0], "height": 1, "radius": 1})";
    return R"({"objects": [{"terrain": {"features": [)" + features + "]}}]}";
}

// clang-format off
INSTANTIATE_TEST_SUITE_P(Files, RejectsBadScene, testing::Values(
    BadScene{"MalformedJson", "{\"dt\": 0.02,\n  \"domain\": }",
             "malformed JSON at line 2, column 13: syntax error while parsing value - unexpected '}'"},
    BadScene{"EmptyFile", "", "empty file"},
    BadScene{"OnlyWhitespace", "\n\n  ", "malformed JSON at line 3, column 3: syntax error while parsing value - unexpected end of input"},
    BadScene{"TrailingText", "{} x", "malformed JSON at line 1, column 4: syntax error"},
    BadScene{"NumberOverflowingDouble", "{\"dt\":\n 1e400}",
             "malformed JSON at line 2, column 6: number overflow parsing '1e400'"},
    BadScene{"DuplicateKey", R"({"dt": 0.1, "dt": 0.2})", "dt: duplicate key"},
    BadScene{"DuplicateNestedKey", R"({"objects": [{"mesh": "wall.obj"}, {"mesh": "wall.obj", "mesh": "bunny.ply"}]})",
             "objects[1].mesh: duplicate key"},
    BadScene{"DeepNesting", deep_nesting(), "objects[0][0][0]"},
    BadScene{"TopLevelArray", "[]", "the top level must be a JSON object (found array)"},
    BadScene{"UnknownTopLevelKey", R"({"wind": {}})",
             "wind: unknown key (expected one of: dt, domain, ambient, objects, emitters, solver)"},
    BadScene{"UnknownObjectKey", R"({"objects": [{"mesh": "wall.obj", "colour": "red"}]})",
             "objects[0].colour: unknown key (expected one of: mesh, static, transform, keyframes, animation, terrain)"},
    BadScene{"UnknownDomainKey", R"({"domain": {"size": 3}})", "domain.size: unknown key"},
    BadScene{"UnknownTransformKey", R"({"objects": [{"mesh": "wall.obj", "transform": {"rotate": [0, 1, 0]}}]})",
             "objects[0].transform.rotate: unknown key (expected one of: translate, rotate_deg, scale)"},
    BadScene{"UnknownKeyframeKey", R"({"objects": [{"mesh": "wall.obj", "keyframes": [{"t": 0, "time": 1}]}]})",
             "objects[0].keyframes[0].time: unknown key"},
    BadScene{"UnknownEmitterKey", R"({"emitters": [{"type": "omni", "power": 1}]})", "emitters[0].power: unknown key"},
    BadScene{"UnknownAnimationKey", R"({"objects": [{"mesh": "fox.glb", "animation": {"clip": "Walk", "rate": 2}}]})",
             "objects[0].animation.rate: unknown key (expected one of: clip, speed, loop, offset)"},
    BadScene{"UnknownAmbientKey", R"({"ambient": {"speed": 1}})", "ambient.speed: unknown key"},
    BadScene{"DtAsString", R"({"dt": "0.02"})", "dt: expected a number (found string)"},
    BadScene{"ZeroDt", R"({"dt": 0})", "dt: must be in (0, 10.0] seconds (found 0.0)"},
    BadScene{"NegativeDt", R"({"dt": -0.5})", "dt: must be in (0, 10.0] seconds (found -0.5)"},
    BadScene{"DtPastTheSolversLongestStep", R"({"dt": 11})", "dt: must be in (0, 10.0] seconds (found 11.0)"},
    BadScene{"DtBelowAFloat", R"({"dt": 1e-300})", "dt: number 1e-300 is too small for a 32-bit float (at least 1.2e-38)"},
    BadScene{"ToleranceBelowAFloat", R"({"solver": {"tolerance": 1e-300}})",
             "solver.tolerance: number 1e-300 is too small for a 32-bit float (at least 1.2e-38)"},
    BadScene{"CenterBeyondWhatFloatsPlace", R"({"domain": {"center": [0, 0, 3e5], "cell_size": 0.5}})",
             "domain.center: is more than 2^19 cells of 0.5 m from the world's origin, where floats cannot place voxels"},
    BadScene{"AmbientOverTheLimit", R"({"ambient": {"velocity": [9999, -9999, 9999]}})",
             "ambient.velocity: must be below 10000.0 m/s (found 17318.775)"},
    BadScene{"DomainNotObject", R"({"domain": [1]})", "domain: expected an object (found array)"},
    BadScene{"CellsTooMany", R"({"domain": {"cells": [300, 16, 16]}})",
             "domain.cells[0]: must be an integer from 8 to 256 (found 300.0)"},
    BadScene{"CellsTooFew", R"({"domain": {"cells": [16, 7, 16]}})",
             "domain.cells[1]: must be an integer from 8 to 256 (found 7.0)"},
    BadScene{"CellsFractional", R"({"domain": {"cells": [16, 16, 16.5]}})",
             "domain.cells[2]: must be an integer from 8 to 256 (found 16.5)"},
    BadScene{"CellsWrongLength", R"({"domain": {"cells": [16, 16]}})",
             "domain.cells: expected an array of 3 integers (found 2 items)"},
    BadScene{"ZeroCellSize", R"({"domain": {"cell_size": 0}})", "domain.cell_size: must be greater than 0 (found 0.0)"},
    BadScene{"ZeroVoxelsPerCell", R"({"domain": {"voxels_per_cell": 0}})",
             "domain.voxels_per_cell: must be an integer from 1 to 8 (found 0.0)"},
    BadScene{"BranchingThree", R"({"domain": {"branching": 3}})", "domain.branching: must be 2, 4 or 8 (found 3.0)"},
    BadScene{"BranchingSixteen", R"({"domain": {"branching": 16}})", "domain.branching: must be 2, 4 or 8 (found 16.0)"},
    BadScene{"NoCascades", R"({"domain": {"cascades": 0}})",
             "domain.cascades: must be an integer from 1 to 8 (found 0.0)"},
    BadScene{"RatioThree", R"({"domain": {"ratio": 3}})", "domain.ratio: must be 2 or 4 (found 3.0)"},
    BadScene{"NegativeHysteresis", R"({"domain": {"hysteresis": -1}})",
             "domain.hysteresis: must be an integer from 0 to 4294967295 (found -1.0)"},
    BadScene{"CenterTooShort", R"({"domain": {"center": [0, 1]}})",
             "domain.center: expected an array of 3 numbers (found 2 items)"},
    BadScene{"CenterItemString", R"({"domain": {"center": [0, "1", 2]}})",
             "domain.center[1]: expected a number (found string)"},
    BadScene{"AmbientVelocityNull", R"({"ambient": {"velocity": null}})",
             "ambient.velocity: expected an array of 3 numbers (found null)"},
    BadScene{"ObjectsNotArray", R"({"objects": {"mesh": "wall.obj"}})", "objects: expected an array (found object)"},
    BadScene{"ObjectNotObject", R"({"objects": ["wall.obj"]})", "objects[0]: expected an object (found string)"},
    BadScene{"MissingMesh", R"({"objects": [{"static": true}]})",
             "objects[0].mesh: missing required key (an object needs a mesh or a terrain)"},
    BadScene{"MeshAndTerrain", R"({"objects": [{"mesh": "wall.obj", "terrain": {}}]})",
             "objects[0].terrain: an object has either a mesh or a terrain, not both"},
    BadScene{"TerrainNotAnObject", R"({"objects": [{"terrain": 3}]})",
             "objects[0].terrain: expected an object (found number)"},
    BadScene{"UnknownTerrainKey", R"({"objects": [{"terrain": {"height": 3}}]})",
             "objects[0].terrain.height: unknown key (expected one of: size, samples, base, features, noise)"},
    BadScene{"AnimatedTerrain", R"({"objects": [{"terrain": {}, "animation": {"clip": "Walk"}}]})",
             "objects[0].animation: a terrain cannot be animated (only glTF meshes can)"},
    BadScene{"StaticTerrainWithKeyframes", R"({"objects": [{"terrain": {}, "static": true, "keyframes": [{"t": 0}]}]})",
             "objects[0].keyframes: a static object cannot have keyframes"},
    BadScene{"TerrainWithTransformAndKeyframes", R"({"objects": [{"terrain": {}, "transform": {}, "keyframes": [{"t": 0}]}]})",
             "objects[0].keyframes: an object has either a transform or keyframes, not both"},
    BadScene{"TerrainSizeOfThree", R"({"objects": [{"terrain": {"size": [1, 2, 3]}}]})",
             "objects[0].terrain.size: expected an array of 2 numbers [sx, sz] (found 3 items)"},
    BadScene{"TerrainSizeNotAnArray", R"({"objects": [{"terrain": {"size": 100}}]})",
             "objects[0].terrain.size: expected an array of 2 numbers [sx, sz] (found number)"},
    BadScene{"TerrainSizeZero", R"({"objects": [{"terrain": {"size": [10, 0]}}]})",
             "objects[0].terrain.size[1]: must be greater than 0 (found 0.0)"},
    BadScene{"TerrainSizeBeyond100Km", R"({"objects": [{"terrain": {"size": [200000, 10]}}]})",
             "objects[0].terrain.size[0]: must be at most 1e+05 m (found 2e+05)"},
    BadScene{"TerrainSamplesZero", R"({"objects": [{"terrain": {"samples": [0, 4]}}]})",
             "objects[0].terrain.samples[0]: must be an integer from 1 to 2048 (found 0.0)"},
    BadScene{"TerrainSamplesFraction", R"({"objects": [{"terrain": {"samples": [4, 2.5]}}]})",
             "objects[0].terrain.samples[1]: must be an integer from 1 to 2048 (found 2.5)"},
    BadScene{"TerrainSamplesBeyond2048", R"({"objects": [{"terrain": {"samples": [2049, 1]}}]})",
             "objects[0].terrain.samples[0]: must be an integer from 1 to 2048 (found 2049.0)"},
    BadScene{"TerrainSamplesOfOne", R"({"objects": [{"terrain": {"samples": [4]}}]})",
             "objects[0].terrain.samples: expected an array of 2 integers [nx, nz] (found 1 items)"},
    BadScene{"TerrainBeyond8MillionTriangles", R"({"objects": [{"terrain": {"samples": [2048, 2000]}}]})",
             "objects[0].terrain.samples: 2 · nx · nz = 8192000 triangles, more than 8000000"},
    BadScene{"TerrainBaseNotANumber", R"({"objects": [{"terrain": {"base": "low"}}]})",
             "objects[0].terrain.base: expected a number (found string)"},
    BadScene{"TerrainBaseBeyond100Km", R"({"objects": [{"terrain": {"base": -1e6}}]})",
             "objects[0].terrain.base: must be within ±1e+05 m (found -1e+06)"},
    BadScene{"TerrainFeaturesNotAnArray", R"({"objects": [{"terrain": {"features": {}}}]})",
             "objects[0].terrain.features: expected an array (found object)"},
    BadScene{"TerrainFeatureNotAnObject", R"({"objects": [{"terrain": {"features": [1]}}]})",
             "objects[0].terrain.features[0]: expected an object (found number)"},
    BadScene{"TerrainFeatureWithoutType", R"({"objects": [{"terrain": {"features": [{"height": 1}]}}]})",
             "objects[0].terrain.features[0].type: missing required key"},
    BadScene{"UnknownTerrainFeature", R"({"objects": [{"terrain": {"features": [{"type": "crater"}]}}]})",
             "objects[0].terrain.features[0].type: unknown terrain feature 'crater' (expected hill, ridge or valley)"},
    BadScene{"HillWithAWidth", R"({"objects": [{"terrain": {"features": [{"type": "hill", "center": [0, 0], "height": 1, "width": 2}]}}]})",
             "objects[0].terrain.features[0].width: unknown key (expected one of: type, center, height, radius)"},
    BadScene{"HillWithoutRadius", R"({"objects": [{"terrain": {"features": [{"type": "hill", "center": [0, 0], "height": 1}]}}]})",
             "objects[0].terrain.features[0].radius: missing required key"},
    BadScene{"HillWithoutCenter", R"({"objects": [{"terrain": {"features": [{"type": "hill", "height": 1, "radius": 1}]}}]})",
             "objects[0].terrain.features[0].center: missing required key"},
    BadScene{"HillCenterOfThree", R"({"objects": [{"terrain": {"features": [{"type": "hill", "center": [0, 0, 0], "height": 1, "radius": 1}]}}]})",
             "objects[0].terrain.features[0].center: expected an array of 2 numbers [x, z] (found 3 items)"},
    BadScene{"HillTooHigh", R"({"objects": [{"terrain": {"features": [{"type": "hill", "center": [0, 0], "height": 1e6, "radius": 1}]}}]})",
             "objects[0].terrain.features[0].height: must be within ±1e+05 m (found 1e+06)"},
    BadScene{"RidgeWithZeroWidth", R"({"objects": [{"terrain": {"features": [{"type": "ridge", "from": [0, 0], "to": [1, 0], "height": 1, "width": 0}]}}]})",
             "objects[0].terrain.features[0].width: must be greater than 0 (found 0.0)"},
    BadScene{"RidgeWithoutTo", R"({"objects": [{"terrain": {"features": [{"type": "ridge", "from": [0, 0], "height": 1, "width": 1}]}}]})",
             "objects[0].terrain.features[0].to: missing required key"},
    BadScene{"RidgeFromNotANumber", R"({"objects": [{"terrain": {"features": [{"type": "ridge", "from": [0, "x"], "to": [1, 0], "height": 1, "width": 1}]}}]})",
             "objects[0].terrain.features[0].from[1]: expected a number (found string)"},
    BadScene{"ValleyWithAHeight", R"({"objects": [{"terrain": {"features": [{"type": "valley", "from": [0, 0], "to": [1, 0], "height": 1, "width": 1}]}}]})",
             "objects[0].terrain.features[0].height: unknown key (expected one of: type, from, to, depth, width)"},
    BadScene{"ValleyWithNegativeDepth", R"({"objects": [{"terrain": {"features": [{"type": "valley", "from": [0, 0], "to": [1, 0], "depth": -5, "width": 1}]}}]})",
             "objects[0].terrain.features[0].depth: must not be negative (found -5.0); a valley digs by its depth"},
    BadScene{"ValleyWithoutDepth", R"({"objects": [{"terrain": {"features": [{"type": "valley", "from": [0, 0], "to": [1, 0], "width": 1}]}}]})",
             "objects[0].terrain.features[0].depth: missing required key"},
    BadScene{"UnknownTerrainNoiseKey", R"({"objects": [{"terrain": {"noise": {"scale": 1}}}]})",
             "objects[0].terrain.noise.scale: unknown key (expected one of: amplitude, wavelength, octaves, seed)"},
    BadScene{"TerrainNoiseNotAnObject", R"({"objects": [{"terrain": {"noise": true}}]})",
             "objects[0].terrain.noise: expected an object (found boolean)"},
    BadScene{"NegativeNoiseAmplitude", R"({"objects": [{"terrain": {"noise": {"amplitude": -1}}}]})",
             "objects[0].terrain.noise.amplitude: must not be negative (found -1.0)"},
    BadScene{"NoiseWavelengthBelowACentimetre", R"({"objects": [{"terrain": {"noise": {"wavelength": 0.001}}}]})",
             "objects[0].terrain.noise.wavelength: must be at least 0.01 m (found 0.001)"},
    BadScene{"ZeroNoiseWavelength", R"({"objects": [{"terrain": {"noise": {"wavelength": 0}}}]})",
             "objects[0].terrain.noise.wavelength: must be greater than 0 (found 0.0)"},
    BadScene{"SeventeenNoiseOctaves", R"({"objects": [{"terrain": {"noise": {"octaves": 17}}}]})",
             "objects[0].terrain.noise.octaves: must be an integer from 1 to 16 (found 17.0)"},
    BadScene{"NegativeNoiseSeed", R"({"objects": [{"terrain": {"noise": {"seed": -1}}}]})",
             "objects[0].terrain.noise.seed: must be an integer from 0 to 4294967295 (found -1.0)"},
    BadScene{"SixtyFiveTerrainFeatures", too_many_features(), "objects[0].terrain.features: at most 64 features (found 65)"},
    BadScene{"EmptyMeshPath", R"({"objects": [{"mesh": ""}]})", "objects[0].mesh: must not be empty"},
    BadScene{"MeshNotFound", R"({"objects": [{"mesh": "wall.obj"}, {"mesh": "missing.obj"}]})",
             "objects[1].mesh: file not found: $DIR/missing.obj"},
    BadScene{"MeshIsADirectory", R"({"objects": [{"mesh": "folder.obj"}]})",
             "objects[0].mesh: is a directory, not a mesh file: $DIR/folder.obj"},
    BadScene{"StaticAsNumber", R"({"objects": [{"mesh": "wall.obj", "static": 1}]})",
             "objects[0].static: expected true or false (found number)"},
    BadScene{"FloatOverflow", R"({"objects": [{"mesh": "wall.obj", "transform": {"translate": [0, 1e39, 0]}}]})",
             "objects[0].transform.translate[1]: number 1e+39 is too large for a 32-bit float"},
    BadScene{"ZeroScale", R"({"objects": [{"mesh": "wall.obj", "transform": {"scale": 0}}]})",
             "objects[0].transform.scale: must be greater than 0 (found 0.0)"},
    BadScene{"NegativeKeyframeScale",
             R"({"objects": [{"mesh": "wall.obj", "keyframes": [{"t": 0}, {"t": 1, "scale": -2}]}]})",
             "objects[0].keyframes[1].scale: must be greater than 0 (found -2.0)"},
    BadScene{"KeyframesOutOfOrder", R"({"objects": [{"mesh": "wall.obj"}, {"mesh": "bunny.ply", "keyframes": [
                 {"t": 0.0}, {"t": 3.0}, {"t": 2.0}]}]})",
             "objects[1].keyframes[2].t: keyframes must be in increasing time order (2.0 after 3.0)"},
    BadScene{"KeyframesAtTheSameTime", R"({"objects": [{"mesh": "wall.obj", "keyframes": [{"t": 1}, {"t": 1}]}]})",
             "objects[0].keyframes[1].t: keyframes must be in increasing time order (1.0 after 1.0)"},
    BadScene{"KeyframeWithoutTime", R"({"objects": [{"mesh": "wall.obj", "keyframes": [{"translate": [0, 0, 0]}]}]})",
             "objects[0].keyframes[0].t: missing required key"},
    BadScene{"NoKeyframes", R"({"objects": [{"mesh": "wall.obj", "keyframes": []}]})",
             "objects[0].keyframes: needs at least one keyframe"},
    BadScene{"TransformAndKeyframes",
             R"({"objects": [{"mesh": "wall.obj", "transform": {}, "keyframes": [{"t": 0}]}]})",
             "objects[0].keyframes: an object has either a transform or keyframes, not both"},
    BadScene{"StaticWithKeyframes", R"({"objects": [{"mesh": "wall.obj", "static": true, "keyframes": [{"t": 0}]}]})",
             "objects[0].keyframes: a static object cannot have keyframes"},
    BadScene{"StaticAnimated", R"({"objects": [{"mesh": "fox.glb", "static": true, "animation": {"clip": "Walk"}}]})",
             "objects[0].animation: a static object cannot be animated"},
    BadScene{"AnimationOnPly", R"({"objects": [{"mesh": "bunny.ply", "animation": {"clip": "Walk"}}]})",
             "objects[0].animation: skinned clips need a glTF mesh (.gltf or .glb), not bunny.ply"},
    BadScene{"AnimationWithoutClip", R"({"objects": [{"mesh": "fox.glb", "animation": {"speed": 2}}]})",
             "objects[0].animation.clip: missing required key"},
    BadScene{"AnimationSpeedString", R"({"objects": [{"mesh": "fox.glb", "animation": {"clip": "Walk", "speed": "fast"}}]})",
             "objects[0].animation.speed: expected a number (found string)"},
    BadScene{"AnimationLoopString", R"({"objects": [{"mesh": "fox.glb", "animation": {"clip": "Walk", "loop": "yes"}}]})",
             "objects[0].animation.loop: expected true or false (found string)"},
    BadScene{"EmitterWithoutType", R"({"emitters": [{"position": [0, 0, 0]}]})", "emitters[0].type: missing required key"},
    BadScene{"UnknownEmitterType", R"({"emitters": [{"type": "omni"}, {"type": "fan"}]})",
             "emitters[1].type: unknown emitter type 'fan' (expected directional, omni, vortex or motor)"},
    BadScene{"ZeroEmitterDirection", R"({"emitters": [{"type": "directional", "direction": [0, 0, 0]}]})",
             "emitters[0].direction: must not be the zero vector"},
    BadScene{"ZeroEmitterRadius", R"({"emitters": [{"type": "omni", "radius": 0}]})",
             "emitters[0].radius: must be greater than 0 (found 0.0)"},
    BadScene{"NegativeFalloff", R"({"emitters": [{"type": "omni", "falloff": -1}]})",
             "emitters[0].falloff: must be in [0, 64.0] (found -1.0)"},
    BadScene{"SixtyFiveEmitters",
             [] {
                 std::string text = R"({"emitters": [{"type": "omni"})";
                 for (int i = 1; i < 65; ++i) text += R"(, {"type": "omni"})";
                 return text + "]}";
             }(),
             "emitters: at most 64 emitters (found 65)"},
    BadScene{"SteepFalloff", R"({"emitters": [{"type": "omni", "falloff": 65}]})",
             "emitters[0].falloff: must be in [0, 64.0] (found 65.0)"},
    BadScene{"StrongEmitter", R"({"emitters": [{"type": "omni"}, {"type": "vortex", "strength": -10001}]})",
             "emitters[1].strength: must be within ±10000.0 m/s (found -10001.0)"},
    BadScene{"EmitterStrengthOverflow", R"({"emitters": [{"type": "omni", "strength": -4e38}]})",
             "emitters[0].strength: number -4e+38 is too large for a 32-bit float"},
    BadScene{"ShapeOnNonMotor", R"({"emitters": [{"type": "omni", "shape": "cone"}]})",
             "emitters[0].shape: only motors have a shape"},
    BadScene{"UnknownMotorShape", R"({"emitters": [{"type": "motor", "shape": "box"}]})",
             "emitters[0].shape: unknown motor shape 'box' (expected capsule or cone)"},
    BadScene{"ConeWithoutLength", R"({"emitters": [{"type": "motor", "shape": "cone"}]})",
             "emitters[0].length: a cone motor needs a length greater than 0"},
    BadScene{"NegativeMotorLength", R"({"emitters": [{"type": "motor", "length": -2}]})",
             "emitters[0].length: must not be negative (found -2.0)"},
    BadScene{"PathOutOfOrder", R"({"emitters": [{"type": "motor", "path": [{"t": 1, "position": [0, 0, 0]}, {"t": 1, "position": [1, 0, 0]}]}]})",
             "emitters[0].path[1].t: path keys must be in increasing time order (1.0 after 1.0)"},
    BadScene{"PathKeyWithoutPosition", R"({"emitters": [{"type": "omni", "path": [{"t": 0}]}]})",
             "emitters[0].path[0].position: missing required key"},
    BadScene{"UnknownAdvection", R"({"solver": {"advection": "bfecc2"}})",
             "solver.advection: unknown advection 'bfecc2' (expected maccormack, semi_lagrangian or none)"},
    BadScene{"UnknownPressureSolver", R"({"solver": {"pressure": "cg"}})",
             "solver.pressure: unknown pressure solver 'cg' (expected mgpcg, multigrid or jacobi)"},
    BadScene{"ToleranceOfOne", R"({"solver": {"tolerance": 1}})", "solver.tolerance: must be less than 1 (found 1.0)"},
    BadScene{"ZeroCycles", R"({"solver": {"max_cycles": 0}})", "solver.max_cycles: must be an integer from 1 to 1000 (found 0.0)"},
    BadScene{"BudgetTooLarge", R"({"solver": {"cycles_per_step": 1001}})", "solver.cycles_per_step: must be an integer from 0 to 1000 (found 1001.0)"},
    BadScene{"NegativeViscosity", R"({"solver": {"viscosity": -1}})", "solver.viscosity: must not be negative (found -1.0)"},
    BadScene{"NineVoxelsPerCell", R"({"domain": {"voxels_per_cell": 9}})",
             "domain.voxels_per_cell: must be an integer from 1 to 8 (found 9.0)"},
    BadScene{"VoxelsBelowATenthOfAMillimetre", R"({"domain": {"cell_size": 0.0002, "voxels_per_cell": 4}})",
             "domain.cell_size: voxels of cell_size / voxels_per_cell = 5e-05 m are below the smallest, 1e-04 m"},
    BadScene{"CellsAboveAKilometre", R"({"domain": {"cell_size": 1500}})",
             "domain.cell_size: must be at most 1000.0 m (found 1500.0)"},
    BadScene{"TreeBeyond1024VoxelsPerAxis", R"({"domain": {"cells": [256, 8, 8], "voxels_per_cell": 8}})",
             "domain: the domain needs 2048 voxels along its longest axis; with branching 4 the tree would exceed 1024 per axis"},
    BadScene{"TreeBeyond1024AtBranchingEight", R"({"domain": {"cells": [8, 8, 130], "voxels_per_cell": 4, "branching": 8}})",
             "domain: the domain needs 520 voxels along its longest axis; with branching 8 the tree would exceed 1024 per axis"}),
    [](const testing::TestParamInfo<BadScene>& param) { return std::string(param.param.name); });
// clang-format on

TEST(LoadScene, rejectsMissingFile) {
    gust::test::TempDir dir;
    const gust::Result<gust::SceneDesc> scene = gust::load_scene(dir.path() / "absent.json");
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.message(), (dir.path() / "absent.json").string() + ": file not found");
}

TEST(LoadScene, rejectsDirectory) {
    gust::test::TempDir dir;
    const gust::Result<gust::SceneDesc> scene = gust::load_scene(dir.path());
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.message(), dir.path().string() + ": is a directory, not a scene file");
}

TEST(LoadScene, survivesEveryTruncationOfTheDesignExample) {
    gust::test::TempDir dir;
    dir.write("wall.obj", "placeholder");
    dir.write("bunny.ply", "placeholder");
    const std::string text = kDesignExample;
    for (std::size_t n = 0; n < text.size(); ++n) {
        const fs::path file = dir.write("scene.json", text.substr(0, n));
        const gust::Result<gust::SceneDesc> scene = gust::load_scene(file);
        ASSERT_FALSE(scene.ok()) << n;
        EXPECT_EQ(scene.message().rfind(file.string() + ": ", 0), 0u) << scene.message();
    }
}

TEST(LoadScene, survivesRandomCorruptionOfTheDesignExample) {
    gust::test::TempDir dir;
    dir.write("wall.obj", "placeholder");
    dir.write("bunny.ply", "placeholder");
    const std::string text = kDesignExample;
    const std::string alphabet = "{}[],:\"0123456789.-+eE \n\ttruefalsnul\\";
    std::mt19937 random(11);
    std::uniform_int_distribution<std::size_t> offset(0, text.size() - 1);
    std::uniform_int_distribution<std::size_t> pick(0, alphabet.size() - 1);
    for (int round = 0; round < 500; ++round) {
        std::string bytes = text;
        for (int k = 0; k < 1 + round % 4; ++k)
            bytes[offset(random)] = alphabet[pick(random)];
        const fs::path file = dir.write("scene.json", bytes);
        const gust::Result<gust::SceneDesc> scene = gust::load_scene(file);
        if (!scene.ok()) {
            EXPECT_EQ(scene.message().rfind(file.string() + ": ", 0), 0u) << scene.message();
        }
    }
}

} // namespace
