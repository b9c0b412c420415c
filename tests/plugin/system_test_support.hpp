// What the System suites share: host hooks that count allocations and log messages, a small validated
// domain, and a box mesh.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <memory>
#include <string>
#include <vector>

namespace gust::test {

/// Counts host memory and warnings; fails the test on any Error-level message.
struct Watch {
    int errors = 0, warnings = 0;
    long live = 0, allocations = 0;
    std::string last;
};

inline Hooks watching(Watch& w) {
    Hooks h;
    h.user = &w;
    h.allocate = [](void* user, std::size_t bytes, std::size_t alignment) -> void* {
        auto* watch = static_cast<Watch*>(user);
        ++watch->live;
        ++watch->allocations;
        return std::aligned_alloc(alignment, (bytes + alignment - 1) / alignment * alignment);
    };
    h.free = [](void* user, void* memory) {
        --static_cast<Watch*>(user)->live;
        std::free(memory);
    };
    h.log = [](void* user, LogLevel level, const char* message) {
        auto* watch = static_cast<Watch*>(user);
        if (level == LogLevel::Error) ++watch->errors;
        if (level == LogLevel::Warning) ++watch->warnings;
        watch->last = message;
    };
    return h;
}

inline SystemDesc small_desc(Watch& watch) {
    SystemDesc desc;
    desc.validation = true;
    desc.domain.cells[0] = 16;
    desc.domain.cells[1] = 8;
    desc.domain.cells[2] = 16;
    desc.domain.voxels_per_cell = 2;
    desc.domain.focus = {0.0f, 4.0f, 0.0f};
    desc.hooks = watching(watch);
    // The tests check converged solves; the API's default fixed budget has a test of its own.
    desc.wind.cycles_per_step = 0;
    return desc;
}

inline Mat4 translation(float x, float y, float z) {
    Mat4 m;
    m.m[12] = x;
    m.m[13] = y;
    m.m[14] = z;
    return m;
}

/// A closed box (12 triangles): from -extent to extent on every axis, or from lo to hi.
struct Box {
    std::vector<float> positions;
    std::vector<std::uint32_t> indices;
    explicit Box(float extent) : Box({-extent, -extent, -extent}, {extent, extent, extent}) {}
    Box(Vec3 lo, Vec3 hi) {
        for (int i = 0; i < 8; ++i)
            positions.insert(positions.end(),
                             {(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
        const std::uint32_t q[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
        for (const auto& f : q)
            indices.insert(indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
    }
    MeshDesc desc(bool deforming = false) const {
        MeshDesc d;
        d.positions = positions.data();
        d.vertex_count = 8;
        d.indices = indices.data();
        d.index_count = std::uint32_t(indices.size());
        d.deforming = deforming;
        return d;
    }
};

/// A System on the small domain; fails on errors, warnings and host memory left allocated.
class SystemTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const Outcome created = System::create(small_desc(watch_), system_);
        ASSERT_TRUE(created) << created.message();
    }
    void TearDown() override {
        system_.reset();
        EXPECT_EQ(watch_.errors, 0) << watch_.last;
        EXPECT_EQ(watch_.warnings, 0) << watch_.last;
        EXPECT_EQ(watch_.live, 0) << "host allocations not freed";
    }
    /// A static box and a moving one in a wind of 3 m/s, stepped `frames` times.
    void run_scene(System& system, int frames) {
        MeshId mesh = 0;
        ASSERT_TRUE(system.create_mesh(box_.desc(), mesh));
        InstanceId fixed = 0, moving = 0;
        ASSERT_TRUE(system.create_instance(mesh, translation(-3.0f, 2.0f, 0.0f), false, fixed));
        ASSERT_TRUE(system.create_instance(mesh, translation(3.0f, 2.0f, 0.0f), true, moving));
        ASSERT_TRUE(system.set_ambient({3.0f, 0.0f, 0.0f}));
        for (int f = 0; f < frames; ++f) {
            ASSERT_TRUE(system.set_transform(moving, translation(3.0f, 2.0f, 0.5f * float(f))));
            const Outcome stepped = system.step(0.05f);
            ASSERT_TRUE(stepped) << stepped.message();
        }
    }

    Watch watch_;
    std::unique_ptr<System> system_;
    Box box_{1.0f};
};

} // namespace gust::test
