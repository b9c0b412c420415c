// Context::create(): gust's own instance (the Vulkan loader opened with dlopen, validation and the debug
// messenger when asked for), the choice of a physical device and the device gust creates on it.
#include "context_detail.hpp"
#include "vk_load.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <dlfcn.h>
#include <link.h>

namespace gust::gpu {

using namespace detail;

namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

bool contains_ignoring_case(std::string_view text, std::string_view part) {
    const auto same = [](char a, char b) {
        return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
    };
    return std::search(text.begin(), text.end(), part.begin(), part.end(), same) != text.end();
}

int type_rank(VkPhysicalDeviceType type) {
    switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return 1;
    default:
        return 0;
    }
}

} // namespace

std::pmr::vector<std::uintptr_t> detail::loaded_objects(std::pmr::memory_resource* memory) {
    std::pmr::vector<std::uintptr_t> objects(memory);
    dl_iterate_phdr(
        [](dl_phdr_info* info, std::size_t, void* out) {
            static_cast<std::pmr::vector<std::uintptr_t>*>(out)->push_back(info->dlpi_addr);
            return 0;
        },
        &objects);
    std::sort(objects.begin(), objects.end());
    return objects;
}

void detail::keep_drivers_loaded(std::span<const std::uintptr_t> before) {
    dl_iterate_phdr(
        [](dl_phdr_info* info, std::size_t, void* data) {
            const auto* old = static_cast<const std::span<const std::uintptr_t>*>(data);
            if (info->dlpi_name && info->dlpi_name[0] != '\0' &&
                !std::binary_search(old->begin(), old->end(), info->dlpi_addr))
                dlopen(info->dlpi_name, RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
            return 0;
        },
        &before);
}

Status Context::init(const ContextDesc& desc) {
    on_message_ = desc.on_message;
    objects_before_ = loaded_objects(host_memory_);
    loader_ = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!loader_) return Status::failure("cannot load the Vulkan loader libvulkan.so.1 (install libvulkan1)");
    vk_.vkGetInstanceProcAddr =
        reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(loader_, "vkGetInstanceProcAddr"));
    if (!vk_.vkGetInstanceProcAddr) return Status::failure("libvulkan.so.1 has no vkGetInstanceProcAddr");
    load_global_functions(vk_); // vkEnumerateInstanceVersion is null before Vulkan 1.1

    std::uint32_t version = VK_API_VERSION_1_0;
    if (vk_.vkEnumerateInstanceVersion) vk_.vkEnumerateInstanceVersion(&version);
    if (version < kApiVersion)
        return Status::failure("the Vulkan loader supports only " + version_string(version) +
                               "; gust needs Vulkan " + version_string(kApiVersion));

    std::pmr::vector<const char*> layers(host_memory_);
    std::pmr::vector<const char*> extensions(host_memory_);
    std::uint32_t count = 0;
    vk_.vkEnumerateInstanceExtensionProperties(nullptr, &count, nullptr);
    std::pmr::vector<VkExtensionProperties> available(count, host_memory_);
    vk_.vkEnumerateInstanceExtensionProperties(nullptr, &count, available.data());
    bool debug_utils = false;
    for (const auto& e : available)
        if (std::strcmp(e.extensionName, VK_EXT_DEBUG_UTILS_EXTENSION_NAME) == 0) debug_utils = true;
    if (desc.validation) {
        vk_.vkEnumerateInstanceLayerProperties(&count, nullptr);
        std::pmr::vector<VkLayerProperties> props(count, host_memory_);
        vk_.vkEnumerateInstanceLayerProperties(&count, props.data());
        const bool found = std::any_of(props.begin(), props.end(), [](const VkLayerProperties& p) {
            return std::strcmp(p.layerName, kValidationLayer) == 0;
        });
        if (!found)
            return Status::failure(std::string("validation was requested but ") + kValidationLayer +
                                   " is not installed (Debian: vulkan-validationlayers)");
        layers.push_back(kValidationLayer);
    }
    if (debug_utils) extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);

    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "gust";
    app.pEngineName = "gust";
    app.apiVersion = kApiVersion;
    const VkDebugUtilsMessengerCreateInfoEXT messenger = messenger_info(this);

    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pNext = debug_utils ? &messenger : nullptr; // also catches messages from create/destroy
    info.pApplicationInfo = &app;
    info.enabledLayerCount = std::uint32_t(layers.size());
    info.ppEnabledLayerNames = layers.data();
    info.enabledExtensionCount = std::uint32_t(extensions.size());
    info.ppEnabledExtensionNames = extensions.data();
    if (VkResult r = vk_.vkCreateInstance(&info, allocator(), &instance_); r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateInstance failed: ") + to_string(r));

    if (Status s = load_instance_table(vk_, instance_); !s) return s;
    if (debug_utils) {
        load_debug_functions(vk_, instance_);
    }
    if (debug_utils && vk_.vkCreateDebugUtilsMessengerEXT)
        vk_.vkCreateDebugUtilsMessengerEXT(instance_, &messenger, allocator(), &messenger_);

    pipeline_cache_path_ = desc.pipeline_cache;
    std::string_view override_spec = desc.device;
    if (override_spec.empty())
        if (const char* env = std::getenv("GUST_DEVICE")) override_spec = env;
    if (Status s = pick_device(override_spec, desc.device_uuid); !s) return s;
    return create_device(desc.external_memory, desc.needs_graphics);
}

Status Context::pick_device(std::string_view override_spec,
                            const std::optional<std::array<std::uint8_t, VK_UUID_SIZE>>& uuid) {
    std::uint32_t count = 0;
    VkResult listed = vk_.vkEnumeratePhysicalDevices(instance_, &count, nullptr);
    std::pmr::vector<VkPhysicalDevice> devices(host_memory_);
    if (listed == VK_SUCCESS) {
        devices.resize(count);
        listed = vk_.vkEnumeratePhysicalDevices(instance_, &count, devices.data());
        devices.resize(count);
    }
    // Out of host memory the loader leaves the handles null, and reading their properties aborted.
    if (listed != VK_SUCCESS && listed != VK_INCOMPLETE)
        return Status::failure(std::string("vkEnumeratePhysicalDevices failed: ") + to_string(listed));
    if (devices.empty())
        return Status::failure("no Vulkan device found (install mesa-vulkan-drivers for lavapipe)");

    int best_rank = -1;
    for (std::uint32_t i = 0; i < count; ++i) {
        VkPhysicalDeviceProperties props;
        vk_.vkGetPhysicalDeviceProperties(devices[i], &props);
        std::array<char, 16> index{};
        std::to_chars(index.data(), index.data() + index.size() - 1, i);
        std::pmr::string& entry = device_names_.emplace_back(index.data());
        entry.append(": ")
            .append(props.deviceName)
            .append(" (")
            .append(type_name(props.deviceType))
            .append(")");
        const bool usable = props.apiVersion >= kApiVersion;
        if (uuid) {
            // Another VkDevice's physical device (ContextDesc::device_uuid): only it can import gust's
            // memory.
            VkPhysicalDeviceIDProperties id{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES};
            VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &id};
            vk_.vkGetPhysicalDeviceProperties2(devices[i], &p2);
            if (usable && physical_ == VK_NULL_HANDLE &&
                std::equal(uuid->begin(), uuid->end(), std::begin(id.deviceUUID)))
                physical_ = devices[i];
            continue;
        }
        if (!override_spec.empty()) {
            // A number is an index only: "5" must not pick "llvmpipe (LLVM 15.0.6)" by its name.
            const bool numeric = override_spec.find_first_not_of("0123456789") == std::string_view::npos;
            const bool by_index = numeric && override_spec == index.data();
            const bool by_name = !numeric && contains_ignoring_case(props.deviceName, override_spec);
            if ((by_index || by_name) && physical_ == VK_NULL_HANDLE) {
                if (!usable)
                    return Status::failure("device '" + std::string(props.deviceName) +
                                           "' selected by GUST_DEVICE/--device supports only Vulkan " +
                                           std::to_string(VK_API_VERSION_MINOR(props.apiVersion)) +
                                           ".x; gust needs " + version_string(kApiVersion));
                physical_ = devices[i];
            }
            continue;
        }
        if (usable && type_rank(props.deviceType) > best_rank) {
            best_rank = type_rank(props.deviceType);
            physical_ = devices[i];
        }
    }
    if (physical_ == VK_NULL_HANDLE) {
        std::string list;
        for (const std::pmr::string& entry : device_names_)
            list.append(list.empty() ? "" : ", ").append(entry);
        if (uuid)
            return Status::failure("no Vulkan " + version_string(kApiVersion) +
                                   " device has the deviceUUID asked for; devices: " + list);
        if (!override_spec.empty())
            return Status::failure("no Vulkan device matches '" + std::string(override_spec) +
                                   "'; devices: " + list);
        return Status::failure("no Vulkan " + version_string(kApiVersion) +
                               " device found; devices: " + list);
    }
    return {};
}

Status Context::create_device(bool external_memory, bool needs_graphics) {
    if (Status s = check_support(vk_, physical_, host_memory_); !s) return s;
    VkPhysicalDeviceProperties props;
    vk_.vkGetPhysicalDeviceProperties(physical_, &props);

    const std::pmr::vector<VkQueueFamilyProperties> families = queue_families(vk_, physical_, host_memory_);
    const std::optional<std::uint32_t> family = pick_queue_family(families, needs_graphics);
    if (!family)
        return Status::failure(std::string("device '") + props.deviceName + "' has no " +
                               (needs_graphics ? "graphics+compute" : "compute") + " queue");
    queue_family_ = *family;

    const std::pmr::vector<VkExtensionProperties> exts = device_extensions(vk_, physical_, host_memory_);
    std::pmr::vector<const char*> enabled(kRequiredExtensions.begin(), kRequiredExtensions.end(),
                                          host_memory_);
    for (const char* name : kOptionalExtensions)
        if (has_extension(exts, name)) enabled.push_back(name);
    info_.conservative_rasterization = has_extension(exts, VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME);
    if (external_memory) {
        if (!has_extension(exts, VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME))
            return Status::failure(std::string("device '") + props.deviceName +
                                   "' lacks VK_KHR_external_memory_fd, which sharing gust's images needs");
        enabled.push_back(VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME);
    }

    FeatureChain features;
    for_each_feature(features.f2.features, features.f12,
                     [](VkBool32& enable, const char*) { enable = VK_TRUE; });

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue_info.queueFamilyIndex = queue_family_;
    queue_info.queueCount = 1;
    queue_info.pQueuePriorities = &priority;
    VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    info.pNext = &features.f2;
    info.queueCreateInfoCount = 1;
    info.pQueueCreateInfos = &queue_info;
    info.enabledExtensionCount = std::uint32_t(enabled.size());
    info.ppEnabledExtensionNames = enabled.data();
    if (VkResult r = vk_.vkCreateDevice(physical_, &info, allocator(), &device_); r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateDevice failed on '") + props.deviceName +
                               "': " + to_string(r));
    if (Status s = finish_device(0); !s) return s;
    if (external_memory)
        if (const std::string missing = load_external_memory_functions(vk_, device_); !missing.empty())
            return Status::failure("vkGetDeviceProcAddr returned null for " + missing);
    return {};
}

} // namespace gust::gpu
