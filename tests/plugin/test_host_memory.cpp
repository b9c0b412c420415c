// With an allocation hook, gust allocates no host memory of its own anywhere else. This binary replaces
// the global operator new and counts the calls gust's code makes while a System call runs (calls from the
// Vulkan driver and the loader, which are not gust's, are told apart by their return address). Vulkan's
// own host allocations reach the hook through VkAllocationCallbacks, so they show up in its count too.
#include "host_vulkan.hpp"
#include "system_test_support.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdlib>
#include <execinfo.h>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <link.h>
#include <new>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

// The main program's code, as GNU ld names its bounds: gust is linked statically into this binary.
extern "C" char __executable_start[];
extern "C" char etext[];

namespace {

std::atomic<bool> g_armed{false};
std::atomic<long> g_gust_news{0};

/// The code segments of the C and C++ runtimes, found once before main (they are loaded by then):
/// telling a frame's library by its address range, not dladdr, keeps the check cheap for a driver with
/// a large symbol table, whose shader compiler allocates millions of times.
struct CodeRange {
    const char* begin;
    const char* end;
};
std::array<CodeRange, 32> g_runtime{};
std::size_t g_runtime_count = 0;

int add_runtime(dl_phdr_info* info, std::size_t, void*) {
    const std::string_view file = info->dlpi_name ? info->dlpi_name : "";
    const std::string_view name = file.substr(file.rfind('/') + 1);
    if (!(name.starts_with("libstdc++") || name.starts_with("libc.") || name.starts_with("libgcc_s") ||
          name.starts_with("ld-linux")))
        return 0;
    for (int i = 0; i < info->dlpi_phnum && g_runtime_count < g_runtime.size(); ++i) {
        const ElfW(Phdr)& segment = info->dlpi_phdr[i];
        if (segment.p_type != PT_LOAD || (segment.p_flags & PF_X) == 0) continue;
        const auto* begin = reinterpret_cast<const char*>(info->dlpi_addr + segment.p_vaddr);
        g_runtime[g_runtime_count++] = {begin, begin + segment.p_memsz};
    }
    return 0;
}
const int g_runtime_found = dl_iterate_phdr(add_runtime, nullptr);

/// True when each of the n frames is this program's code (gust's and the test's) or the C and C++
/// runtimes'.
bool gust_frames(void* const* frames, int n) {
    for (int i = 0; i < n; ++i) {
        const auto* pc = static_cast<const char*>(frames[i]);
        if (pc >= __executable_start && pc < etext) continue;
        const CodeRange* first = g_runtime.data();
        if (std::none_of(first, first + g_runtime_count,
                         [pc](const CodeRange& r) { return pc >= r.begin && pc < r.end; }))
            return false;
    }
    return true;
}

/// True when every frame of the calling stack is gust's or the runtimes' (gust_frames): an allocation
/// with a Vulkan loader, driver or layer frame on its stack is theirs, even where it reaches operator
/// new through a std::string member this program also instantiates. The nearest frames are looked at
/// first: they settle the driver's own allocations (a shader compiler makes millions) without
/// unwinding its deep stacks.
bool only_gust_on_stack() {
    std::array<void*, 8> near{};
    const int n = backtrace(near.data(), int(near.size()));
    if (!gust_frames(near.data(), n)) return false;
    if (n < int(near.size())) return true;
    std::array<void*, 96> frames{};
    return gust_frames(frames.data(), backtrace(frames.data(), int(frames.size())));
}

void count() {
    if (g_armed.load(std::memory_order_relaxed) && only_gust_on_stack())
        g_gust_news.fetch_add(1, std::memory_order_relaxed);
}

void* allocate(std::size_t bytes, std::size_t alignment) {
    const std::size_t size = (bytes + alignment - 1) / alignment * alignment;
    return std::aligned_alloc(alignment, size ? size : alignment);
}

} // namespace

void* operator new(std::size_t bytes) {
    count();
    if (void* p = allocate(bytes, alignof(std::max_align_t))) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t bytes) {
    count();
    if (void* p = allocate(bytes, alignof(std::max_align_t))) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t bytes, std::align_val_t alignment) {
    count();
    if (void* p = allocate(bytes, std::size_t(alignment))) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t bytes, std::align_val_t alignment) {
    count();
    if (void* p = allocate(bytes, std::size_t(alignment))) return p;
    throw std::bad_alloc();
}
void* operator new(std::size_t bytes, const std::nothrow_t&) noexcept {
    count();
    return allocate(bytes, alignof(std::max_align_t));
}
void* operator new[](std::size_t bytes, const std::nothrow_t&) noexcept {
    count();
    return allocate(bytes, alignof(std::max_align_t));
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}

namespace gust::test {
namespace {

/// Runs one gust call with the counter armed; the test's own code runs disarmed.
template <class F> Outcome counted(F&& call) {
    g_armed = true;
    Outcome o = call();
    g_armed = false;
    return o;
}

/// Destroys the System (counted too), then expects no operator new from gust's code in the test, every
/// hook allocation freed and no error logged.
void destroy_and_expect_nothing_else(std::unique_ptr<System>& system, const Watch& watch) {
    counted([&] {
        system.reset();
        return Outcome();
    });
    EXPECT_EQ(g_gust_news.load(), 0) << "operator new calls from gust's code while a hook was given";
    EXPECT_GT(watch.allocations, 0);
    EXPECT_EQ(watch.live, 0) << "host allocations not freed";
    EXPECT_EQ(watch.errors, 0) << watch.last;
}

TEST(HostMemory, theCounterSeesThisProgramsAllocationsThroughTheCppRuntime) {
    g_gust_news = 0;
    const std::string text(1000, 'x');
    std::ostringstream out;
    counted([&] {
        out << text; // the string buffer grows inside libstdc++'s compiled code
        return Outcome();
    });
    EXPECT_GE(g_gust_news.load(), 1) << "the C++ runtime's code was not told apart from a driver's";
}

TEST(HostMemory, aSystemWithAnAllocationHookAllocatesNothingElseInItsWholeLife) {
    g_gust_news = 0;
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.voxelize = VoxelizePath::Auto; // measures both paths, so both run
    std::unique_ptr<System> system;
    const Box box(1.0f);
    MeshId rigid = 0, skinned = 0;
    InstanceId fixed = 0, moving = 0, pose = 0;
    ASSERT_TRUE(counted([&] { return System::create(desc, system); }));
    ASSERT_TRUE(counted([&] { return system->create_mesh(box.desc(), rigid); }));
    ASSERT_TRUE(counted([&] { return system->create_mesh(box.desc(true), skinned); }));
    ASSERT_TRUE(counted([&] { return system->create_instance(rigid, translation(-3, 2, 0), false, fixed); }));
    ASSERT_TRUE(counted([&] { return system->create_instance(rigid, translation(3, 2, 0), true, moving); }));
    ASSERT_TRUE(counted([&] { return system->create_instance(skinned, translation(0, 2, 3), true, pose); }));
    ASSERT_TRUE(counted([&] { return system->set_ambient({3.0f, 0.0f, 0.0f}); }));
    const std::array<WindEmitter, 2> emitters = {
        WindEmitter{.type = WindEmitterType::Omni, .position = {0, 2, -3}, .strength = 2.0f},
        WindEmitter{.type = WindEmitterType::Vortex,
                    .position = {2, 2, 2},
                    .direction = {0, 1, 0},
                    .strength = 1.0f}};
    ASSERT_TRUE(counted([&] { return system->set_emitters(emitters); }));

    std::array<Vec3, 3> points = {Vec3{0, 2, 0}, Vec3{4, 3, 1}, Vec3{100, 0, 0}};
    std::array<Vec3, 3> wind{};
    std::vector<float> positions = box.positions;
    for (int frame = 0; frame < 6; ++frame) {
        for (float& p : positions)
            p *= 1.01f;
        ASSERT_TRUE(counted([&] { return system->set_vertices(skinned, positions.data(), 8); }));
        ASSERT_TRUE(
            counted([&] { return system->set_transform(moving, translation(3, 2, 0.5f * float(frame))); }));
        if (frame == 3) {
            ASSERT_TRUE(counted([&] { return system->set_transform(fixed, translation(-3, 2, 1)); }));
        }
        ASSERT_TRUE(counted([&] { return system->set_focus({0.0f, 4.0f, 1.0f * float(frame)}); }));
        QueryId ticket = 0;
        ASSERT_TRUE(counted([&] { return system->query_async(points, ticket); }));
        const Outcome stepped = counted([&] { return system->step(1.0f / 30.0f); });
        ASSERT_TRUE(stepped) << stepped.message();
        ASSERT_TRUE(counted([&] { return system->fetch(ticket, wind); }));
        ASSERT_TRUE(counted([&] { return system->query(points, wind); }));
        WindSample sample;
        ASSERT_TRUE(counted([&] { return system->wind_at(points[0], sample); }));
    }
    std::size_t count = 0;
    std::array<VoxelCoord, 16> voxels{};
    std::array<TreeNode, 16> nodes{};
    ASSERT_TRUE(counted([&] { return system->debug_voxels(voxels, count); }));
    ASSERT_TRUE(counted([&] { return system->debug_tree_nodes(nodes, count); }));
    ASSERT_TRUE(counted([&] { return system->destroy_instance(pose); }));
    ASSERT_TRUE(counted([&] { return system->destroy_mesh(skinned); }));
    const FrameStats& stats = system->stats();
    EXPECT_FALSE(stats.ms.empty()) << "no pass timings: the steps above did not run as assumed";
    EXPECT_GT(stats.fragments, 0u);
    destroy_and_expect_nothing_else(system, watch);
}

// System::create allocated its state before the System itself: when the second allocation failed, the
// first was never freed. Later ones fail inside Vulkan (the instance), which read as an unsupported device.
TEST(HostMemory, aCreateWhoseAllocationFailsFreesWhatItTookAndSaysSo) {
    struct Failing {
        Watch watch;
        long allocations = 0, fail_at = 0;
    };
    for (const long at : {0L, 1L, 2L, 5L, 10L, 20L, 40L}) {
        SCOPED_TRACE("allocation " + std::to_string(at));
        Failing failing{{}, 0, at};
        SystemDesc desc = small_desc(failing.watch);
        desc.hooks.user = &failing;
        desc.hooks.allocate = [](void* user, std::size_t bytes, std::size_t alignment) -> void* {
            auto* f = static_cast<Failing*>(user);
            if (f->allocations++ == f->fail_at) return nullptr;
            ++f->watch.live;
            return allocate(bytes, alignment);
        };
        desc.hooks.free = [](void* user, void* memory) {
            --static_cast<Failing*>(user)->watch.live;
            std::free(memory);
        };
        desc.hooks.log = nullptr;
        std::unique_ptr<System> system;
        const Outcome created = System::create(desc, system);
        EXPECT_EQ(created.code(), ErrorCode::DeviceFailure) << created.message();
        EXPECT_EQ(system, nullptr);
        EXPECT_EQ(failing.watch.live, 0) << "host allocations not freed";
    }
}

/// A System made from `desc` (its hooks the caller's) holding a moving 1 m box above the ground, as the
/// tests of failing allocations step it.
void make_with_moving_box(const SystemDesc& desc, std::unique_ptr<System>& system) {
    ASSERT_TRUE(System::create(desc, system));
    const Box box(1.0f);
    MeshId mesh = 0;
    InstanceId instance = 0;
    ASSERT_TRUE(system->create_mesh(box.desc(), mesh));
    ASSERT_TRUE(system->create_instance(mesh, translation(0, 2, 0), true, instance));
}

// The allocation hook may return null. When it does inside a step, the step fails with DeviceFailure, and
// since a step that failed part-way leaves the System's state unknown, every later step refuses to run
// rather than give wrong wind (it gave 0.2-0.6 m/s inside a static box, and 1.7 m/s for 2.95 upstream).
TEST(HostMemory, aStepWhoseAllocationFailsLeavesTheSystemRefusingLaterSteps) {
    struct Failing {
        long allocations = 0, fail_at = -1;
    };
    int failed_steps = 0;
    for (long extra = 1; extra <= 64 && failed_steps == 0; ++extra) {
        Failing failing;
        Watch watch;
        SystemDesc desc = small_desc(watch);
        desc.hooks.user = &failing;
        desc.hooks.log = nullptr;
        desc.hooks.allocate = [](void* user, std::size_t bytes, std::size_t alignment) -> void* {
            auto* f = static_cast<Failing*>(user);
            if (f->allocations++ == f->fail_at) return nullptr;
            return std::aligned_alloc(alignment, (bytes + alignment - 1) / alignment * alignment);
        };
        desc.hooks.free = [](void*, void* memory) { std::free(memory); };
        std::unique_ptr<System> system;
        ASSERT_NO_FATAL_FAILURE(make_with_moving_box(desc, system));
        failing.fail_at = failing.allocations + extra;
        const Outcome stepped = system->step(1.0f / 30.0f);
        if (stepped) continue; // the step made fewer allocations than that
        ++failed_steps;
        EXPECT_EQ(stepped.code(), ErrorCode::DeviceFailure) << stepped.message();
        for (int later = 0; later < 2; ++later) {
            const Outcome again = system->step(1.0f / 30.0f);
            EXPECT_EQ(again.code(), ErrorCode::DeviceFailure);
            EXPECT_NE(std::string(again.message()).find("an earlier step failed"), std::string::npos)
                << again.message();
        }
    }
    EXPECT_EQ(failed_steps, 1) << "no allocation of a step could be made to fail";
}

// gust's own memory may run out at any of its allocations in a step, once or for good. The step then
// fails with DeviceFailure; it never throws (a failure kept by allocating threw std::bad_alloc out of
// step) and later steps refuse to run. The driver's allocations through the hook are left alone here:
// lavapipe (Mesa 22.3) crashed inside vkCmdPipelineBarrier2 when its own allocation there fails, a fault
// of the driver's; for drivers that report a failed recording, vkEndCommandBuffer's result is checked and
// such a buffer is never submitted (docs/api.md, "Errors").
TEST(HostMemory, aStepFailsCleanlyWhereverGustsOwnMemoryRunsOut) {
    struct Failing {
        long ours = 0, fail_at = -1; // allocations gust's own code made, and the first to fail
        bool forever = false;
    };
    const auto make = [](Failing& failing, std::unique_ptr<System>& system) {
        Watch unused;
        SystemDesc desc = small_desc(unused);
        desc.hooks.user = &failing;
        desc.hooks.allocate = [](void* user, std::size_t bytes, std::size_t alignment) -> void* {
            auto* f = static_cast<Failing*>(user);
            const long n = only_gust_on_stack() ? f->ours++ : -1;
            if (n >= 0 && f->fail_at >= 0 && (n == f->fail_at || (f->forever && n > f->fail_at)))
                return nullptr;
            return allocate(bytes, alignment);
        };
        desc.hooks.free = [](void*, void* memory) { std::free(memory); };
        desc.hooks.log = nullptr;
        make_with_moving_box(desc, system);
    };
    long per_step = 0;
    {
        Failing counting;
        std::unique_ptr<System> system;
        ASSERT_NO_FATAL_FAILURE(make(counting, system));
        const long before = counting.ours;
        ASSERT_TRUE(system->step(1.0f / 30.0f));
        per_step = counting.ours - before;
    }
    ASSERT_GT(per_step, 4);
    for (const bool forever : {false, true})
        for (const long at : {0L, 1L, 2L, 3L, per_step / 4, per_step / 2, 3 * per_step / 4, per_step - 1}) {
            SCOPED_TRACE((forever ? "from allocation " : "at allocation ") + std::to_string(at) + " of " +
                         std::to_string(per_step));
            Failing failing;
            std::unique_ptr<System> system;
            ASSERT_NO_FATAL_FAILURE(make(failing, system));
            failing.forever = forever;
            failing.fail_at = failing.ours + at;
            const Outcome stepped = system->step(1.0f / 30.0f);
            failing.fail_at = -1;
            EXPECT_EQ(stepped.code(), ErrorCode::DeviceFailure) << stepped.message();
            const Outcome again = system->step(1.0f / 30.0f);
            EXPECT_NE(std::string(again.message()).find("an earlier step failed"), std::string::npos)
                << again.message();
        }
}

TEST(HostMemory, recordingFramesIntoTheHostsCommandBuffersAllocatesNothingElse) {
    g_gust_news = 0;
    HostVulkan host;
    ASSERT_TRUE(host.ok()) << host.error();
    constexpr std::uint32_t kFrames = 2;
    ASSERT_TRUE(host.start_frames(kFrames));
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.host = &host.device();
    desc.submission = Submission::HostCommands;
    desc.frames_in_flight = kFrames;
    std::unique_ptr<System> system;
    const Box box(1.0f);
    MeshId mesh = 0;
    InstanceId moving = 0;
    ASSERT_TRUE(counted([&] { return System::create(desc, system); }));
    ASSERT_TRUE(counted([&] { return system->create_mesh(box.desc(true), mesh); }));
    ASSERT_TRUE(counted([&] { return system->create_instance(mesh, translation(0, 2, 0), true, moving); }));
    ASSERT_TRUE(counted([&] { return system->set_ambient({2.0f, 0.0f, 1.0f}); }));
    const std::array<Vec3, 2> points = {Vec3{0, 2, 0}, Vec3{500, 0, 0}};
    std::vector<float> positions = box.positions;
    QueryId first = 0;
    for (std::uint32_t frame = 0; frame < kFrames + 4; ++frame) {
        for (float& p : positions)
            p *= 1.01f;
        ASSERT_TRUE(counted([&] { return system->set_vertices(mesh, positions.data(), 8); }));
        ASSERT_TRUE(
            counted([&] { return system->set_transform(moving, translation(0, 2, 0.5f * float(frame))); }));
        QueryId ticket = 0;
        ASSERT_TRUE(counted([&] { return system->query_async(points, ticket); }));
        if (frame == 0) first = ticket;
        VkCommandBuffer commands = host.begin_frame();
        ASSERT_NE(commands, VK_NULL_HANDLE);
        const Outcome stepped = counted([&] { return system->step(1.0f / 30.0f, commands); });
        ASSERT_TRUE(host.submit_frame());
        ASSERT_TRUE(stepped) << stepped.message();
    }
    std::array<Vec3, 2> wind{};
    ASSERT_TRUE(counted([&] { return system->fetch(first, wind); }));
    EXPECT_FALSE(system->stats().ms.empty())
        << "no frame's timings came back: the frames did not run as assumed";
    ASSERT_TRUE(host.finish_frames());
    destroy_and_expect_nothing_else(system, watch);
    EXPECT_EQ(host.messages(), 0);
}

} // namespace
} // namespace gust::test
