// The wind snapshot (SystemDesc::snapshot, System::sample) and the threading contract of gust.hpp: one
// writer, many readers. Built a second time with ThreadSanitizer (tests/plugin/CMakeLists.txt).
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

// The ThreadSanitizer build runs without the validation layer: its own threads and locks are not gust's, and
// the plain build validates the same calls.
#ifndef GUST_TEST_VALIDATION
#define GUST_TEST_VALIDATION 1
#endif

namespace gust::test {
namespace {

/// Log counters any thread may touch (the hooks here allocate nothing: Vulkan's own threads stay apart).
struct Counts {
    std::atomic<int> errors{0};
};

SystemDesc snapshot_desc(Counts& counts, bool snapshot) {
    SystemDesc desc;
    desc.validation = GUST_TEST_VALIDATION != 0;
    desc.domain.cells[0] = 16;
    desc.domain.cells[1] = 8;
    desc.domain.cells[2] = 16;
    desc.domain.voxels_per_cell = 2;
    desc.domain.focus = {0.0f, 4.0f, 0.0f};
    desc.snapshot = snapshot;
    desc.hooks.user = &counts;
    desc.hooks.log = [](void* user, LogLevel level, const char*) {
        if (level == LogLevel::Error) static_cast<Counts*>(user)->errors.fetch_add(1);
    };
    return desc;
}

/// A static box at (-3, 2, 0) and a moving one, in a wind of 3 m/s.
struct Scene {
    std::vector<float> positions;
    std::vector<std::uint32_t> indices;
    MeshId mesh = 0;
    InstanceId fixed = 0, moving = 0;

    explicit Scene(System& system) {
        for (int i = 0; i < 8; ++i)
            for (int a = 0; a < 3; ++a)
                positions.push_back((i >> a & 1) ? 1.0f : -1.0f);
        const std::uint32_t q[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
        for (const auto& f : q)
            indices.insert(indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
        MeshDesc d;
        d.positions = positions.data();
        d.vertex_count = 8;
        d.indices = indices.data();
        d.index_count = std::uint32_t(indices.size());
        EXPECT_TRUE(system.create_mesh(d, mesh));
        EXPECT_TRUE(system.create_instance(mesh, at(-3.0f, 2.0f, 0.0f), false, fixed));
        EXPECT_TRUE(system.create_instance(mesh, at(3.0f, 2.0f, 0.0f), true, moving));
        EXPECT_TRUE(system.set_ambient({3.0f, 0.0f, 0.0f}));
    }
    static Mat4 at(float x, float y, float z) {
        Mat4 m;
        m.m[12] = x;
        m.m[13] = y;
        m.m[14] = z;
        return m;
    }
    Outcome step(System& system, int f) {
        if (Outcome o = system.set_transform(moving, at(3.0f, 2.0f, 0.25f * float(f % 8))); !o) return o;
        return system.step(0.05f);
    }
};

bool finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Random points over the domain (16 x 8 x 16 m from (-8, 0, -8)) and a metre beyond it.
std::vector<Vec3> random_points(std::size_t count, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> x(-9.0f, 9.0f), y(-1.0f, 9.0f);
    std::vector<Vec3> points(count);
    for (Vec3& p : points)
        p = {x(random), y(random), x(random)};
    return points;
}

TEST(Snapshot, RefusesWhenOffOrEmptyAndOnBadInput) {
    Counts counts;
    std::unique_ptr<System> off, on;
    ASSERT_TRUE(System::create(snapshot_desc(counts, false), off));
    ASSERT_TRUE(System::create(snapshot_desc(counts, true), on));
    const Vec3 points[2] = {{0, 4, 0}, {1, 4, 0}};
    Vec3 out[2];
    const Outcome forgotten = off->sample(points, out);
    EXPECT_EQ(forgotten.code(), ErrorCode::NotEnabled) << "a wrong setup, not an answer to wait for";
    EXPECT_NE(forgotten.message().find("SystemDesc::snapshot"), std::string::npos) << forgotten.message();
    EXPECT_EQ(on->sample(points, out).code(), ErrorCode::NotReady) << "nothing published before a step";
    ASSERT_TRUE(off->step(0.05f));
    ASSERT_TRUE(on->step(0.05f));
    EXPECT_EQ(off->sample(points, out).code(), ErrorCode::NotEnabled);
    SnapshotInfo info;
    ASSERT_TRUE(on->sample(points, out, info));
    EXPECT_EQ(info.frame, 1u);
    EXPECT_EQ(info.extent[0], 16u);
    EXPECT_EQ(on->sample(points, std::span<Vec3>(out, 1)).code(), ErrorCode::InvalidArgument);
    const Vec3 bad[1] = {{0.0f, NAN, 0.0f}};
    EXPECT_EQ(on->sample(bad, std::span<Vec3>(out, 1)).code(), ErrorCode::InvalidArgument);
    EXPECT_TRUE(on->sample({}, {}));
    EXPECT_EQ(counts.errors.load(), 0);
}

// One wind at a point (issue 42, docs/api.md): query and the snapshot read the same texels alike, by walls
// and in their shear layers, inside the boxes, on a box's top face and beyond the domain.
TEST(Snapshot, queryAndSampleGiveOneWindAtEveryPoint) {
    Counts counts;
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(snapshot_desc(counts, true), system));
    Scene scene(*system);
    WindEmitter omni;
    omni.type = WindEmitterType::Omni;
    omni.position = {0.0f, 4.0f, 4.0f};
    omni.radius = 3.0f;
    omni.strength = 2.0f;
    ASSERT_TRUE(system->set_emitters({&omni, 1}));
    for (int f = 0; f < 12; ++f)
        ASSERT_TRUE(scene.step(*system, f));
    // Every cell centre, points scattered over the domain and a metre beyond it, the static box's top face,
    // its inside (still) and points beyond each face (the ambient wind).
    std::vector<Vec3> points = random_points(2000, 7);
    for (int k = 0; k < 16; ++k)
        for (int j = 0; j < 8; ++j)
            for (int i = 0; i < 16; ++i)
                points.push_back({-8.0f + float(i) + 0.5f, float(j) + 0.5f, -8.0f + float(k) + 0.5f});
    for (float x = -4.0f; x <= -2.0f; x += 0.125f)
        points.push_back({x, 3.0f, 0.3f});
    const std::size_t open = points.size();
    points.push_back({-3.0f, 2.0f, 0.0f});
    for (const Vec3& outside : {Vec3{-8.5f, 4, 0}, Vec3{8.5f, 4, 0}, Vec3{0, -0.5f, 0}, Vec3{0, 8.5f, 0},
                                Vec3{0, 4, -8.5f}, Vec3{0, 4, 8.5f}})
        points.push_back(outside);
    std::vector<Vec3> queried(points.size()), sampled(points.size());
    ASSERT_TRUE(system->query(points, queried));
    SnapshotInfo info;
    ASSERT_TRUE(system->sample(points, sampled, info));
    EXPECT_EQ(info.frame, 12u);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3 &q = queried[i], &s = sampled[i];
        // The same half-float texels, blended in float on the GPU and on the CPU.
        const float tolerance = 1e-4f * std::max({1.0f, std::abs(q.x), std::abs(q.y), std::abs(q.z)});
        EXPECT_NEAR(s.x, q.x, tolerance) << "point " << i << (i >= open ? " (solid or outside)" : "");
        EXPECT_NEAR(s.y, q.y, tolerance) << "point " << i;
        EXPECT_NEAR(s.z, q.z, tolerance) << "point " << i;
    }
    EXPECT_FLOAT_EQ(sampled.back().x, 3.0f) << "the ambient wind outside";
    EXPECT_EQ(counts.errors.load(), 0);
}

// The goal: 8 threads, each sampling 10,000 points a frame while the main thread steps.
TEST(Snapshot, ReadersSampleWhileTheWriterSteps) {
    Counts counts;
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(snapshot_desc(counts, true), system));
    Scene scene(*system);
    ASSERT_TRUE(scene.step(*system, 0));
    constexpr int kReaders = 8, kSteps = 30;
    constexpr std::size_t kPoints = 10000;
    std::atomic<bool> stepping{true};
    struct Reader {
        std::vector<Vec3> points, answers;
        std::uint64_t last_frame = 0;
        int calls = 0, failures = 0, non_finite = 0, backwards = 0;
        std::uint64_t stats_frames = 0;
    };
    std::vector<Reader> readers(kReaders);
    std::vector<std::thread> threads;
    for (int r = 0; r < kReaders; ++r) {
        readers[r].points = random_points(kPoints, unsigned(r + 1));
        readers[r].answers.resize(kPoints);
        threads.emplace_back([&, r] {
            Reader& me = readers[r];
            FrameStats stats;
            // At least a few calls each, and on until a call that began after the writer was done.
            for (bool more = true; more;) {
                more = stepping.load() || me.calls < 3;
                SnapshotInfo info;
                if (!system->sample(me.points, me.answers, info)) {
                    ++me.failures;
                    continue;
                }
                ++me.calls;
                for (const Vec3& v : me.answers)
                    if (!finite(v)) ++me.non_finite;
                if (info.frame < me.last_frame) ++me.backwards;
                me.last_frame = info.frame;
                if (system->read_stats(stats)) me.stats_frames = std::max(me.stats_frames, stats.frame);
            }
        });
    }
    for (int f = 1; f <= kSteps; ++f) {
        const Outcome stepped = scene.step(*system, f);
        EXPECT_TRUE(stepped) << stepped.message();
    }
    stepping.store(false);
    for (std::thread& t : threads)
        t.join();
    const std::uint64_t last = std::uint64_t(kSteps) + 1;
    for (int r = 0; r < kReaders; ++r) {
        const Reader& me = readers[r];
        EXPECT_EQ(me.failures, 0) << "reader " << r;
        EXPECT_EQ(me.non_finite, 0) << "reader " << r;
        EXPECT_EQ(me.backwards, 0) << "reader " << r << " saw an older snapshot after a newer one";
        EXPECT_GE(me.calls, 4);
        // The readers went on after the last step: their last answer is the last snapshot's, the same as
        // one thread alone reads from it.
        EXPECT_EQ(me.last_frame, last) << "reader " << r;
        std::vector<Vec3> alone(kPoints);
        SnapshotInfo info;
        ASSERT_TRUE(system->sample(me.points, alone, info));
        ASSERT_EQ(info.frame, last);
        for (std::size_t i = 0; i < kPoints; ++i)
            ASSERT_TRUE(alone[i].x == me.answers[i].x && alone[i].y == me.answers[i].y &&
                        alone[i].z == me.answers[i].z)
                << "reader " << r << " point " << i;
    }
    EXPECT_EQ(counts.errors.load(), 0);
}

TEST(Snapshot, OverlappingWriterCallsAreRefused) {
    Counts counts;
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(snapshot_desc(counts, true), system));
    Scene scene(*system);
    // A second thread makes writer calls while the first steps: each either runs or is refused as Busy.
    std::atomic<bool> stepping{true};
    std::atomic<int> refused{0}, other{0};
    std::thread intruder([&] {
        while (stepping.load()) {
            const Outcome o = system->set_ambient({2.0f, 0.0f, 0.0f});
            if (o.code() == ErrorCode::Busy)
                refused.fetch_add(1);
            else if (!o)
                other.fetch_add(1);
        }
    });
    int busy_steps = 0;
    for (int f = 0; f < 20; ++f) {
        const Outcome stepped = system->step(0.05f);
        if (stepped.code() == ErrorCode::Busy)
            ++busy_steps;
        else
            EXPECT_TRUE(stepped) << stepped.message();
    }
    stepping.store(false);
    intruder.join();
    EXPECT_EQ(other.load(), 0);
    EXPECT_GT(refused.load() + busy_steps, 0) << "20 steps beside a busy writer and no overlap was caught";
    EXPECT_EQ(counts.errors.load(), 0);
}

TEST(Snapshot, AWriterCallInsideAWriterCallIsRefused) {
    // A hook runs inside step: a writer call made from it overlaps the step on the same thread.
    struct Inside {
        System* system = nullptr;
        ErrorCode got = ErrorCode::Ok;
        int calls = 0;
    } inside;
    SystemDesc desc;
    desc.domain.cells[0] = 16;
    desc.domain.cells[1] = 8;
    desc.domain.cells[2] = 16;
    desc.domain.voxels_per_cell = 2;
    desc.hooks.user = &inside;
    desc.hooks.allocate = [](void* user, std::size_t bytes, std::size_t alignment) -> void* {
        auto* in = static_cast<Inside*>(user);
        if (in->system && in->calls++ == 0) in->got = in->system->set_ambient({1.0f, 0.0f, 0.0f}).code();
        return std::aligned_alloc(alignment, (bytes + alignment - 1) / alignment * alignment);
    };
    desc.hooks.free = [](void*, void* memory) { std::free(memory); };
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(desc, system));
    Scene scene(*system);
    inside.system = system.get();
    ASSERT_TRUE(system->step(0.05f));
    inside.system = nullptr;
    EXPECT_GT(inside.calls, 0);
    EXPECT_EQ(inside.got, ErrorCode::Busy);
}

} // namespace
} // namespace gust::test
