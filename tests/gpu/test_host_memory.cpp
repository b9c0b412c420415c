// gpu::VulkanAllocator and ContextDesc::memory: Vulkan's host allocations and the Context's own come from
// the given memory_resource, and all of it is given back.
#include "support/gpu_env.hpp"

#include <cstdint>
#include <cstring>
#include <gtest/gtest.h>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/context.hpp>
#include <gust/gpu/host_memory.hpp>
#include <memory>
#include <memory_resource>
#include <new>
#include <vector>

namespace gust::test {
namespace {

/// new/delete that counts what is live, and runs out while `empty` is set.
class CountingResource final : public std::pmr::memory_resource {
  public:
    long live = 0, allocations = 0;
    bool empty = false;

  private:
    void* do_allocate(std::size_t bytes, std::size_t alignment) override {
        if (empty) throw std::bad_alloc();
        ++live;
        ++allocations;
        return std::pmr::new_delete_resource()->allocate(bytes, alignment);
    }
    void do_deallocate(void* p, std::size_t bytes, std::size_t alignment) override {
        --live;
        std::pmr::new_delete_resource()->deallocate(p, bytes, alignment);
    }
    bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
        return this == &other;
    }
};

/// A validated Context taking its host memory from `memory`.
std::unique_ptr<gpu::Context> context_on(std::pmr::memory_resource& memory) {
    gpu::ContextDesc desc;
    desc.validation = true;
    desc.memory = &memory;
    auto ctx = gpu::Context::create(desc);
    EXPECT_TRUE(ctx) << ctx.message();
    return ctx ? std::move(*ctx) : nullptr;
}

TEST(VulkanAllocator, leavesVulkanToTheDriverForNewDeleteAndCallsTheResourceOtherwise) {
    EXPECT_EQ(gpu::VulkanAllocator(std::pmr::new_delete_resource()).callbacks(), nullptr);
    CountingResource counting;
    const gpu::VulkanAllocator allocator(&counting);
    const VkAllocationCallbacks* cb = allocator.callbacks();
    ASSERT_NE(cb, nullptr);
    void* p = cb->pfnAllocation(cb->pUserData, 100, 8, VK_SYSTEM_ALLOCATION_SCOPE_OBJECT);
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(counting.live, 1);
    cb->pfnFree(cb->pUserData, p);
    EXPECT_EQ(counting.live, 0);
    cb->pfnFree(cb->pUserData, nullptr);
    EXPECT_EQ(counting.live, 0);
}

TEST(VulkanAllocator, reallocationKeepsTheContentsAndTheAlignment) {
    CountingResource counting;
    const gpu::VulkanAllocator allocator(&counting);
    const VkAllocationCallbacks* cb = allocator.callbacks();
    ASSERT_NE(cb, nullptr);
    constexpr std::size_t kAlign = 256;
    auto* p = static_cast<std::uint8_t*>(
        cb->pfnReallocation(cb->pUserData, nullptr, 40, kAlign, VK_SYSTEM_ALLOCATION_SCOPE_COMMAND));
    ASSERT_NE(p, nullptr);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % kAlign, 0u);
    for (std::uint8_t i = 0; i < 40; ++i)
        p[i] = std::uint8_t(i * 7 + 1);

    auto* grown = static_cast<std::uint8_t*>(
        cb->pfnReallocation(cb->pUserData, p, 5000, kAlign, VK_SYSTEM_ALLOCATION_SCOPE_COMMAND));
    ASSERT_NE(grown, nullptr);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(grown) % kAlign, 0u);
    for (std::uint8_t i = 0; i < 40; ++i)
        ASSERT_EQ(grown[i], std::uint8_t(i * 7 + 1)) << "byte " << int(i);
    EXPECT_EQ(counting.live, 1);

    auto* shrunk = static_cast<std::uint8_t*>(
        cb->pfnReallocation(cb->pUserData, grown, 10, 16, VK_SYSTEM_ALLOCATION_SCOPE_COMMAND));
    ASSERT_NE(shrunk, nullptr);
    for (std::uint8_t i = 0; i < 10; ++i)
        ASSERT_EQ(shrunk[i], std::uint8_t(i * 7 + 1)) << "byte " << int(i);
    EXPECT_EQ(cb->pfnReallocation(cb->pUserData, shrunk, 0, 16, VK_SYSTEM_ALLOCATION_SCOPE_COMMAND), nullptr);
    EXPECT_EQ(counting.live, 0);
}

TEST(ContextHostMemory, theContextAndVulkanTakeTheirHostMemoryFromTheResourceAndGiveItAllBack) {
    CountingResource counting;
    {
        auto ctx = context_on(counting);
        ASSERT_TRUE(ctx);
        gpu::Context& c = *ctx;
        EXPECT_EQ(c.memory(), &counting);
        EXPECT_NE(c.allocator(), nullptr);
        const long after_create = counting.allocations;
        EXPECT_GT(after_create, 1) << "the instance and device took no host memory from the resource";

        auto buffer = gpu::Buffer::create(c, 4096, gpu::MemoryUse::Device);
        ASSERT_TRUE(buffer) << buffer.message();
        std::uint32_t words[16] = {};
        ASSERT_TRUE(gpu::download(c, *buffer, words, sizeof(words)));
        EXPECT_GT(counting.allocations, after_create) << "the buffer and its submission took none";
        EXPECT_EQ(c.validation_messages(), 0u) << c.last_validation_message();
    }
    EXPECT_EQ(counting.live, 0) << "host allocations not given back";
}

// A buffer released while frames are in flight is kept until they complete. Keeping it needs no memory
// then: each buffer reserved its place when it was made. When the host's memory had run out, the release
// threw from a noexcept move (std::terminate); the fallback that freed the buffer at once could free one a
// frame recorded into the host's command buffer would still read.
TEST(BufferRelease, whileFramesAreInFlightNeedsNoMemoryAndCreationFailsCleanlyWithout) {
    CountingResource memory;
    auto ctx = context_on(memory);
    ASSERT_TRUE(ctx);
    ctx->begin_frame(1);
    std::vector<gpu::Buffer> buffers;
    for (int i = 0; i < 40; ++i) {
        auto b = gpu::Buffer::create(*ctx, 256, gpu::MemoryUse::Device);
        ASSERT_TRUE(b) << b.message();
        buffers.push_back(std::move(*b));
    }
    memory.empty = true;
    const auto refused = gpu::Buffer::create(*ctx, 256, gpu::MemoryUse::Device);
    EXPECT_FALSE(refused) << "a buffer that could not be released later is not made";
    buffers.clear(); // every one released into the list, without allocating
    memory.empty = false;
    ctx->retire(1);
    EXPECT_EQ(ctx->validation_messages(), 0u) << ctx->last_validation_message();
}

} // namespace
} // namespace gust::test
