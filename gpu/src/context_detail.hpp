// What the Context's files share: gust's device requirements and the queries that check them
// (device_support.cpp), and the debug messenger (context.cpp). Private to the gpu module.
#pragma once

#include <array>
#include <gust/gpu/context.hpp>
#include <memory_resource>
#include <span>
#include <string>
#include <vector>

namespace gust::gpu::detail {

/// What device_requirements() lists beyond the features.
inline constexpr std::uint32_t kApiVersion = VK_API_VERSION_1_2;
inline constexpr std::array<const char*, 0> kRequiredExtensions{};
inline constexpr std::array kOptionalExtensions{VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME};

// The one list of device features gust uses: create() enables it, adopt() and check_device_support()
// check it, add_required_features() hands it to a host. vertexPipelineStoresAndAtomics because
// voxelize.geom counts rejected triangles with an atomic. Nothing of Vulkan 1.3 (synchronization2,
// dynamic rendering, maintenance4) nor scalarBlockLayout: Godot 4 creates its device with Vulkan 1.2 and
// none of them (docs/godot.md), so gust records Vulkan 1.0 barriers and render passes, and its shaders,
// SPIR-V 1.5, keep every block within the relaxed layout Vulkan 1.2 validates.
template <class Fn>
void for_each_feature(VkPhysicalDeviceFeatures& f, VkPhysicalDeviceVulkan12Features& f12, Fn&& fn) {
    fn(f.geometryShader, "geometryShader");
    fn(f.fragmentStoresAndAtomics, "fragmentStoresAndAtomics");
    fn(f.vertexPipelineStoresAndAtomics, "vertexPipelineStoresAndAtomics");
    fn(f.shaderInt64, "shaderInt64");
    fn(f12.bufferDeviceAddress, "bufferDeviceAddress");
}

// VkPhysicalDeviceFeatures2 -> Vulkan12Features, chained (so neither copied nor moved).
struct FeatureChain {
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    FeatureChain() = default;
    FeatureChain(const FeatureChain&) = delete;
    FeatureChain& operator=(const FeatureChain&) = delete;
};

/// Load addresses of the shared objects the process holds now.
std::pmr::vector<std::uintptr_t> loaded_objects(std::pmr::memory_resource* memory);
/// Marks every shared object loaded since `before` (loaded_objects) as never to be unloaded. The Vulkan
/// loader unloads its drivers with the last instance and loads them again with the next, and glibc never
/// gives back the static TLS of an unloaded library: NVIDIA's driver (libnvidia-tls) failed to load at
/// the 30th System of one process ("cannot allocate memory in static TLS block", so vkCreateInstance
/// found no driver). Kept loaded, each later instance finds it in place.
void keep_drivers_loaded(std::span<const std::uintptr_t> before);

/// Adds `name` to a comma-separated list.
void append(std::string& list, const char* name);
/// "1.3" for VK_API_VERSION_1_3.
std::string version_string(std::uint32_t version);
/// "discrete", "integrated", "virtual", "cpu" or "other".
const char* type_name(VkPhysicalDeviceType type);

std::pmr::vector<VkExtensionProperties> device_extensions(const Dispatch& vk, VkPhysicalDevice physical,
                                                          std::pmr::memory_resource* memory);
bool has_extension(std::span<const VkExtensionProperties> exts, const char* name);
std::pmr::vector<VkQueueFamilyProperties> queue_families(const Dispatch& vk, VkPhysicalDevice physical,
                                                         std::pmr::memory_resource* memory);

/// Loads the instance-level table through vk.vkGetInstanceProcAddr; fails naming what it did not return.
Status load_instance_table(Dispatch& vk, VkInstance instance);
/// What `physical` lacks of device_requirements(), every item named; ok when nothing.
Status check_support(const Dispatch& vk, VkPhysicalDevice physical, std::pmr::memory_resource* memory);

/// A debug messenger that routes warnings and errors to ctx->report().
VkDebugUtilsMessengerCreateInfoEXT messenger_info(Context* ctx);

} // namespace gust::gpu::detail
