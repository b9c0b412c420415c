// Physics the wind must get right around obstacles, after many steps and not only after one projection,
// each test against a named reference: potential flow past a sphere, a bluff body's stagnation, speed-up
// and wake, uniform flow along a wall, plug flow in a duct, a rigid body's inside, incompressibility through
// a control surface, a teleport and a walking skinned character. Everything goes through the engine-facing
// API (gust.hpp), as a game would drive it, on small grids so that lavapipe runs them in CI. The probes read
// the solver's field below a cell (WindReading::Solver), since the claims are the solver's; the answers a
// game reads (WindReading::Wind, the textures) have tests of their own here and in the plugin's suites.
#include "plugin/system_test_support.hpp"
#include "support/mesh_gen.hpp"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <gust/scene/animated_mesh.hpp>
#include <numeric>
#include <string>
#include <vector>

namespace gust::test {
namespace {

Vec3 to_api(glm::vec3 v) {
    return {v.x, v.y, v.z};
}
glm::vec3 from_api(Vec3 v) {
    return {v.x, v.y, v.z};
}
Mat4 to_api(const glm::mat4& m) {
    Mat4 out;
    std::copy_n(glm::value_ptr(m), 16, out.m);
    return out;
}
Mat4 at(glm::vec3 translation) {
    return to_api(glm::translate(glm::mat4(1.0f), translation));
}

/// A quad with corners a, b, c, d in order: two triangles, no thickness (a wall of one quad).
TestMesh quad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
    return {{a, b, c, d}, {0, 1, 2, 0, 2, 3}};
}

/// The meshes of `parts` as one mesh.
TestMesh joined(const std::vector<TestMesh>& parts) {
    TestMesh out;
    for (const TestMesh& m : parts) {
        const auto base = std::uint32_t(out.positions.size());
        out.positions.insert(out.positions.end(), m.positions.begin(), m.positions.end());
        for (const std::uint32_t i : m.indices)
            out.indices.push_back(base + i);
    }
    return out;
}

/// A room from lo to hi with a 1 x 1 m vent in the middle of its +x wall. Thin (`thickness` 0): its six
/// walls are single quads, the +x one four quads around the vent. Thick: boxes `thickness` deep inside the
/// room's outline, the +x one four boxes around the vent.
TestMesh vented_room(glm::vec3 lo, glm::vec3 hi, float thickness) {
    const glm::vec3 mid = 0.5f * (lo + hi);
    const float v0y = mid.y - 0.5f, v1y = mid.y + 0.5f, v0z = mid.z - 0.5f, v1z = mid.z + 0.5f;
    std::vector<TestMesh> parts;
    if (thickness == 0.0f) {
        const auto x_wall = [](float x, float y0, float y1, float z0, float z1) {
            return quad({x, y0, z0}, {x, y1, z0}, {x, y1, z1}, {x, y0, z1});
        };
        parts.push_back(x_wall(lo.x, lo.y, hi.y, lo.z, hi.z));
        parts.push_back(quad({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z}));
        parts.push_back(quad({lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}));
        parts.push_back(quad({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z}));
        parts.push_back(quad({lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}));
        parts.push_back(x_wall(hi.x, lo.y, v0y, lo.z, hi.z));
        parts.push_back(x_wall(hi.x, v1y, hi.y, lo.z, hi.z));
        parts.push_back(x_wall(hi.x, v0y, v1y, lo.z, v0z));
        parts.push_back(x_wall(hi.x, v0y, v1y, v1z, hi.z));
        return joined(parts);
    }
    const float t = thickness, x1 = hi.x - t;
    parts.push_back(box(lo, {lo.x + t, hi.y, hi.z}));
    parts.push_back(box(lo, {hi.x, lo.y + t, hi.z}));
    parts.push_back(box({lo.x, hi.y - t, lo.z}, hi));
    parts.push_back(box(lo, {hi.x, hi.y, lo.z + t}));
    parts.push_back(box({lo.x, lo.y, hi.z - t}, hi));
    parts.push_back(box({x1, lo.y, lo.z}, {hi.x, v0y, hi.z}));
    parts.push_back(box({x1, v1y, lo.z}, {hi.x, hi.y, hi.z}));
    parts.push_back(box({x1, v0y, lo.z}, {hi.x, v1y, v0z}));
    parts.push_back(box({x1, v0y, v1z}, {hi.x, v1y, hi.z}));
    return joined(parts);
}

/// Steps of the wall tests: 10 s of wind at dt 0.05 s, time for the fan's wind to reach the wall and pile
/// up against it many times over.
constexpr int kWallSteps = 200;

/// A directional emitter (a fan) at `position` blowing `strength` m/s along +x within `radius`.
WindEmitter fan(glm::vec3 position, float strength, float radius) {
    WindEmitter e;
    e.type = WindEmitterType::Directional;
    e.position = to_api(position);
    e.direction = {1.0f, 0.0f, 0.0f};
    e.radius = radius;
    e.strength = strength;
    return e;
}

/// A System with the validation layer on over `cells` cells of `cell_size` metres centred on `centre`.
class Physics : public ::testing::Test {
  protected:
    void create(glm::uvec3 cells, float cell_size, glm::vec3 centre, std::uint32_t voxels_per_cell = 4,
                const WindSettings& wind = {}) {
        SystemDesc desc = small_desc(watch_);
        for (int a = 0; a < 3; ++a)
            desc.domain.cells[a] = cells[a];
        desc.domain.cell_size = cell_size;
        desc.domain.voxels_per_cell = voxels_per_cell;
        desc.domain.focus = to_api(centre);
        desc.wind = wind;
        desc.wind.cycles_per_step =
            0; // every step solved to the tolerance: the references are converged flows
        const Outcome created = System::create(desc, system_);
        ASSERT_TRUE(created) << created.message();
    }
    void TearDown() override {
        system_.reset();
        EXPECT_EQ(watch_.errors, 0) << watch_.last;
    }
    /// A gust mesh of `m`'s positions and indices (a TestMesh, or a loaded Mesh).
    template <class Triangles> MeshId mesh(const Triangles& m, bool deforming = false) {
        MeshDesc desc;
        desc.positions = &m.positions[0].x;
        desc.vertex_count = std::uint32_t(m.positions.size());
        desc.indices = m.indices.data();
        desc.index_count = std::uint32_t(m.indices.size());
        desc.deforming = deforming;
        MeshId id = 0;
        const Outcome made = system_->create_mesh(desc, id);
        EXPECT_TRUE(made) << made.message();
        return id;
    }
    InstanceId place(const TestMesh& m, bool moving = false, const Mat4& transform = {}) {
        InstanceId id = 0;
        const Outcome placed = system_->create_instance(mesh(m), transform, moving, id);
        EXPECT_TRUE(placed) << placed.message();
        return id;
    }
    /// One step; the solve must have met its tolerance or left a residual under 1% of the divergence it
    /// started from, and never diverged.
    void step(float dt) {
        const Outcome stepped = system_->step(dt);
        ASSERT_TRUE(stepped) << stepped.message();
        const FrameStats& s = system_->stats();
        EXPECT_FALSE(s.diverged) << "frame " << s.frame;
        EXPECT_TRUE(s.converged || s.residual <= 1e-2f * s.divergence_before)
            << "frame " << s.frame << ": residual " << s.residual << " of " << s.divergence_before;
    }
    std::vector<glm::vec3> wind(const std::vector<glm::vec3>& points,
                                WindReading reading = WindReading::Solver) {
        std::vector<Vec3> in(points.size()), out(points.size());
        std::transform(points.begin(), points.end(), in.begin(), [](glm::vec3 p) { return to_api(p); });
        const Outcome asked = system_->query(in, out, reading);
        EXPECT_TRUE(asked) << asked.message();
        std::vector<glm::vec3> velocities(points.size());
        std::transform(out.begin(), out.end(), velocities.begin(), from_api);
        return velocities;
    }
    glm::vec3 wind(glm::vec3 point) { return wind(std::vector{point})[0]; }

    Watch watch_;
    std::unique_ptr<System> system_;
};

// Potential flow past a sphere of radius R in a uniform stream U: beside the equator, at distance r from
// the centre, the flow runs at U (1 + R^3 / (2 r^3)) (Lamb, Hydrodynamics, §92). Free-slip walls keep that
// speed-up step after step: 200 steps carry the air 40 m, past the sphere four times over.
TEST_F(Physics, aSphereInUniformFlowKeepsPotentialFlowsSpeedUpBesideItsEquator) {
    const float U = 4.0f, R = 4.0f;
    create({40, 24, 24}, 1.0f, glm::vec3(0.0f));
    place(icosphere(4, glm::vec3(0.0f), R));
    ASSERT_TRUE(system_->set_ambient({U, 0.0f, 0.0f}));
    for (int i = 0; i < 200; ++i)
        step(0.05f);
    for (const float r : {R + 0.6f, R + 1.5f, R + 2.5f}) {
        const float expected = U * (1.0f + R * R * R / (2.0f * r * r * r));
        for (const glm::vec3 side :
             {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0), glm::vec3(0, -1, 0)}) {
            const glm::vec3 u = wind(r * side);
            // The sphere is 8 cells across, and its 24 x 24-cell channel speeds all the air up by about 3%.
            EXPECT_NEAR(u.x, expected, 0.08f * U) << "r " << r << " side " << side.y << "," << side.z;
        }
    }
}

// Cells beside a wall carry their air (issue 42). Around a free-slip sphere of radius R = 4.2 m in 1 m cells
// of 4 voxels, potential flow (Lamb, Hydrodynamics, §92) runs at 0.8 U or more everywhere within 1 m outside
// the sphere and more than 35° off the wind's axis; behind the equator the real flow separates, and the
// wake's edge is slower. Before, 41 of the 265 cells whose centres lie within 1 m answered 0 m/s, and 17 % of
// those more than 35° off the axis under 0.3 U: a centre on the corner of a surface voxel counted as solid.
TEST_F(Physics, cellsBesideASphereAnswerTheirAirAndNotStillAir) {
    const float U = 4.0f, R = 4.2f;
    create({32, 20, 20}, 1.0f, glm::vec3(0.0f));
    place(icosphere(4, glm::vec3(0.0f), R));
    ASSERT_TRUE(system_->set_ambient({U, 0.0f, 0.0f}));
    for (int i = 0; i < 40; ++i)
        step(0.05f);
    std::vector<glm::vec3> centres;
    for (float z = -9.5f; z < 10.0f; z += 1.0f)
        for (float y = -9.5f; y < 10.0f; y += 1.0f)
            for (float x = -15.5f; x < 16.0f; x += 1.0f) {
                const glm::vec3 c(x, y, z);
                const float r = glm::length(c);
                if (r > R && r <= R + 1.0f && std::abs(c.x) < r * std::cos(glm::radians(35.0f)))
                    centres.push_back(c);
            }
    ASSERT_GT(centres.size(), 150u);
    const std::vector<glm::vec3> u = wind(centres, WindReading::Wind);
    float slowest_front = 1e9f, slowest = 1e9f;
    std::size_t slow = 0;
    for (std::size_t i = 0; i < centres.size(); ++i) {
        const float speed = glm::length(u[i]);
        slowest = std::min(slowest, speed);
        if (centres[i].x <= 0.0f) slowest_front = std::min(slowest_front, speed);
        slow += speed < 0.3f * U ? 1 : 0;
        EXPECT_GT(speed, 0.2f * U) << "cell at " << centres[i].x << ", " << centres[i].y << ", "
                                   << centres[i].z;
    }
    RecordProperty("cells", std::to_string(centres.size()));
    RecordProperty("under_0_3_U", std::to_string(slow));
    RecordProperty("slowest_front_over_U", std::to_string(slowest_front / U));
    RecordProperty("slowest_over_U", std::to_string(slowest / U));
    EXPECT_LE(slow, centres.size() / 20) << "cells under 0.3 U, of " << centres.size();
    EXPECT_GT(slowest_front, 0.6f * U) << "the sphere's front half, ahead of any separation";
}

// A bluff body (a cube) in a stream: the air stops at the middle of its front face (the stagnation point),
// runs faster than the stream past its sides, and turns back behind it in a recirculating wake (Martinuzzi
// and Tropea 1993 measure the wake of a cube at about one cube length).
TEST_F(Physics, aBoxStopsTheAirInFrontSpeedsItUpBesideAndRecirculatesItBehind) {
    const float U = 4.0f;
    create({40, 20, 20}, 1.0f, glm::vec3(0.0f));
    place(box(glm::vec3(-3.0f), glm::vec3(3.0f)));
    ASSERT_TRUE(system_->set_ambient({U, 0.0f, 0.0f}));
    for (int i = 0; i < 200; ++i)
        step(0.05f);
    EXPECT_LT(glm::length(wind({-3.5f, 0.0f, 0.0f})), 0.35f * U) << "stagnation in front";
    float beside = 0.0f;
    for (const float d : {3.5f, 4.5f, 5.5f})
        beside = std::max({beside, wind({0.0f, 0.0f, d}).x, wind({0.0f, d, 0.0f}).x});
    EXPECT_GT(beside, 1.15f * U) << "speed-up beside";
    float behind = U;
    for (float x = 3.5f; x <= 9.0f; x += 0.5f)
        behind = std::min(behind, wind({x, 0.0f, 0.0f}).x);
    EXPECT_LT(behind, 0.0f) << "the wake turns back";
}

// A square prism standing from the floor to the ceiling of a channel sheds a vortex street, a bluff body's
// wake at a Strouhal number f D / U of about 0.13 (Okajima 1982, J. Fluid Mech. 123: square cylinders,
// over a wide range of Reynolds numbers); a coarse grid's numerical viscosity moves it, so 0.10-0.20 is
// asked. Vorticity confinement (Fedkiw, Stam and Jensen 2001), on by default, puts back the swirl numerical
// diffusion takes; it must keep the street shedding without making the wake fast: its fastest air stays
// below twice the wind (issue 31 measured 2.2-2.4U behind a prism). The prism stands 0.15 m off the centre
// line, so that the street starts without waiting for rounding to break the symmetry; the lateral wind 3D
// behind it gives f.
TEST_F(Physics, aSquarePrismShedsAStreetOfVorticesWhoseAirStaysSlowerThanTwiceTheWind) {
    const float U = 4.0f, D = 3.0f, dt = 0.05f, x0 = -13.0f;
    create({48, 8, 40}, 1.0f, glm::vec3(0.0f));
    // A floor and a ceiling 6 m apart close the channel; the prism stands from one to the other.
    place(box({-30.0f, -6.0f, -25.0f}, {30.0f, -3.1f, 25.0f}));
    place(box({-30.0f, 3.1f, -25.0f}, {30.0f, 6.0f, 25.0f}));
    place(box({x0 - 0.5f * D, -3.5f, 0.15f - 0.5f * D}, {x0 + 0.5f * D, 3.5f, 0.15f + 0.5f * D}));
    ASSERT_TRUE(system_->set_ambient({U, 0.0f, 0.0f}));
    std::vector<glm::vec3> wake;
    for (float a = x0 + D; a < 22.0f; a += 0.5f)
        for (float b = -2.0f; b <= 2.0f; b += 2.0f)
            for (float c = -15.75f; c < 16.0f; c += 0.5f)
                wake.push_back({a, b, c});
    const glm::vec3 probe(x0 + 3.0f * D, 0.0f, 0.0f);
    constexpr int kSpinUp = 150, kSteps = 600;
    std::vector<float> lateral;
    float fastest = 0.0f;
    for (int i = 0; i < kSteps; ++i) {
        step(dt);
        if (i < kSpinUp) continue;
        lateral.push_back(wind(probe).z);
        if (i % 10 == 0)
            for (const glm::vec3& u : wind(wake))
                fastest = std::max(fastest, glm::length(u));
    }
    const float mean = std::accumulate(lateral.begin(), lateral.end(), 0.0f) / float(lateral.size());
    int crossings = 0, first = -1, last = -1;
    for (std::size_t i = 1; i < lateral.size(); ++i)
        if ((lateral[i - 1] - mean) * (lateral[i] - mean) < 0.0f) {
            ++crossings;
            if (first < 0) first = int(i);
            last = int(i);
        }
    const float swing =
        *std::max_element(lateral.begin(), lateral.end()) - *std::min_element(lateral.begin(), lateral.end());
    ASSERT_GE(crossings, 3) << "the wake sheds (lateral swing " << swing << " m/s)";
    const float strouhal = 0.5f * float(crossings - 1) / (float(last - first) * dt) * D / U;
    RecordProperty("strouhal", std::to_string(strouhal));
    RecordProperty("fastest_over_U", std::to_string(fastest / U));
    EXPECT_GT(swing, 0.5f * U) << "the street swings the air behind the prism from side to side";
    EXPECT_GT(strouhal, 0.10f);
    EXPECT_LT(strouhal, 0.20f);
    EXPECT_LT(fastest, 2.0f * U) << "fastest air in the wake";
}

// Uniform flow along a plane wall is an exact solution of the free-slip equations: nothing may slow the air
// beside the wall, however many steps pass. The wall is a long block entering through the upwind side (its
// inside touches no open side, so it is sealed), ending downstream at x = 6.
TEST_F(Physics, airAlongAWallKeepsItsSpeedStepAfterStep) {
    const float U = 4.0f;
    create({40, 20, 20}, 1.0f, glm::vec3(0.0f));
    place(box({-40.0f, -3.0f, -3.0f}, {6.0f, 3.0f, 3.0f}));
    ASSERT_TRUE(system_->set_ambient({U, 0.0f, 0.0f}));
    for (int i = 0; i < 200; ++i)
        step(0.05f);
    EXPECT_GT(system_->stats().sealed_cells, 100u) << "the block's inside is solid";
    for (float x = -16.0f; x <= -8.0f; x += 2.0f)
        for (const float d : {3.4f, 4.0f, 5.0f}) {
            EXPECT_NEAR(wind({x, 0.0f, d}).x, U, 0.03f * U) << "x " << x << ", " << d - 3.0f << " m out";
            EXPECT_NEAR(wind({x, -d, 0.0f}).x, U, 0.03f * U) << "x " << x << ", " << d - 3.0f << " m below";
        }
    EXPECT_LT(glm::length(wind({-10.0f, 0.0f, 0.0f})), 1e-4f) << "inside the block";
}

// A piston in a duct closed behind it pushes the air ahead as a plug: incompressible air in a tube of fixed
// section moves at the piston's speed (mass conservation). The space the piston leaves behind is sealed off
// (no air flows into it), so it is solid, not a pocket the pressure solve cannot satisfy.
TEST_F(Physics, aPistonInAClosedDuctMovesTheAirAtItsSpeed) {
    create({40, 12, 12}, 1.0f, glm::vec3(0.0f));
    for (const auto& [lo, hi] : {std::pair(glm::vec3(-17, 2, -3), glm::vec3(12, 3, 3)),
                                 std::pair(glm::vec3(-17, -3, -3), glm::vec3(12, -2, 3)),
                                 std::pair(glm::vec3(-17, -2, 2), glm::vec3(12, 2, 3)),
                                 std::pair(glm::vec3(-17, -2, -3), glm::vec3(12, 2, -2)),
                                 std::pair(glm::vec3(-17, -2, -2), glm::vec3(-16, 2, 2))})
        place(box(lo, hi));
    const float speed = 2.0f, dt = 0.05f;
    const InstanceId piston = place(box({0, -2, -2}, {1, 2, 2}), true, at({-14.0f, 0.0f, 0.0f}));
    for (int i = 1; i <= 40; ++i) {
        ASSERT_TRUE(system_->set_transform(piston, at({-14.0f + speed * dt * float(i), 0.0f, 0.0f})));
        step(dt);
        if (i < 10) continue;
        EXPECT_GT(system_->stats().sealed_cells, 0u) << "behind the piston";
        for (const glm::vec3 p :
             {glm::vec3(0.0f), glm::vec3(4.0f, 1.0f, -1.0f), glm::vec3(-4.0f, -1.2f, 0.8f)}) {
            const glm::vec3 u = wind(p);
            EXPECT_NEAR(u.x, speed, 0.1f * speed) << "step " << i << " at x " << p.x;
            EXPECT_LT(std::abs(u.y) + std::abs(u.z), 0.1f * speed) << "step " << i << " at x " << p.x;
        }
    }
}

// A closed box moving through still air is a rigid body: its inside moves with it (queries there answer
// its velocity), holds no air of its own, and pushes the air ahead of it; every step's solve converges.
TEST_F(Physics, aClosedBoxMovingThroughStillAirMovesItsInsideWithIt) {
    create({32, 16, 16}, 1.0f, glm::vec3(0.0f));
    const glm::vec3 velocity(3.0f, 0.0f, 0.0f);
    const float dt = 0.05f;
    const InstanceId crate = place(box(glm::vec3(-1.5f), glm::vec3(1.5f)), true, at({-8.0f, 0.0f, 0.0f}));
    for (int i = 1; i <= 60; ++i) {
        const glm::vec3 centre(-8.0f + velocity.x * dt * float(i), 0.0f, 0.0f);
        ASSERT_TRUE(system_->set_transform(crate, at(centre)));
        step(dt);
        EXPECT_TRUE(system_->stats().converged) << "step " << i;
        EXPECT_GT(system_->stats().sealed_cells, 0u) << "step " << i;
        // The first step has no last transform to move from: the box's motion counts from the second.
        const glm::vec3 expected = i == 1 ? glm::vec3(0.0f) : velocity;
        for (const glm::vec3 offset :
             {glm::vec3(0.0f), glm::vec3(0.7f, -0.6f, 0.5f), glm::vec3(-0.9f, 0.8f, -0.4f)})
            EXPECT_LT(glm::length(wind(centre + offset) - expected), 0.02f * velocity.x) << "step " << i;
        if (i > 5) {
            // Potential flow ahead of a moving sphere of radius R falls off as U (R/r)^3: about a third of
            // U 0.7 m ahead of this box's face; the mean over 0.5..1.5 m is well over a tenth.
            float ahead = 0.0f, behind = 0.0f;
            for (const float d : {0.5f, 1.0f, 1.5f})
                for (const glm::vec3 off : {glm::vec3(0.0f), glm::vec3(0.0f, 0.4f, -0.4f)}) {
                    ahead += wind(centre + off + glm::vec3(1.5f + d, 0.0f, 0.0f)).x / 6.0f;
                    behind += wind(centre + off - glm::vec3(1.5f + d, 0.0f, 0.0f)).x / 6.0f;
                }
            EXPECT_GT(ahead, 0.1f * velocity.x) << "step " << i << ": pushed ahead";
            EXPECT_GT(behind, 0.1f * velocity.x) << "step " << i << ": drawn along behind";
        }
    }
    EXPECT_LT(glm::length(wind({0.0f, 0.0f, 7.0f})), 0.5f) << "still air stays nearly still far to the side";
}

// A static building's inside is still air whatever brushes past it: a crate sliding along its wall,
// overlapping it by 0.1 m, gave the whole inside the crate's velocity (the one moving cell on the region's
// border set it). A crate sliding on a static floor, its bottom in the floor, still carries its inside.
TEST_F(Physics, theInsideOfAStaticBoxStaysStillWhileACrateSlidesAlongItsWallOrOnTheFloor) {
    create({32, 16, 16}, 1.0f, glm::vec3(0.0f));
    const glm::vec3 velocity(4.0f, 0.0f, 0.0f);
    const float dt = 0.05f;
    place(box(glm::vec3(-3.0f), glm::vec3(3.0f)));
    place(box({-16.0f, -8.0f, -8.0f}, {16.0f, -5.0f, 8.0f}));
    const InstanceId brushing = place(box(glm::vec3(-0.5f), glm::vec3(0.5f)), true, at({-8.0f, 0.0f, 3.4f}));
    const InstanceId sliding =
        place(box(glm::vec3(-1.5f), glm::vec3(1.5f)), true, at({-12.0f, -3.6f, -6.0f}));
    for (int i = 1; i <= 60; ++i) {
        const float x = velocity.x * dt * float(i);
        ASSERT_TRUE(system_->set_transform(brushing, at({-8.0f + x, 0.0f, 3.4f})));
        ASSERT_TRUE(system_->set_transform(sliding, at({-12.0f + x, -3.6f, -6.0f})));
        step(dt);
        EXPECT_TRUE(system_->stats().converged) << "step " << i;
        // Every 0.25 m through the inside, up to the voxels of the wall the crate overlaps (a point in the
        // wall's cell answered the whole cell's fragments, the crate's velocity).
        std::vector<glm::vec3> inside;
        for (float a = -2.625f; a < 2.7f; a += 0.25f)
            for (float b = -2.625f; b < 2.7f; b += 0.25f)
                for (float c = -2.625f; c < 2.7f; c += 0.25f)
                    inside.push_back({a, b, c});
        float fastest = 0.0f;
        for (const glm::vec3& u : wind(inside))
            fastest = std::max(fastest, glm::length(u));
        EXPECT_LT(fastest, 0.02f * velocity.x) << "step " << i;
        if (i > 1) {
            EXPECT_LT(glm::length(wind({-12.0f + x, -3.6f, -6.0f}) - velocity), 0.02f * velocity.x)
                << "step " << i << ": the sliding crate's inside";
        }
    }
}

// A crate moving inside a closed static building, its walls halfway through cells: the building's inside
// away from the crate stays still, and so does the air outside the building. The building's sealed inside
// took the crate's velocity (the only moving cells around it), and through cells holding both the outside
// air and the wall the faces pushed the outside air at 2.6 m/s.
TEST_F(Physics, aCrateMovingInsideAClosedStaticBuildingLeavesTheAirOutsideStill) {
    create({32, 16, 32}, 1.0f, glm::vec3(0.0f));
    place(box({-5.5f, -3.5f, -5.5f}, {6.5f, 4.5f, 6.5f}));
    const float speed = 2.0f, dt = 0.05f;
    float x = -2.5f;
    const InstanceId crate = place(box(glm::vec3(-1.0f), glm::vec3(1.0f)), true, at({x, 0.3f, 0.2f}));
    std::vector<glm::vec3> outside, far_inside;
    for (float a = -15.25f; a < 15.5f; a += 1.5f)
        for (float b = -7.25f; b < 7.5f; b += 1.5f)
            for (float c = -15.25f; c < 15.5f; c += 1.5f) {
                const bool in_building =
                    a > -5.75f && a < 6.75f && b > -3.75f && b < 4.75f && c > -5.75f && c < 6.75f;
                if (!in_building) outside.push_back({a, b, c});
            }
    for (float a = -4.75f; a < 5.9f; a += 0.5f)
        for (float b = -2.75f; b < 3.9f; b += 0.5f)
            far_inside.push_back({a, b, 4.5f});
    for (int i = 1; i <= 50; ++i) {
        x += speed * dt * (i <= 25 ? 1.0f : -1.0f);
        ASSERT_TRUE(system_->set_transform(crate, at({x, 0.3f, 0.2f})));
        step(dt);
        if (i == 1 || i == 26) continue; // the first step and the turn have no steady motion yet
        float fastest_outside = 0.0f, fastest_inside = 0.0f;
        for (const glm::vec3& u : wind(outside))
            fastest_outside = std::max(fastest_outside, glm::length(u));
        for (const glm::vec3& u : wind(far_inside))
            fastest_inside = std::max(fastest_inside, glm::length(u));
        EXPECT_LT(fastest_outside, 0.01f * speed) << "step " << i;
        EXPECT_LT(fastest_inside, 0.01f * speed)
            << "step " << i << ": the building's inside, away from the crate";
        EXPECT_LT(glm::length(wind({x, 0.3f, 0.2f}) - glm::vec3(i <= 25 ? speed : -speed, 0.0f, 0.0f)),
                  0.02f * speed)
            << "step " << i << ": the crate's own inside";
    }
}

// A crate's inside moves with it wherever its walls fall in the grid: walls filling the first voxel layer
// of a cell left the sealed cells beside them with no moving fragments of their own, and on every step the
// crate stood on whole metres its inside read 0.
TEST_F(Physics, aCratesInsideMovesWithItAtEveryPlaceInTheGrid) {
    create({32, 16, 16}, 1.0f, glm::vec3(0.0f));
    const float speed = 5.0f, dt = 0.05f;
    float x = -8.0f;
    const MeshId crate_mesh = mesh(box(glm::vec3(-1.25f), glm::vec3(1.25f)));
    InstanceId crate = 0;
    ASSERT_TRUE(system_->create_moving_instance(crate_mesh, at({x, 0.0f, 0.0f}),
                                                at({x - speed * dt, 0.0f, 0.0f}), crate));
    for (int i = 0; i < 40; ++i) {
        step(dt);
        EXPECT_LT(glm::length(wind({x, 0.0f, 0.0f}) - glm::vec3(speed, 0.0f, 0.0f)), 0.01f * speed)
            << "step " << i << " at x " << x;
        x += speed * dt;
        ASSERT_TRUE(system_->set_transform(crate, at({x, 0.0f, 0.0f})));
    }
}

// Incompressibility: the volume flux through any closed surface is zero (the divergence theorem). On the
// grid's face planes a query at a face centre reads that face's velocity, so the sum over a control box
// around an obstacle is the discrete flux and must cancel to within the solve's tolerance.
TEST_F(Physics, noAirIsMadeOrLostInsideAControlSurfaceAroundAnObstacle) {
    const float U = 4.0f;
    create({32, 16, 16}, 1.0f, glm::vec3(0.0f));
    place(box(glm::vec3(-2.0f), glm::vec3(2.0f)));
    ASSERT_TRUE(system_->set_ambient({U, 0.0f, 0.0f}));
    for (int i = 0; i < 60; ++i)
        step(0.05f);
    const int half = 6;
    double net = 0.0, inflow = 0.0;
    for (int a = 0; a < 3; ++a)
        for (const int side : {-1, 1}) {
            std::vector<glm::vec3> points;
            for (int i = -half; i < half; ++i)
                for (int j = -half; j < half; ++j) {
                    glm::vec3 p;
                    p[a] = float(side * half);
                    p[(a + 1) % 3] = float(i) + 0.5f;
                    p[(a + 2) % 3] = float(j) + 0.5f;
                    points.push_back(p);
                }
            for (const glm::vec3& u : wind(points)) {
                const double out = double(side) * u[a];
                net += out;
                if (out < 0.0) inflow -= out;
            }
        }
    EXPECT_GT(inflow, 0.9 * U * (2 * half) * (2 * half)) << "the stream enters through the upwind face";
    EXPECT_LT(std::abs(net), 1e-3 * inflow) << "net outflow " << net << " m^3/s of " << inflow;
}

// A teleport moves a solid without motion: flagged, the jump pushes no air at all; unflagged, the jump
// looks like a surface moving at 400 m/s, which the solid speed limit caps, and the wind stays bounded and
// settles. (Before the limit such a jump drove the wind to 9e8 m/s.)
TEST_F(Physics, aTeleportPushesNoAirAndAnUnflaggedJumpStaysBounded) {
    const float U = 2.0f, dt = 0.05f;
    float flagged_peak = 0.0f;
    // The jump's step: at dt a 20 m jump looks like 400 m/s; at 1e-4 s like 2e5 m/s, beyond what half
    // floats (the fragment list's velocities) hold.
    for (const auto& [flagged, jump_dt] :
         {std::pair{true, dt}, std::pair{false, dt}, std::pair{false, 1e-4f}}) {
        SCOPED_TRACE(jump_dt);
        create({32, 16, 16}, 1.0f, glm::vec3(0.0f));
        const InstanceId crate =
            place(box(glm::vec3(-1.0f), glm::vec3(1.0f)), true, at({-10.0f, 0.0f, 0.0f}));
        ASSERT_TRUE(system_->set_ambient({U, 0.0f, 0.0f}));
        for (int i = 0; i < 10; ++i)
            step(dt);
        ASSERT_TRUE(system_->set_transform(crate, at({10.0f, 0.0f, 0.0f}), flagged));
        std::vector<glm::vec3> points;
        for (float x = -14.0f; x <= 14.0f; x += 1.0f)
            for (float z = -6.0f; z <= 6.0f; z += 1.5f)
                points.push_back({x, 0.3f, z});
        float peak = 0.0f;
        for (int i = 0; i < 30; ++i) {
            step(i == 0 ? jump_dt : dt);
            for (const glm::vec3& u : wind(points))
                peak = std::max(peak, glm::length(u));
        }
        const float settled = glm::length(wind({0.0f, 0.0f, 6.0f}) - glm::vec3(U, 0.0f, 0.0f));
        if (flagged) {
            flagged_peak = peak;
            EXPECT_LT(peak, 2.0f * U) << "a teleport pushes no air";
        } else {
            // Inside the box the wind is the box's own velocity, clamped to the limit (50 m/s); air pushed
            // round it runs at most half as fast again.
            EXPECT_LE(peak, 1.5f * 50.0f) << "the solid speed limit bounds the push";
            EXPECT_GT(peak, flagged_peak) << "an unflagged jump does push";
        }
        EXPECT_LT(settled, 0.5f * U) << (flagged ? "flagged" : "unflagged") << ": the wind settles again";
    }
}

// A rigid body turning far each frame: a 1 m cube tumbling 1.9 rad a frame about a tilted axis in still air,
// its corners at up to 75 m/s, clamped to the 50 m/s solid speed limit. A rigid motion keeps the body's
// volume, so the air it stirs runs about as fast as its clamped surface at most. Taken along the chords
// from last frame's places, its surface converged (it drew about 140 m³/s into itself) and drove the air
// to 200–470 m/s.
TEST_F(Physics, aCubeTumblingFarEachFrameStirsTheAirNoFasterThanItsSurface) {
    create({16, 16, 16}, 0.5f, glm::vec3(0.0f));
    InstanceId tumbler = 0;
    ASSERT_TRUE(system_->create_instance(mesh(box(glm::vec3(-0.5f), glm::vec3(0.5f))), {}, true, tumbler));
    const glm::vec3 axis = glm::normalize(glm::vec3(0.3f, 0.7f, -0.5f));
    std::vector<glm::vec3> points;
    for (float x = -3.0f; x <= 3.0f; x += 0.5f)
        for (float y = -3.0f; y <= 3.0f; y += 0.5f)
            for (float z = -3.0f; z <= 3.0f; z += 0.5f)
                points.push_back({x, y, z});
    float peak = 0.0f;
    for (int frame = 1; frame <= 40; ++frame) {
        ASSERT_TRUE(
            system_->set_transform(tumbler, to_api(glm::rotate(glm::mat4(1.0f), 1.9f * float(frame), axis))));
        step(0.02f);
        for (const glm::vec3& u : wind(points))
            peak = std::max(peak, glm::length(u));
    }
    EXPECT_GT(peak, 5.0f) << "the cube stirs the air";
    EXPECT_LE(peak, 1.2f * 50.0f);
}

// A skinned character walking round a hut for 1,000 frames: its limbs close and open pockets of air against
// the walls and the ground every few frames (the sample's frame-79 blow-up was one), and its clip wraps
// every 2 s. Every solve stays bounded: converged or within 1% of its divergence, never diverged, and the
// wind near the character stays at the speeds of wind and walk.
TEST_F(Physics, aSkinnedCharacterWalksAThousandFramesWithABoundedResidual) {
    create({24, 12, 24}, 0.5f, glm::vec3(0.0f, 2.0f, 0.0f), 2);
    auto walker = AnimatedMesh::load(GUST_ASSETS_DIR "/characters/CesiumMan.glb");
    ASSERT_TRUE(walker) << walker.message();
    const MeshId body = mesh(walker->rest_pose(), true);
    ASSERT_NE(body, 0u);
    InstanceId instance = 0;
    ASSERT_TRUE(system_->create_instance(body, {}, true, instance));
    place(box({-8.0f, -1.0f, -8.0f}, {8.0f, 0.0f, 8.0f}));
    place(box({-1.0f, 0.0f, -1.0f}, {1.0f, 2.5f, 1.0f}));
    ASSERT_TRUE(system_->set_ambient({3.0f, 0.0f, 1.0f}));
    const float dt = 1.0f / 30.0f, radius = 1.35f;
    const double duration = walker->clip_duration(0);
    std::vector<glm::vec3> posed;
    double last_lap = 0.0;
    for (int frame = 0; frame < 1000; ++frame) {
        const float t = float(frame) * dt, angle = 0.6f * t;
        const glm::vec3 where(radius * std::cos(angle), 0.0f, radius * std::sin(angle));
        // CesiumMan's posed vertices stand y-up (its joints carry the file's z-up turn); face it along its
        // path.
        const glm::mat4 model =
            glm::rotate(glm::translate(glm::mat4(1.0f), where), -angle, glm::vec3(0, 1, 0));
        walker->pose(0, t, true, posed);
        const double lap = std::floor(t / duration);
        ASSERT_TRUE(
            system_->set_vertices(body, &posed[0].x, std::uint32_t(posed.size()), 12, lap != last_lap));
        last_lap = lap;
        ASSERT_TRUE(system_->set_transform(instance, to_api(model)));
        step(dt);
        if (frame % 50 == 0) {
            for (const glm::vec3& u :
                 wind({where + glm::vec3(0.4f, 1.0f, 0.0f), where + glm::vec3(0.0f, 0.3f, 0.4f)}))
                EXPECT_LT(glm::length(u), 12.0f) << "frame " << frame;
        }
    }
}

// Nothing crosses a closed face. A wall of one quad spans the whole section of a channel, and a fan blows
// 8 m/s at it from 4 m in front, with the game's defaults (MacCormack, vorticity confinement 0.2): the air
// behind the wall has no way to move (the projection alone keeps it exactly still), so after many steps it
// must still be still, wherever the wall lies within its cell. The backtrace, the velocity extension,
// confinement and the reported velocity each carried the front's wind through the wall (up to 3.4 m/s
// behind it after 200 steps; issue 31).
TEST_F(Physics, aWallOfOneQuadKeepsAFansWindInFrontOfItAtEveryOffset) {
    for (const float offset : {0.1f, 0.45f, 0.8f}) {
        SCOPED_TRACE(offset);
        create({32, 16, 16}, 1.0f, glm::vec3(0.0f));
        const float x = 2.0f + offset;
        place(quad({x, -9.0f, -9.0f}, {x, 9.0f, -9.0f}, {x, 9.0f, 9.0f}, {x, -9.0f, 9.0f}));
        const WindEmitter blower = fan({x - 4.0f, 0.0f, 0.0f}, 8.0f, 3.0f);
        ASSERT_TRUE(system_->set_emitters({&blower, 1}));
        // The goal holds after 500 steps: 25 s of the fan's wind piling up against the wall.
        for (int i = 0; i < 500; ++i)
            step(0.05f);
        std::vector<glm::vec3> behind;
        for (float a = x + 1.25f; a < 16.0f; a += 0.5f)
            for (float b = -7.75f; b < 8.0f; b += 1.0f)
                for (float c = -7.75f; c < 8.0f; c += 1.0f)
                    behind.push_back({a, b, c});
        float fastest = 0.0f;
        for (const glm::vec3& u : wind(behind))
            fastest = std::max(fastest, glm::length(u));
        RecordProperty("behind_at_" + std::to_string(offset), std::to_string(fastest));
        EXPECT_GT(glm::length(wind({x - 2.0f, 0.0f, 0.0f})), 2.0f) << "the fan blows at the wall";
        EXPECT_LT(fastest, 0.2f) << "behind the wall";
    }
}

// A room of single-quad walls with a 1 x 1 m vent in its lee wall, in an 8 m/s wind: the inside fills only
// through the vent, on the lee side where the air is slow, so away from the walls it stays nearly still.
// Through the walls themselves the air inside reached 1.55 m/s mean (issue 31). Walls thicker than a cell
// must hold alike.
TEST_F(Physics, aVentedRoomOfThinOrThickWallsKeepsItsInsideCalmInAStrongWind) {
    const glm::vec3 lo(-4.3f, -3.3f, -4.4f), hi(4.4f, 3.3f, 4.3f);
    for (const float thickness : {0.0f, 1.5f}) {
        SCOPED_TRACE(thickness);
        create({32, 16, 24}, 1.0f, glm::vec3(0.0f));
        place(vented_room(lo, hi, thickness));
        ASSERT_TRUE(system_->set_ambient({8.0f, 0.0f, 0.0f}));
        for (int i = 0; i < kWallSteps; ++i)
            step(0.05f);
        std::vector<glm::vec3> inside;
        const glm::vec3 from = lo + glm::vec3(thickness + 1.0f), to = hi - glm::vec3(thickness + 1.0f);
        for (float a = from.x; a <= to.x; a += 0.5f)
            for (float b = from.y; b <= to.y; b += 0.5f)
                for (float c = from.z; c <= to.z; c += 0.5f)
                    inside.push_back({a, b, c});
        double sum = 0.0;
        for (const glm::vec3& u : wind(inside))
            sum += glm::length(u);
        RecordProperty("inside_" + std::to_string(thickness), std::to_string(sum / double(inside.size())));
        EXPECT_LT(sum / double(inside.size()), 0.25) << "mean speed inside, 1 m from the walls";
        EXPECT_GT(wind({0.0f, 0.0f, hi.z + 6.0f}).x, 6.0f) << "the wind blows past the room";
    }
}

// A moving wall holds alike. A door of one quad, hinged about z 2 m beyond the channel's -y side and
// reaching 2 m past its +y side (so at every angle it closes the section), swings +-0.04 rad with a period
// of 8 s while a fan blows 8 m/s at it. The air behind it moves only as the door pushes it: potential flow
// driven by the door, whose fastest point in the channel (18 m from the hinge) moves at 18 * 0.04 * 2 pi /
// 8 = 0.57 m/s, so nowhere more than a cell behind the door's farthest reach may the air run faster than
// that, with a quarter more for the grid. Where the door crossed a cell's middle, the cell's faces kept
// the other side's wind, and the air behind reached 1.30 m/s.
TEST_F(Physics, aDoorOfOneQuadSwingingInAFansWindPushesTheAirBehindItNoFasterThanItMoves) {
    create({32, 16, 16}, 1.0f, glm::vec3(0.0f));
    const glm::vec3 hinge(2.45f, -10.0f, 0.0f);
    const float amplitude = 0.04f, period = 8.0f, reach = 20.0f, dt = 0.05f;
    const auto door_at = [&](float t) {
        const float angle = amplitude * std::sin(2.0f * glm::pi<float>() * t / period);
        return to_api(
            glm::rotate(glm::translate(glm::mat4(1.0f), hinge), angle, glm::vec3(0.0f, 0.0f, 1.0f)));
    };
    const TestMesh leaf =
        quad({0.0f, 0.0f, -9.0f}, {0.0f, reach, -9.0f}, {0.0f, reach, 9.0f}, {0.0f, 0.0f, 9.0f});
    const InstanceId door = place(leaf, true, door_at(0.0f));
    const WindEmitter blower = fan({hinge.x - 4.0f, 0.0f, 0.0f}, 8.0f, 3.0f);
    ASSERT_TRUE(system_->set_emitters({&blower, 1}));
    for (int i = 1; i <= kWallSteps; ++i) {
        ASSERT_TRUE(system_->set_transform(door, door_at(dt * float(i))));
        step(dt);
    }
    const float swing = amplitude * (reach - 2.0f); // the farthest the door reaches inside the channel
    std::vector<glm::vec3> behind;
    for (float a = hinge.x + swing + 1.25f; a < 16.0f; a += 0.5f)
        for (float b = -7.75f; b < 8.0f; b += 1.0f)
            for (float c = -7.75f; c < 8.0f; c += 1.0f)
                behind.push_back({a, b, c});
    float fastest = 0.0f;
    for (const glm::vec3& u : wind(behind))
        fastest = std::max(fastest, glm::length(u));
    RecordProperty("behind", std::to_string(fastest));
    EXPECT_GT(glm::length(wind({hinge.x - 2.0f, 0.0f, 0.0f})), 2.0f) << "the fan blows at the door";
    const float door_speed = (reach - 2.0f) * amplitude * 2.0f * glm::pi<float>() / period;
    EXPECT_LT(fastest, 1.25f * door_speed) << "behind the door";
}

} // namespace
} // namespace gust::test
