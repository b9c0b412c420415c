// A System of nested cascades (WindDomain::cascades, docs/solver.md "Cascades"): bad nests are refused, a
// query outside the finest cascade answers from a coarser one, and a ridge beyond the finest cascade shelters
// the player as one fine grid covering both does.
#include "system_test_support.hpp"

#include <array>
#include <cmath>

namespace gust::test {
namespace {

/// A closed box from lo to hi (world, m), as a mesh placed by the identity.
struct Slab {
    std::array<float, 24> positions{};
    std::vector<std::uint32_t> indices;
    Slab(Vec3 lo, Vec3 hi) {
        const Box unit(1.0f);
        for (int i = 0; i < 8; ++i) {
            positions[std::size_t(3 * i)] = (i & 1) ? hi.x : lo.x;
            positions[std::size_t(3 * i + 1)] = (i & 2) ? hi.y : lo.y;
            positions[std::size_t(3 * i + 2)] = (i & 4) ? hi.z : lo.z;
        }
        indices = unit.indices;
    }
    MeshDesc desc() const {
        MeshDesc d;
        d.positions = positions.data();
        d.vertex_count = 8;
        d.indices = indices.data();
        d.index_count = std::uint32_t(indices.size());
        return d;
    }
};

TEST(Cascades, badNestsAreRefusedWithTheirReason) {
    struct Case {
        std::uint32_t cascades, ratio;
        float cell_size;
        bool snapshot;
        const char* says;
    };
    for (const Case& c :
         {Case{0, 4, 1.0f, false, "domain.cascades must be 1..8"},
          Case{9, 4, 1.0f, false, "domain.cascades must be 1..8"},
          Case{2, 3, 1.0f, false, "domain.ratio must be 2 or 4"}, Case{6, 4, 1.0f, false, "more than 1000 m"},
          Case{2, 2, 1.0f, true, "snapshot holds one cascade"}}) {
        Watch watch;
        SystemDesc desc = small_desc(watch);
        desc.domain.cascades = c.cascades;
        desc.domain.ratio = c.ratio;
        desc.domain.cell_size = c.cell_size;
        desc.snapshot = c.snapshot;
        std::unique_ptr<System> system;
        const Outcome created = System::create(desc, system);
        EXPECT_EQ(created.code(), ErrorCode::InvalidArgument) << c.says;
        EXPECT_NE(created.message().find(c.says), std::string::npos) << created.message();
        EXPECT_FALSE(system);
    }
}

TEST(Cascades, aQueryBeyondTheFinestCascadeAnswersFromTheCoarserOnes) {
    // A fan 20 m out, beyond the finest cascade (16 m wide) but inside the next (64 m).
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.domain.cascades = 3;
    desc.domain.ratio = 4;
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(desc, system));
    const WindEmitter fan{.type = WindEmitterType::Directional,
                          .position = {20.0f, 4.0f, 0.0f},
                          .direction = {0.0f, 0.0f, 1.0f},
                          .radius = 6.0f,
                          .strength = 6.0f};
    ASSERT_TRUE(system->set_emitters({&fan, 1}));
    for (int f = 0; f < 32; ++f)
        ASSERT_TRUE(system->step(0.1f));
    const Vec3 points[] = {{20.0f, 4.0f, 0.0f}, {0.0f, 4.0f, 0.0f}, {120.0f, 4.0f, 0.0f}};
    std::array<Vec3, 3> wind{};
    ASSERT_TRUE(system->query(points, wind));
    EXPECT_GT(wind[0].z, 2.0f) << "the fan blows in the second cascade";
    EXPECT_LT(std::abs(wind[1].z), 0.5f * wind[0].z) << "the finest cascade lies beside the fan";
    EXPECT_LT(std::abs(wind[2].z), 0.5f)
        << "120 m out only the third cascade holds the point, far from the fan";
    EXPECT_EQ(watch.errors, 0) << watch.last;
}

TEST(Cascades, shiftingTheOriginMovesTheWindTheSolidsAndThePendingQueries) {
    // Two Systems of one scene; the second's world is rebased half-way by an offset of no whole cells.
    const Vec3 offset{37.3f, -2.5f, -12.9f};
    // Off the voxel planes, so that no face of it lies where rounding the shifted coordinates could flip a voxel.
    const Slab block({-1.8f, 0.1f, -0.9f}, {1.2f, 2.9f, 1.7f});
    std::unique_ptr<System> systems[2];
    Watch watch[2];
    for (int i = 0; i < 2; ++i) {
        SystemDesc desc = small_desc(watch[i]);
        desc.domain.cascades = 2;
        desc.domain.ratio = 2;
        ASSERT_TRUE(System::create(desc, systems[i]));
        MeshId mesh = 0;
        InstanceId id = 0;
        ASSERT_TRUE(systems[i]->create_mesh(block.desc(), mesh));
        ASSERT_TRUE(systems[i]->create_instance(mesh, Mat4{}, false, id));
        ASSERT_TRUE(systems[i]->set_ambient({4.0f, 0.0f, 1.0f}));
        const WindEmitter fan{.type = WindEmitterType::Directional,
                              .position = {-5.0f, 2.0f, 3.0f},
                              .direction = {0.0f, 1.0f, 0.0f},
                              .radius = 2.0f,
                              .strength = 5.0f};
        ASSERT_TRUE(systems[i]->set_emitters({&fan, 1}));
        for (int f = 0; f < 10; ++f)
            ASSERT_TRUE(systems[i]->step(0.1f));
    }
    const Vec3 points[] = {{3.0f, 1.5f, 0.5f}, {-5.0f, 2.0f, 3.0f}, {0.0f, 4.0f, -3.0f}, {14.0f, 4.0f, 0.0f}};
    QueryId asked[2] = {0, 0};
    for (int i = 0; i < 2; ++i)
        ASSERT_TRUE(systems[i]->query_async(points, asked[i]));
    ASSERT_TRUE(systems[1]->shift_origin(offset));
    for (int f = 0; f < 10; ++f)
        for (auto& system : systems)
            ASSERT_TRUE(system->step(0.1f));
    std::array<Vec3, 4> before[2], after[2];
    std::vector<Vec3> moved;
    for (const Vec3& p : points)
        moved.push_back({p.x + offset.x, p.y + offset.y, p.z + offset.z});
    for (int i = 0; i < 2; ++i) {
        ASSERT_TRUE(systems[i]->fetch(asked[i], before[i]));
        ASSERT_TRUE(systems[i]->query(i == 0 ? std::span<const Vec3>(points) : std::span<const Vec3>(moved),
                                      after[i]));
    }
    const auto distance = [](const Vec3& a, const Vec3& b) {
        return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
    };
    for (std::size_t k = 0; k < 4; ++k) {
        EXPECT_LT(distance(before[0][k], before[1][k]), 0.02f) << "the pending query, point " << k;
        EXPECT_LT(distance(after[0][k], after[1][k]), 0.05f) << "point " << k;
    }
    // The fan still blows where it stood.
    EXPECT_GT(after[1][1].y, 1.0f);
    const Vec3 origin = systems[1]->domain_origin();
    EXPECT_NEAR(origin.x, systems[0]->domain_origin().x + offset.x, 1e-3f);
    EXPECT_NEAR(origin.z, systems[0]->domain_origin().z + offset.z, 1e-3f);
    Vec3 far = {1e30f, 0.0f, 0.0f};
    EXPECT_EQ(systems[1]->shift_origin(far).code(), ErrorCode::InvalidArgument);
    for (const Watch& w : watch)
        EXPECT_EQ(w.errors, 0) << w.last;
}

/// The mean wind along x over a 16x16 m patch 8 m above the ground around the player, after `frames` frames
/// of an 8 m/s wind over the ground, with a 32 m ridge 100 m upwind when `ridge` is set.
float wind_at_player(const WindDomain& domain, bool ridge, int frames) {
    Watch watch;
    SystemDesc desc;
    desc.validation = true;
    desc.domain = domain;
    desc.hooks = watching(watch);
    std::unique_ptr<System> system;
    const Outcome created = System::create(desc, system);
    EXPECT_TRUE(created) << created.message();
    if (!created) return 0.0f;
    const Slab ground({-600.0f, -200.0f, -600.0f}, {600.0f, 0.0f, 600.0f});
    const Slab hill({-108.0f, -10.0f, -600.0f}, {-92.0f, 32.0f, 600.0f});
    MeshId ground_mesh = 0, hill_mesh = 0;
    InstanceId id = 0;
    EXPECT_TRUE(system->create_mesh(ground.desc(), ground_mesh));
    EXPECT_TRUE(system->create_instance(ground_mesh, Mat4{}, false, id));
    if (ridge) {
        EXPECT_TRUE(system->create_mesh(hill.desc(), hill_mesh));
        EXPECT_TRUE(system->create_instance(hill_mesh, Mat4{}, false, id));
    }
    EXPECT_TRUE(system->set_ambient({8.0f, 0.0f, 0.0f}));
    for (int f = 0; f < frames; ++f) {
        const Outcome stepped = system->step(0.25f);
        EXPECT_TRUE(stepped) << stepped.message();
        if (!stepped) return 0.0f;
    }
    std::vector<Vec3> points, wind;
    for (float x = -8.0f; x <= 8.0f; x += 4.0f)
        for (float z = -8.0f; z <= 8.0f; z += 4.0f)
            points.push_back({x, 8.0f, z});
    wind.resize(points.size());
    EXPECT_TRUE(system->query(points, wind));
    float sum = 0.0f;
    for (const Vec3& w : wind)
        sum += w.x;
    EXPECT_EQ(watch.errors, 0) << watch.last;
    return sum / float(wind.size());
}

TEST(Cascades, aRidgeBeyondTheFinestCascadeSheltersThePlayerAsOneFineGridDoes) {
    // The nest: 32x16x16 cells of 4 m (128 m along the wind) in one of 8 m (256 m), so the ridge, 100 m
    // upwind, lies in the coarser cascade only. The reference: one grid of 4 m cells holding both.
    WindDomain nest;
    nest.cells[0] = 32;
    nest.cells[1] = 16;
    nest.cells[2] = 16;
    nest.cell_size = 4.0f;
    nest.voxels_per_cell = 2;
    nest.focus = {0.0f, 24.0f, 0.0f};
    nest.cascades = 2;
    nest.ratio = 2;
    WindDomain fine = nest;
    fine.cascades = 1;
    fine.cells[0] = 56;
    fine.cells[1] = 24;
    fine.focus = {-48.0f, 40.0f, 0.0f};
    WindDomain alone = nest;
    alone.cascades = 1;
    constexpr int kFrames = 160; // 40 s: the wind crosses the reference grid 1.4 times
    const float reference = 1.0f - wind_at_player(fine, true, kFrames) / wind_at_player(fine, false, kFrames);
    const float nested = 1.0f - wind_at_player(nest, true, kFrames) / wind_at_player(nest, false, kFrames);
    const float single = 1.0f - wind_at_player(alone, true, kFrames) / wind_at_player(alone, false, kFrames);
    RecordProperty("reference_shelter", std::to_string(reference));
    RecordProperty("nested_shelter", std::to_string(nested));
    EXPECT_GT(reference, 0.1f) << "the ridge should slow the wind at the player";
    EXPECT_NEAR(nested, reference, 0.2f * reference) << "reference " << reference << ", nested " << nested;
    EXPECT_LT(std::abs(single), 0.2f * reference) << "one cascade should not see the ridge at all";
}

} // namespace
} // namespace gust::test
