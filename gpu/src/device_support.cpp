// What gust needs of a device and the queries that check it, shared by Context::create() and
// Context::adopt() and handed to hosts (device_requirements(), add_required_features(),
// check_device_support()).
#include "context_detail.hpp"
#include "vk_load.hpp"

#include <algorithm>
#include <cstring>

namespace gust::gpu {
namespace detail {

void append(std::string& list, const char* name) {
    list += (list.empty() ? "" : ", ") + std::string(name);
}

std::string version_string(std::uint32_t version) {
    return std::to_string(VK_API_VERSION_MAJOR(version)) + "." +
           std::to_string(VK_API_VERSION_MINOR(version));
}

const char* type_name(VkPhysicalDeviceType type) {
    switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return "cpu";
    default:
        return "other";
    }
}

std::pmr::vector<VkExtensionProperties> device_extensions(const Dispatch& vk, VkPhysicalDevice physical,
                                                          std::pmr::memory_resource* memory) {
    std::uint32_t count = 0;
    vk.vkEnumerateDeviceExtensionProperties(physical, nullptr, &count, nullptr);
    std::pmr::vector<VkExtensionProperties> exts(count, memory);
    vk.vkEnumerateDeviceExtensionProperties(physical, nullptr, &count, exts.data());
    return exts;
}

bool has_extension(std::span<const VkExtensionProperties> exts, const char* name) {
    return std::any_of(exts.begin(), exts.end(), [&](const VkExtensionProperties& e) {
        return std::strcmp(name, e.extensionName) == 0;
    });
}

std::pmr::vector<VkQueueFamilyProperties> queue_families(const Dispatch& vk, VkPhysicalDevice physical,
                                                         std::pmr::memory_resource* memory) {
    std::uint32_t count = 0;
    vk.vkGetPhysicalDeviceQueueFamilyProperties(physical, &count, nullptr);
    std::pmr::vector<VkQueueFamilyProperties> families(count, memory);
    vk.vkGetPhysicalDeviceQueueFamilyProperties(physical, &count, families.data());
    return families;
}

Status load_instance_table(Dispatch& vk, VkInstance instance) {
    if (const std::string missing = load_instance_functions(vk, instance); !missing.empty())
        return Status::failure("vkGetInstanceProcAddr returned null for " + missing +
                               " (is the instance Vulkan 1.2?)");
    return {};
}

Status check_support(const Dispatch& vk, VkPhysicalDevice physical, std::pmr::memory_resource* memory) {
    VkPhysicalDeviceProperties props;
    vk.vkGetPhysicalDeviceProperties(physical, &props);
    const auto device = [&] { return "device '" + std::string(props.deviceName) + "'"; }; // on failure only
    if (props.apiVersion < kApiVersion)
        return Status::failure(device() + " supports only Vulkan " + version_string(props.apiVersion) +
                               "; gust needs " + version_string(kApiVersion));
    FeatureChain have;
    vk.vkGetPhysicalDeviceFeatures2(physical, &have.f2);
    std::string missing_features;
    for_each_feature(have.f2.features, have.f12, [&](VkBool32 supported, const char* name) {
        if (!supported) append(missing_features, name);
    });
    const std::pmr::vector<VkExtensionProperties> exts = device_extensions(vk, physical, memory);
    std::string missing_extensions;
    for (const char* name : kRequiredExtensions)
        if (!has_extension(exts, name)) append(missing_extensions, name);
    std::string message;
    if (!missing_features.empty()) message = device() + " lacks required features: " + missing_features;
    if (!missing_extensions.empty())
        message += (message.empty() ? device() : std::string(";")) +
                   " lacks required extensions: " + missing_extensions;
    if (!message.empty()) return Status::failure(message);
    return {};
}

} // namespace detail

using namespace detail;

DeviceRequirements device_requirements() {
    DeviceRequirements req;
    req.api_version = kApiVersion;
    req.extensions.assign(kRequiredExtensions.begin(), kRequiredExtensions.end());
    req.optional_extensions.assign(kOptionalExtensions.begin(), kOptionalExtensions.end());
    FeatureChain chain;
    for_each_feature(chain.f2.features, chain.f12,
                     [&](VkBool32&, const char* name) { req.features.push_back(name); });
    return req;
}

Status add_required_features(VkPhysicalDeviceFeatures2& features) {
    VkPhysicalDeviceVulkan12Features* f12 = nullptr;
    for (auto* s = static_cast<VkBaseOutStructure*>(features.pNext); s; s = s->pNext)
        if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES)
            f12 = reinterpret_cast<VkPhysicalDeviceVulkan12Features*>(s);
    if (!f12)
        return Status::failure("the pNext chain of VkPhysicalDeviceFeatures2 lacks "
                               "VkPhysicalDeviceVulkan12Features, where gust's required features are set");
    for_each_feature(features.features, *f12, [](VkBool32& enable, const char*) { enable = VK_TRUE; });
    return {};
}

Status check_device_support(PFN_vkGetInstanceProcAddr get_instance_proc_addr, VkInstance instance,
                            VkPhysicalDevice physical_device) {
    if (!get_instance_proc_addr || !instance || !physical_device)
        return Status::failure("check_device_support needs vkGetInstanceProcAddr, an instance and a "
                               "physical device (one is null)");
    Dispatch vk;
    vk.vkGetInstanceProcAddr = get_instance_proc_addr;
    if (Status s = load_instance_table(vk, instance); !s) return s;
    return check_support(vk, physical_device, std::pmr::new_delete_resource());
}

std::optional<std::uint32_t> pick_queue_family(std::span<const VkQueueFamilyProperties> families,
                                               bool needs_graphics) {
    const auto first = [&](VkQueueFlags graphics) -> std::optional<std::uint32_t> {
        for (std::uint32_t i = 0; i < families.size(); ++i) {
            const VkQueueFlags flags = families[i].queueFlags;
            if (families[i].queueCount > 0 && (flags & VK_QUEUE_COMPUTE_BIT) &&
                (flags & VK_QUEUE_GRAPHICS_BIT) == graphics)
                return i;
        }
        return std::nullopt;
    };
    // A compute-only family is a second hardware queue beside the game's graphics one (AMD's async
    // compute engines, NVIDIA's compute family), so gust's step overlaps the game's rendering instead of
    // waiting for a gap in it.
    if (!needs_graphics)
        if (std::optional<std::uint32_t> async = first(0)) return async;
    return first(VK_QUEUE_GRAPHICS_BIT);
}

} // namespace gust::gpu
