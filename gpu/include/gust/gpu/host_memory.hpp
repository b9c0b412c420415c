// Host memory: everything gust keeps on the CPU, and what Vulkan allocates on gust's behalf, comes
// from one std::pmr::memory_resource per Context (the engine's allocation hook; new/delete by default).
#pragma once

#include <cstddef>
#include <gust/gpu/vk.hpp>
#include <memory_resource>
#include <string>
#include <utility>
#include <vector>

namespace gust::gpu {

/// GPU milliseconds per named pass, in recording order.
using Timings = std::pmr::vector<std::pair<std::pmr::string, double>>;

/// Base of the objects the modules create: `new (memory) T(...)` takes the block from `memory` and
/// `delete` gives it back there, so a std::unique_ptr<T> keeps its default deleter. T's alignment must
/// not exceed alignof(std::max_align_t).
class HostObject {
  public:
    static void* operator new(std::size_t bytes, std::pmr::memory_resource* memory);
    static void operator delete(void* object) noexcept;
    /// Called only when T's constructor throws.
    static void operator delete(void* object, std::pmr::memory_resource* memory) noexcept;
};

/// VkAllocationCallbacks that take Vulkan's host memory from a resource; null (the driver's own
/// allocator) when the resource is new/delete. Not copyable: Vulkan keeps the callbacks' address.
class VulkanAllocator {
  public:
    explicit VulkanAllocator(std::pmr::memory_resource* memory);
    VulkanAllocator(const VulkanAllocator&) = delete;
    VulkanAllocator& operator=(const VulkanAllocator&) = delete;
    const VkAllocationCallbacks* callbacks() const { return use_ ? &callbacks_ : nullptr; }

  private:
    VkAllocationCallbacks callbacks_{};
    bool use_ = false;
};

} // namespace gust::gpu
