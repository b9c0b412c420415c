// The shared per-cell kernels on their own, and every solver pass on the CPU (same kernels, host
// arrays) against the GPU on small grids (16^3, and one with odd sides) with static and moving solids,
// over two steps (the second with the warm-started pressure solve).
#include "solver/solid_world.hpp"
#include "solver/solver_cells.h"
#include "solver/solver_math.h"
#include "support/gpu_env.hpp"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <gust/solver/cpu_wind.hpp>
#include <limits>
#include <random>

namespace gust::test {
namespace {

using namespace shaderio;

CellBits layers(std::uint32_t v, CellBits (&faces)[6]) {
    for (std::uint32_t s = 0; s < 6; ++s)
        faces[s] = bits_layer(s / 2, (s & 1) ? v - 1 : 0, v);
    return bits_all(v);
}

TEST(CellKernels, partsAreTheTwoSidesOfAWallThroughTheCellLargerFirst) {
    for (std::uint32_t v : {4u, 5u, 8u}) {
        CellBits faces[6];
        layers(v, faces);
        const CellBits wall = bits_layer(0, 1, v); // voxels with x == 1
        CellBits first, second;
        cell_parts(wall, v, faces, first, second);
        EXPECT_EQ(bits_count(first), (v - 2) * v * v) << "v " << v;
        EXPECT_FALSE(bits_touch(first, faces, 0)) << "the x = 0 side is cut off";
        EXPECT_EQ(bits_count(bits_and(first, faces[1])), v * v);
        EXPECT_TRUE(bits_equal(second, bits_layer(0, 0, v))) << "the smaller side is the x = 0 layer";
    }
}

TEST(CellKernels, anEmptyCellIsOneWholePartAndAFullOneHasNone) {
    CellBits faces[6];
    const CellBits all = layers(4, faces);
    CellBits first, second;
    cell_parts(bits_none(), 4, faces, first, second);
    EXPECT_TRUE(bits_equal(first, all));
    EXPECT_EQ(bits_count(second), 0u);
    cell_parts(all, 4, faces, first, second);
    EXPECT_EQ(bits_count(first) + bits_count(second), 0u);
}

TEST(CellKernels, aCellOfThreePiecesKeepsTheTwoLargest) {
    CellBits faces[6];
    layers(8, faces);
    // Walls at x == 1 and x == 4 leave pieces of 1, 2 and 3 layers.
    const CellBits walls = bits_or(bits_layer(0, 1, 8), bits_layer(0, 4, 8));
    CellBits first, second;
    cell_parts(walls, 8, faces, first, second);
    EXPECT_EQ(bits_count(first), 3u * 64u);
    EXPECT_TRUE(bits_touch(first, faces, 1));
    EXPECT_EQ(bits_count(second), 2u * 64u);
    EXPECT_FALSE(bits_touch(second, faces, 0) || bits_touch(second, faces, 1)) << "the middle piece";
}

// Cells of up to 64 voxels take the two-word fill; it must pick the same components as the general one,
// ties included, on cells whose free voxels split into many pieces.
TEST(CellKernels, twoWordFillMatchesTheGeneralFill) {
    std::mt19937 random(7);
    for (std::uint32_t v : {1u, 2u, 3u, 4u}) {
        CellBits faces[6];
        const CellBits all = layers(v, faces);
        for (int trial = 0; trial < 400; ++trial) {
            const std::uint32_t percent = std::uniform_int_distribution<std::uint32_t>(0, 100)(random);
            CellBits occupied = bits_none();
            for (std::uint32_t i = 0; i < v * v * v; ++i)
                if (std::uniform_int_distribution<std::uint32_t>(0, 99)(random) < percent)
                    occupied.w[i / 32] |= 1u << (i % 32);
            CellBits small[2], general[2];
            cell_parts_small(occupied, v, faces, small[0], small[1]);
            cell_parts_general(occupied, v, faces, general[0], general[1]);
            for (int part = 0; part < 2; ++part) {
                ASSERT_TRUE(bits_equal(small[part], general[part]))
                    << "v " << v << ", trial " << trial << ", " << percent << "%, part " << part;
                ASSERT_TRUE(bits_equal(bits_and(small[part], all), small[part]));
            }
            ASSERT_GE(bits_count(small[0]), bits_count(small[1]));
            ASSERT_EQ(bits_count(bits_and(small[0], small[1])), 0u);
        }
    }
}

TEST(CellKernels, solidSpeedIsClampedByLengthAndADivergedSolveIsCaught) {
    EXPECT_EQ(clamp_speed(vec3(3.0f, 4.0f, 0.0f), 10.0f), vec3(3.0f, 4.0f, 0.0f));
    const vec3 clamped = clamp_speed(vec3(30.0f, 40.0f, 0.0f), 10.0f);
    EXPECT_NEAR(length(clamped), 10.0f, 1e-5f);
    EXPECT_NEAR(clamped.x / clamped.y, 0.75f, 1e-6f) << "the direction is kept";
    EXPECT_FALSE(solve_diverged(5.0f, 1.0f, 0.5f)) << "a few times its start is a wandering residual";
    EXPECT_TRUE(solve_diverged(6.7e3f, 0.1f, 0.86f)) << "the sample's frame 79";
    EXPECT_TRUE(solve_diverged(std::numeric_limits<float>::quiet_NaN(), 1.0f, 1.0f));
}

TEST(CellKernels, faceFractionCountsVoxelPairsOpenOnBothSides) {
    CellBits faces[6];
    const CellBits all = layers(4, faces);
    EXPECT_EQ(face_open_fraction(all, all, 1, 4, faces), 1.0f);
    // Block the low cell's top layer (y == 3) for x < 2: half the y face closes.
    CellBits low = all;
    for (std::uint32_t z = 0; z < 4; ++z)
        for (std::uint32_t x = 0; x < 2; ++x) {
            const std::uint32_t i = x + 4 * (3 + 4 * z);
            low.w[i / 32] &= ~(1u << (i % 32));
        }
    EXPECT_EQ(face_open_fraction(low, all, 1, 4, faces), 0.5f);
    EXPECT_EQ(face_open_fraction(low, all, 0, 4, faces), 1.0f) << "x faces of the cell are untouched";
}

TEST(CellKernels, emitterProfilesPointWhereTheirTypeSays) {
    GpuEmitter e{};
    e.position = vec3(0.0f);
    e.direction = vec3(0, 0, 1);
    e.radius = 2.0f;
    e.strength = 3.0f;
    e.falloff = 1.0f;
    e.type = kEmitterOmni;
    EXPECT_GT(emitter_velocity(e, vec3(1, 0, 0)).x, 0.0f) << "omni pushes out";
    e.strength = -3.0f;
    EXPECT_LT(emitter_velocity(e, vec3(1, 0, 0)).x, 0.0f) << "negative omni pulls in";
    EXPECT_EQ(emitter_velocity(e, vec3(3, 0, 0)), vec3(0.0f)) << "nothing beyond the radius";
    e.strength = 3.0f;
    e.type = kEmitterVortex;
    EXPECT_GT(emitter_velocity(e, vec3(1, 0, 0)).y, 0.0f) << "right-handed about +z";
    EXPECT_NEAR(emitter_velocity(e, vec3(1, 0, 0)).x, 0.0f, 1e-6f);
    e.type = kEmitterCone;
    e.extent = 4.0f;
    EXPECT_EQ(emitter_velocity(e, vec3(0, 0, -1)), vec3(0.0f)) << "nothing behind a cone's tip";
    EXPECT_GT(emitter_velocity(e, vec3(0.1f, 0, 3)).z, 0.0f);
    EXPECT_EQ(emitter_velocity(e, vec3(1.5f, 0, 1)), vec3(0.0f)) << "outside the cone at that depth";
    EXPECT_EQ(emitter_drive(5.0f, 3.0f, 0.5f), 5.0f) << "air already faster is left alone";
    EXPECT_EQ(emitter_drive(1.0f, 3.0f, 0.5f), 2.0f);
}

struct PassCase {
    const char* name;
    Advection advection;
    float vorticity;
    float viscosity;
    PressureSolver pressure;
    bool emitters;
    std::uint32_t voxels_per_cell = 4; ///< 3: cells straddle the tree's 4-voxel bricks; 5: wide voxel sets
    glm::uvec3 cells{16, 16, 16};      ///< odd sides: rows of one colour differ, faces not a multiple of 4
};

class CpuMatchesGpu : public GpuTestWithParam<PassCase> {};

TEST_P(CpuMatchesGpu, onASmallGridWithSolids) {
    const PassCase& pass = GetParam();
    SolverDesc desc;
    desc.cells = pass.cells;
    desc.advection = pass.advection;
    desc.vorticity = pass.vorticity;
    desc.viscosity = pass.viscosity;
    desc.pressure = pass.pressure;
    desc.voxels_per_cell = pass.voxels_per_cell;
    desc.tolerance = pass.pressure == PressureSolver::Jacobi ? 1e-3f : 1e-5f;
    auto gpu_created = WindSolver::create(ctx(), desc);
    ASSERT_TRUE(gpu_created) << gpu_created.message();
    auto cpu_created = CpuWind::create(desc);
    ASSERT_TRUE(cpu_created) << cpu_created.message();
    WindSolver& gpu = **gpu_created;
    CpuWind& cpu = **cpu_created;

    SolidWorld solids(ctx(), desc);
    const float dt = 0.1f;
    // The moving box's foot sinks into a static slab: cells where both lie push only with the pairs that
    // touch no static voxel (moving_share).
    solids.update({{icosphere(2, {5.2f, 7.9f, 8.3f}, 2.6f), glm::mat4(1.0f), std::nullopt},
                   {box({0.6f, 2.2f, 0.7f}, {15.3f, 4.3f, 15.4f}), glm::mat4(1.0f), std::nullopt},
                   {box({9.3f, 4.1f, 4.4f}, {12.6f, 11.2f, 10.7f}),
                    glm::translate(glm::mat4(1.0f), {0.2f, 0.1f, 0.0f}), glm::mat4(1.0f)}},
                  dt);
    const glm::vec3 ambient(2.0f, 0.5f, 0.0f);
    for (auto set : {gpu.set_ambient(ambient), cpu.set_ambient(ambient)})
        ASSERT_TRUE(set);
    if (pass.emitters) {
        const Emitter emitters[] = {
            {EmitterType::Directional, {4, 4, 4}, {0, 1, 0}, 3.0f, 5.0f, 1.0f, 0.0f},
            {EmitterType::Omni, {12, 12, 12}, {1, 0, 0}, 3.0f, -4.0f, 2.0f, 0.0f},
            {EmitterType::Vortex, {8, 12, 4}, {1, 0, 0}, 3.0f, 4.0f, 0.5f, 0.0f},
            {EmitterType::CapsuleMotor, {2, 13, 2}, {0, 0, 1}, 1.5f, 6.0f, 1.0f, 10.0f},
            {EmitterType::ConeMotor, {14, 2, 2}, {0, 0, 1}, 3.0f, 6.0f, 0.0f, 10.0f}};
        for (auto set : {gpu.set_emitters(emitters), cpu.set_emitters(emitters)})
            ASSERT_TRUE(set);
    }
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> d(-2.0f, 2.0f);
    std::vector<float> field(gpu.face_count());
    for (float& v : field)
        v = d(rng);
    for (auto set : {gpu.set_velocity(field), cpu.set_velocity(field)})
        ASSERT_TRUE(set);

    const SolidSource source = solids.source();
    const CpuSolid host_solid = solids.cpu();
    // Two steps: the second starts its pressure solve from the first one's (the warm start).
    for (int step = 0; step < 2; ++step) {
        auto gs = gpu.step(dt, &source);
        ASSERT_TRUE(gs) << gs.message();
        auto cs = cpu.step(dt, &host_solid);
        ASSERT_TRUE(cs) << cs.message();
        EXPECT_EQ(gs->cut_cells, cs->cut_cells);
        EXPECT_EQ(gs->fluid_cells, cs->fluid_cells);
        EXPECT_EQ(gs->sealed_cells, cs->sealed_cells);
        // On 16^3 the closed box and sphere lie inside the domain, so their insides are sealed; the odd
        // grid cuts both open at its sides.
        if (pass.cells == glm::uvec3(16)) {
            EXPECT_GT(gs->sealed_cells, 0u) << "the box and sphere have insides";
        }
        EXPECT_EQ(gs->moving_fragments, cs->moving_fragments);
        EXPECT_GT(gs->cut_cells, 0u);
        EXPECT_TRUE(gs->converged && cs->converged) << "step " << step;
        EXPECT_NEAR(gs->divergence_before, cs->divergence_before, 1e-4 * cs->divergence_before)
            << "step " << step;
    }

    auto expect_close = [](const std::vector<float>& a, const std::vector<float>& b, float tolerance,
                           const char* what) {
        ASSERT_EQ(a.size(), b.size()) << what;
        const auto finite = [](float v) { return std::isfinite(v); };
        EXPECT_TRUE(std::all_of(a.begin(), a.end(), finite)) << what << ": the GPU's is not finite";
        EXPECT_TRUE(std::all_of(b.begin(), b.end(), finite)) << what << ": the CPU's is not finite";
        float scale = 0.0f, worst = 0.0f;
        std::size_t at = 0;
        for (std::size_t i = 0; i < a.size(); ++i) {
            scale = std::max(scale, std::abs(b[i]));
            if (std::abs(a[i] - b[i]) > worst) {
                worst = std::abs(a[i] - b[i]);
                at = i;
            }
        }
        EXPECT_LE(worst, tolerance * std::max(scale, 1.0f))
            << what << ": worst at " << at << " gpu " << a[at] << " cpu " << b[at];
    };
    auto open = gpu.read_open_fraction();
    auto solid_velocity = gpu.read_solid_velocity();
    auto solid_fraction = gpu.read_solid_fraction();
    auto velocity = gpu.read_velocity();
    auto pressure = gpu.read_pressure();
    ASSERT_TRUE(open && solid_velocity && solid_fraction && velocity && pressure);
    const std::vector<float> cpu_open(cpu.open_fraction().begin(),
                                      cpu.open_fraction().begin() + std::ptrdiff_t(open->size()));
    expect_close(*open, cpu_open, 0.0f, "open fraction");
    expect_close(*solid_fraction, cpu.solid_fraction(), 0.0f, "solid fraction");
    expect_close(*solid_velocity, cpu.solid_velocity(), 1e-5f, "solid velocity");
    expect_close(*velocity, cpu.velocity(), 2e-3f, "velocity");
    expect_close(*pressure, cpu.pressure(), 2e-3f, "pressure");
}

INSTANTIATE_TEST_SUITE_P(
    Passes, CpuMatchesGpu,
    ::testing::Values(
        PassCase{"conjugateGradients", Advection::None, 0.0f, 0.0f, PressureSolver::MultigridPCG, false},
        PassCase{"solidAndProjection", Advection::None, 0.0f, 0.0f, PressureSolver::Multigrid, false},
        PassCase{"semiLagrangian", Advection::SemiLagrangian, 0.0f, 0.0f, PressureSolver::Multigrid, false},
        PassCase{"macCormack", Advection::MacCormack, 0.0f, 0.0f, PressureSolver::Multigrid, false},
        PassCase{"emitters", Advection::None, 0.0f, 0.0f, PressureSolver::Multigrid, true},
        PassCase{"vorticity", Advection::None, 0.5f, 0.0f, PressureSolver::Multigrid, false},
        PassCase{"viscosity", Advection::None, 0.0f, 0.2f, PressureSolver::Multigrid, false},
        // α·sum passes a float's range: the Jacobi step must give the neighbours' mean, not inf / inf.
        PassCase{"hugeViscosity", Advection::None, 0.0f, 3e38f, PressureSolver::Multigrid, false},
        PassCase{"jacobi", Advection::None, 0.0f, 0.0f, PressureSolver::Jacobi, false},
        PassCase{"cellsAcrossBricks", Advection::None, 0.0f, 0.0f, PressureSolver::Multigrid, false, 3},
        // Over 4^3 voxels a cell: the voxel-set passes' sixteen-word build (solver_io.h, kBitsWords).
        PassCase{"wideVoxelSets", Advection::MacCormack, 0.0f, 0.0f, PressureSolver::Multigrid, false, 5},
        PassCase{"oddSides",
                 Advection::SemiLagrangian,
                 0.3f,
                 0.0f,
                 PressureSolver::MultigridPCG,
                 true,
                 4,
                 {15, 9, 11}},
        PassCase{"everything", Advection::MacCormack, 0.3f, 0.05f, PressureSolver::MultigridPCG, true}),
    [](const ::testing::TestParamInfo<PassCase>& param) { return std::string(param.param.name); });

} // namespace
} // namespace gust::test
