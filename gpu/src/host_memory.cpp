#include <algorithm>
#include <cstring>
#include <gust/gpu/host_memory.hpp>
#include <new>

namespace gust::gpu {
namespace {

/// What precedes each block handed out: where it came from and how it was asked for. Vulkan frees and
/// reallocates by pointer alone, and a memory_resource wants the size and alignment back.
struct alignas(std::max_align_t) Header {
    std::pmr::memory_resource* memory = nullptr;
    std::size_t bytes = 0;     ///< the whole block, header included
    std::size_t alignment = 0; ///< the whole block's
    std::size_t size = 0;      ///< what the caller asked for
};

void* take(std::pmr::memory_resource* memory, std::size_t size, std::size_t alignment) {
    alignment = std::max(alignment, alignof(Header));
    const std::size_t offset = (sizeof(Header) + alignment - 1) / alignment * alignment;
    auto* block = static_cast<std::byte*>(memory->allocate(offset + size, alignment));
    void* user = block + offset;
    new (static_cast<std::byte*>(user) - sizeof(Header)) Header{memory, offset + size, alignment, size};
    return user;
}

Header& header_of(void* user) {
    return *std::launder(reinterpret_cast<Header*>(static_cast<std::byte*>(user) - sizeof(Header)));
}

void give_back(void* user) {
    const Header h = header_of(user);
    const std::size_t offset = h.bytes - h.size;
    h.memory->deallocate(static_cast<std::byte*>(user) - offset, h.bytes, h.alignment);
}

void* VKAPI_CALL vk_allocate(void* memory, std::size_t size, std::size_t alignment, VkSystemAllocationScope) {
    try {
        return take(static_cast<std::pmr::memory_resource*>(memory), size, alignment);
    } catch (const std::bad_alloc&) {
        return nullptr;
    }
}

void VKAPI_CALL vk_free(void*, void* user) {
    if (user) give_back(user);
}

void* VKAPI_CALL vk_reallocate(void* memory, void* original, std::size_t size, std::size_t alignment,
                               VkSystemAllocationScope scope) {
    if (!original) return vk_allocate(memory, size, alignment, scope);
    if (size == 0) {
        give_back(original);
        return nullptr;
    }
    void* moved = vk_allocate(memory, size, alignment, scope);
    if (!moved) return nullptr;
    std::memcpy(moved, original, std::min(size, header_of(original).size));
    give_back(original);
    return moved;
}

} // namespace

void* HostObject::operator new(std::size_t bytes, std::pmr::memory_resource* memory) {
    return take(memory, bytes, alignof(std::max_align_t));
}

void HostObject::operator delete(void* object) noexcept {
    if (object) give_back(object);
}

void HostObject::operator delete(void* object, std::pmr::memory_resource*) noexcept {
    if (object) give_back(object);
}

VulkanAllocator::VulkanAllocator(std::pmr::memory_resource* memory)
    : use_(memory && !memory->is_equal(*std::pmr::new_delete_resource())) {
    callbacks_.pUserData = memory;
    callbacks_.pfnAllocation = vk_allocate;
    callbacks_.pfnReallocation = vk_reallocate;
    callbacks_.pfnFree = vk_free;
}

} // namespace gust::gpu
