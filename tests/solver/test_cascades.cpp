// Two cascades of one focus, coupled (WindSolver::couple, docs/solver.md "Cascades"): the finer takes the
// coarser one's wind beyond its grid, the coarser takes the finer one's wind where it covers it, the mass
// through the finer one's border matches the coarser one's through the same surface, and the answer has no
// seam at the border. Small grids: lavapipe runs them in CI.
#include "solver/solver_math.h"
#include "support/gpu_env.hpp"

#include <array>
#include <cmath>
#include <glm/gtx/component_wise.hpp>
#include <gtest/gtest.h>
#include <gust/solver/wind_solver.hpp>

namespace gust::test {
namespace {

using shaderio::face_index;

class CascadeTest : public GpuTest {};

/// The nest every test uses: a coarse grid of 16x8x16 cells of 2 m and a fine one of 16x8x16 cells of 1 m,
/// both centred on (16, 8, 16).
struct Nest {
    std::unique_ptr<WindSolver> coarse, fine;
    static constexpr glm::vec3 centre{16.0f, 8.0f, 16.0f};

    Nest(gpu::Context& ctx, bool coupled, PassLayout layout = PassLayout::Auto) {
        SolverDesc d;
        d.cells = {16, 8, 16};
        d.layout = layout;
        d.cell_size = 2.0f;
        d.origin = centre - 0.5f * glm::vec3(d.cells) * d.cell_size;
        auto c = WindSolver::create(ctx, d);
        EXPECT_TRUE(c) << c.message();
        d.cell_size = 1.0f;
        d.origin = centre - 0.5f * glm::vec3(d.cells) * d.cell_size;
        auto f = WindSolver::create(ctx, d);
        EXPECT_TRUE(f) << f.message();
        if (!c || !f) return;
        coarse = std::move(*c);
        fine = std::move(*f);
        if (coupled) {
            EXPECT_TRUE(coarse->couple(nullptr, fine.get()));
            EXPECT_TRUE(fine->couple(coarse.get(), nullptr));
        }
    }
    /// The coarse cascade steps every second frame with twice the step, as a ratio of 2 has it.
    void run(int frames, float dt) {
        for (int i = 0; i < frames; ++i) {
            if (i % 2 == 0) {
                auto s = coarse->step(2.0f * dt);
                ASSERT_TRUE(s) << s.message();
                EXPECT_FALSE(s->diverged);
            }
            auto s = fine->step(dt);
            ASSERT_TRUE(s) << s.message();
            EXPECT_FALSE(s->diverged);
        }
    }
};

/// The ambient wind of both cascades, and a fan in the coarse cascade upwind of the fine one that bends it.
constexpr glm::vec3 kWind(3.0f, 0.0f, 0.0f);
const Emitter kUpwindFan{
    EmitterType::Directional, Nest::centre - glm::vec3(11.0f, 0.0f, 3.0f), {0, 0, 1}, 4.0f, 5.0f, 0.0f, 0.0f};

/// The largest difference between the fine cascade's cell velocities and the coarse one's at the same
/// points, over the local speed, in the fine cascade's outermost `layers` cells (0: every cell).
float largest_difference(Nest& nest, int layers) {
    const glm::ivec3 n(nest.fine->desc().cells);
    auto cells = nest.fine->read_cell_velocity();
    EXPECT_TRUE(cells) << cells.message();
    if (!cells) return 0.0f;
    std::vector<glm::vec3> points;
    std::vector<glm::vec3> fine;
    for (int z = 0; z < n.z; ++z)
        for (int y = 0; y < n.y; ++y)
            for (int x = 0; x < n.x; ++x) {
                const glm::ivec3 c(x, y, z);
                const int depth = glm::min(glm::compMin(c), glm::compMin(n - 1 - c));
                if (layers > 0 && depth >= layers) continue;
                points.push_back(nest.fine->origin() + glm::vec3(c) + 0.5f);
                fine.push_back((*cells)[std::size_t(shaderio::cell_index(n, c))]);
            }
    auto coarse = nest.coarse->sample(points);
    EXPECT_TRUE(coarse) << coarse.message();
    float worst = 0.0f;
    for (std::size_t k = 0; coarse && k < points.size(); ++k)
        worst = std::max(worst, glm::distance(fine[k], (*coarse)[k]) / glm::length((*coarse)[k]));
    return worst;
}

TEST_F(CascadeTest, theFinerCascadeTakesTheCoarserOnesWindAtItsBorder) {
    // The fan bends the breeze in the coarse cascade only; only the coupling brings that into the fine one.
    for (bool coupled : {true, false}) {
        Nest nest(ctx(), coupled);
        ASSERT_TRUE(nest.coarse && nest.fine);
        for (WindSolver* s : {nest.coarse.get(), nest.fine.get()})
            ASSERT_TRUE(s->set_ambient(kWind));
        ASSERT_TRUE(nest.coarse->set_emitters({&kUpwindFan, 1}));
        nest.run(60, 0.1f);
        // Across the border (the fine cascade's outermost cell layer) the two differ by at most 10 % of the
        // local speed.
        const float border = largest_difference(nest, 1);
        if (coupled)
            EXPECT_LT(border, 0.1f);
        else
            EXPECT_GT(border, 0.3f) << "uncoupled, the fine cascade should not see the coarse one's fan";
    }
}

// A GPU's layout (PassLayout::FewerStages: the warm start's scale summed in the nested advection's
// correction, which couple() builds again for the nest) gives a coupled nest the wind of lavapipe's own
// layout (LessWork) but for the sums' rounding; CI runs lavapipe, so this is where a nest runs it.
TEST_F(CascadeTest, aNestInAGpusLayoutBlowsTheWindOfLavapipesLayout) {
    std::vector<glm::vec3> wind[2];
    for (int fewer = 0; fewer < 2; ++fewer) {
        Nest nest(ctx(), true, fewer == 1 ? PassLayout::FewerStages : PassLayout::LessWork);
        ASSERT_TRUE(nest.coarse && nest.fine);
        for (WindSolver* s : {nest.coarse.get(), nest.fine.get()}) {
            ASSERT_TRUE(s->set_ambient(kWind));
            EXPECT_EQ(s->desc().layout, fewer == 1 ? PassLayout::FewerStages : PassLayout::LessWork);
        }
        ASSERT_TRUE(nest.coarse->set_emitters({&kUpwindFan, 1}));
        nest.run(20, 0.1f);
        for (WindSolver* s : {nest.coarse.get(), nest.fine.get()}) {
            auto cells = s->read_cell_velocity();
            ASSERT_TRUE(cells) << cells.message();
            wind[fewer].insert(wind[fewer].end(), cells->begin(), cells->end());
        }
    }
    ASSERT_EQ(wind[0].size(), wind[1].size());
    float largest = 0.0f, apart = 0.0f;
    for (std::size_t i = 0; i < wind[0].size(); ++i) {
        largest = std::max(largest, glm::length(wind[0][i]));
        apart = std::max(apart, glm::distance(wind[0][i], wind[1][i]));
    }
    EXPECT_GT(largest, 2.0f);
    EXPECT_LT(apart, 1e-3f * largest);
}

TEST_F(CascadeTest, theCoarserCascadeTakesTheFinerOnesWindWhereItCoversIt) {
    // A fan in the fine cascade only, blowing +x through its middle.
    const Emitter fan{EmitterType::Directional, Nest::centre, {1, 0, 0}, 3.0f, 6.0f, 0.0f, 0.0f};
    float coupled_speed = 0.0f;
    for (bool coupled : {true, false}) {
        Nest nest(ctx(), coupled);
        ASSERT_TRUE(nest.coarse && nest.fine);
        ASSERT_TRUE(nest.fine->set_emitters({&fan, 1}));
        nest.run(40, 0.1f);
        const glm::vec3 points[] = {Nest::centre};
        auto fine = nest.fine->sample(points);
        auto coarse = nest.coarse->sample(points);
        ASSERT_TRUE(fine && coarse);
        if (coupled) {
            coupled_speed = (*coarse)[0].x;
            EXPECT_GT((*fine)[0].x, 3.0f);
            // The coarse cell averages the fan's jet with the slower air around it.
            EXPECT_GT(coupled_speed, 0.4f * (*fine)[0].x);
            EXPECT_LT(coupled_speed, 1.1f * (*fine)[0].x);
        } else {
            EXPECT_LT(std::abs((*coarse)[0].x), 0.05f) << "uncoupled, the coarse cascade should stay still";
        }
    }
}

TEST_F(CascadeTest, theMassThroughTheFinerBorderMatchesTheCoarserOnesAndTheAnswerHasNoSeam) {
    // Uneven wind reaches the fine cascade: the breeze, bent by the fan upwind of it.
    Nest nest(ctx(), true);
    ASSERT_TRUE(nest.coarse && nest.fine);
    for (WindSolver* s : {nest.coarse.get(), nest.fine.get()})
        ASSERT_TRUE(s->set_ambient(kWind));
    ASSERT_TRUE(nest.coarse->set_emitters({&kUpwindFan, 1}));
    nest.run(60, 0.1f);

    // Flux through each side of the fine cascade's border (m^3/s, positive inwards): its own faces', and the
    // coarse cascade's faces that tile the same surface (the fine grid's border lies on coarse faces).
    const auto side_fluxes = [](WindSolver& solver, glm::ivec3 lo, glm::ivec3 hi) {
        const glm::ivec3 n(solver.desc().cells);
        const float area = solver.desc().cell_size * solver.desc().cell_size;
        auto u = solver.read_velocity();
        EXPECT_TRUE(u) << u.message();
        std::array<double, 6> flux{};
        for (int i = 0; u && i < shaderio::faces_total(n); ++i) {
            std::uint32_t axis;
            const glm::ivec3 f = shaderio::face_from_index(n, i, axis);
            bool across = true;
            for (std::uint32_t a = 0; a < 3; ++a)
                if (a != axis) across = across && f[int(a)] >= lo[int(a)] && f[int(a)] < hi[int(a)];
            if (!across) continue;
            if (f[int(axis)] == lo[int(axis)]) flux[2 * axis] += area * (*u)[std::size_t(i)];
            if (f[int(axis)] == hi[int(axis)]) flux[2 * axis + 1] -= area * (*u)[std::size_t(i)];
        }
        return flux;
    };
    const glm::ivec3 fine_cells(nest.fine->desc().cells);
    const glm::ivec3 offset((nest.fine->origin() - nest.coarse->origin()) / nest.coarse->desc().cell_size);
    const auto fine = side_fluxes(*nest.fine, glm::ivec3(0), fine_cells);
    const auto coarse = side_fluxes(*nest.coarse, offset, offset + fine_cells / 2);
    // What enters through the border (the sides with net inflow) matches within 1 %; each side within 3 % of
    // that (a side's bilinear samples reach past its rim into the coarse faces beside it, which the fan's jet
    // crosses here).
    double fine_in = 0.0, coarse_in = 0.0;
    for (int side = 0; side < 6; ++side) {
        fine_in += std::max(fine[side], 0.0);
        coarse_in += std::max(coarse[side], 0.0);
    }
    ASSERT_GT(coarse_in, 0.0);
    EXPECT_NEAR(fine_in, coarse_in, 0.01 * coarse_in);
    for (int side = 0; side < 6; ++side)
        EXPECT_NEAR(fine[side], coarse[side], 0.03 * coarse_in) << "side " << side;

    // Along a line out through the border, the fine cascade's answer (blended into the coarse one's over its
    // last cells) steps by no more than 10 % of the local speed between points 0.25 m apart.
    std::vector<glm::vec3> line;
    for (float x = 4.0f; x <= 12.0f; x += 0.25f)
        line.push_back(nest.fine->origin() + glm::vec3(x - 6.0f, 4.2f, 7.3f));
    auto along = nest.fine->sample(line);
    ASSERT_TRUE(along) << along.message();
    for (std::size_t k = 1; k < line.size(); ++k) {
        const float speed = glm::length((*along)[k]);
        EXPECT_LT(glm::distance((*along)[k], (*along)[k - 1]), 0.1f * speed) << "at x = " << line[k].x;
    }
}

} // namespace
} // namespace gust::test
