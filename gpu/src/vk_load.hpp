// Filling a Dispatch table (gust/gpu/vk.hpp) from one of its X-macro lists: the one place an entry
// point is looked up by name. Private to the gpu module.
#pragma once

#include <gust/gpu/vk.hpp>
#include <string>

namespace gust::gpu::detail {

// One entry of an X-macro list, looked up through the `get` and `handle` in scope; an entry the loader
// returned null for is added to `missing`.
#define GUST_LOAD(name)                                                                                      \
    vk.name = reinterpret_cast<PFN_##name>(get(handle, #name));                                              \
    if (!vk.name) missing.append(missing.empty() ? "" : ", ").append(#name);

/// Loads GUST_VK_GLOBAL_FUNCTIONS through vk.vkGetInstanceProcAddr(VK_NULL_HANDLE, ...); returns the
/// names of those it got null for, comma-separated (empty when none).
inline std::string load_global_functions(Dispatch& vk) {
    const PFN_vkGetInstanceProcAddr get = vk.vkGetInstanceProcAddr;
    const VkInstance handle = VK_NULL_HANDLE;
    std::string missing;
    GUST_VK_GLOBAL_FUNCTIONS(GUST_LOAD)
    return missing;
}

/// Loads GUST_VK_INSTANCE_FUNCTIONS through vk.vkGetInstanceProcAddr(instance, ...); returns the names
/// it got null for, as load_global_functions.
inline std::string load_instance_functions(Dispatch& vk, VkInstance instance) {
    const PFN_vkGetInstanceProcAddr get = vk.vkGetInstanceProcAddr;
    const VkInstance handle = instance;
    std::string missing;
    GUST_VK_INSTANCE_FUNCTIONS(GUST_LOAD)
    return missing;
}

/// Loads GUST_VK_DEBUG_FUNCTIONS (VK_EXT_debug_utils) through vk.vkGetInstanceProcAddr(instance, ...);
/// returns the names it got null for, as load_global_functions.
inline std::string load_debug_functions(Dispatch& vk, VkInstance instance) {
    const PFN_vkGetInstanceProcAddr get = vk.vkGetInstanceProcAddr;
    const VkInstance handle = instance;
    std::string missing;
    GUST_VK_DEBUG_FUNCTIONS(GUST_LOAD)
    return missing;
}

/// Loads GUST_VK_DEVICE_FUNCTIONS through vk.vkGetDeviceProcAddr(device, ...); returns the names it got
/// null for, as load_global_functions.
inline std::string load_device_functions(Dispatch& vk, VkDevice device) {
    const PFN_vkGetDeviceProcAddr get = vk.vkGetDeviceProcAddr;
    const VkDevice handle = device;
    std::string missing;
    GUST_VK_DEVICE_FUNCTIONS(GUST_LOAD)
    return missing;
}

/// Loads GUST_VK_EXTERNAL_MEMORY_FUNCTIONS (VK_KHR_external_memory_fd) through vk.vkGetDeviceProcAddr(device,
/// ...); returns the names it got null for, as load_global_functions.
inline std::string load_external_memory_functions(Dispatch& vk, VkDevice device) {
    const PFN_vkGetDeviceProcAddr get = vk.vkGetDeviceProcAddr;
    const VkDevice handle = device;
    std::string missing;
    GUST_VK_EXTERNAL_MEMORY_FUNCTIONS(GUST_LOAD)
    return missing;
}

#undef GUST_LOAD

} // namespace gust::gpu::detail
