#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <dlfcn.h>
#include <filesystem>
#include <fstream>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/context.hpp>
#include <unistd.h>

namespace gust::gpu {

namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

/// The pipeline cache file: this header, then the blob vkGetPipelineCacheData gave. Vulkan must get the
/// blob back whole (its size as written), which its own header cannot tell, so a file cut short or
/// damaged is recognised by this one and never reaches the driver.
struct CacheFileHeader {
    char magic[8];
    std::uint64_t bytes;    ///< of the blob that follows
    std::uint64_t checksum; ///< fnv1a() of the blob
};
constexpr char kCacheMagic[8] = {'g', 'u', 's', 't', 'p', 'c', '0', '1'};

/// FNV-1a, 64 bits: enough to tell a damaged file from a good one (not an adversary's).
std::uint64_t fnv1a(const char* data, std::size_t bytes) {
    std::uint64_t hash = 14695981039346656037ull;
    for (std::size_t i = 0; i < bytes; ++i) {
        hash ^= static_cast<unsigned char>(data[i]);
        hash *= 1099511628211ull;
    }
    return hash;
}

/// The blob of a pipeline cache file when it is whole and holds the cache of the device `props`
/// describes; empty otherwise (no file, another format, cut short, damaged, another device or driver).
std::pmr::vector<char> read_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props,
                                           std::pmr::memory_resource* memory) {
    std::pmr::vector<char> file(memory);
    std::error_code ec;
    // A folder or a device file is no cache (and reading a folder throws).
    if (!std::filesystem::is_regular_file(path, ec)) return file;
    std::ifstream in(path, std::ios::binary);
    file.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    std::pmr::vector<char> blob(memory);
    CacheFileHeader header{};
    if (file.size() < sizeof(header)) return blob;
    std::memcpy(&header, file.data(), sizeof(header));
    const char* data = file.data() + sizeof(header);
    if (std::memcmp(header.magic, kCacheMagic, sizeof(kCacheMagic)) != 0 ||
        header.bytes != file.size() - sizeof(header) || header.checksum != fnv1a(data, header.bytes))
        return blob;
    // Vulkan's own header (VkPipelineCacheHeaderVersionOne) names the device and driver build.
    VkPipelineCacheHeaderVersionOne vk_header{};
    if (header.bytes < sizeof(vk_header)) return blob;
    std::memcpy(&vk_header, data, sizeof(vk_header));
    if (vk_header.headerVersion != VK_PIPELINE_CACHE_HEADER_VERSION_ONE ||
        vk_header.vendorID != props.vendorID || vk_header.deviceID != props.deviceID ||
        std::memcmp(vk_header.pipelineCacheUUID, props.pipelineCacheUUID, VK_UUID_SIZE) != 0)
        return blob;
    blob.assign(data, data + header.bytes);
    return blob;
}

bool contains_ignoring_case(std::string_view text, std::string_view part) {
    const auto same = [](char a, char b) {
        return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
    };
    return std::search(text.begin(), text.end(), part.begin(), part.end(), same) != text.end();
}

/// What device_requirements() lists beyond the features.
constexpr std::uint32_t kApiVersion = VK_API_VERSION_1_3;
constexpr std::array<const char*, 0> kRequiredExtensions{};
constexpr std::array kOptionalExtensions{VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME};

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

std::string version_string(std::uint32_t version) {
    return std::to_string(VK_API_VERSION_MAJOR(version)) + "." +
           std::to_string(VK_API_VERSION_MINOR(version));
}

void append(std::string& list, const char* name) {
    list += (list.empty() ? "" : ", ") + std::string(name);
}

// The one list of device features gust uses: create() enables it, adopt() and check_device_support()
// check it, add_required_features() hands it to a host. vertexPipelineStoresAndAtomics because
// voxelize.geom counts rejected triangles with an atomic.
template <class Fn>
void for_each_feature(VkPhysicalDeviceFeatures& f, VkPhysicalDeviceVulkan12Features& f12,
                      VkPhysicalDeviceVulkan13Features& f13, Fn&& fn) {
    fn(f.geometryShader, "geometryShader");
    fn(f.fragmentStoresAndAtomics, "fragmentStoresAndAtomics");
    fn(f.vertexPipelineStoresAndAtomics, "vertexPipelineStoresAndAtomics");
    fn(f.shaderInt64, "shaderInt64");
    fn(f12.bufferDeviceAddress, "bufferDeviceAddress");
    fn(f12.scalarBlockLayout, "scalarBlockLayout");
    fn(f13.synchronization2, "synchronization2");
    fn(f13.dynamicRendering, "dynamicRendering");
    fn(f13.maintenance4, "maintenance4");
}

// VkPhysicalDeviceFeatures2 -> Vulkan12Features -> Vulkan13Features, chained (so neither copied nor moved).
struct FeatureChain {
    VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &f13};
    VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    FeatureChain() = default;
    FeatureChain(const FeatureChain&) = delete;
    FeatureChain& operator=(const FeatureChain&) = delete;
};

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

bool graphics_and_compute(const VkQueueFamilyProperties& family) {
    const VkQueueFlags want = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
    return (family.queueFlags & want) == want;
}

// Loads the instance-level table through vk.vkGetInstanceProcAddr; fails naming what it did not return.
Status load_instance_functions(Dispatch& vk, VkInstance instance) {
    std::string missing;
#define GUST_LOAD(name)                                                                                      \
    vk.name = reinterpret_cast<PFN_##name>(vk.vkGetInstanceProcAddr(instance, #name));                       \
    if (!vk.name) append(missing, #name);
    GUST_VK_INSTANCE_FUNCTIONS(GUST_LOAD)
#undef GUST_LOAD
    if (!missing.empty())
        return Status::failure("vkGetInstanceProcAddr returned null for " + missing +
                               " (is the instance Vulkan 1.3?)");
    return {};
}

// What `physical` lacks of device_requirements(), every item named; ok when nothing.
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
    for_each_feature(have.f2.features, have.f12, have.f13, [&](VkBool32 supported, const char* name) {
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

VKAPI_ATTR VkBool32 VKAPI_CALL debug_callback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                              VkDebugUtilsMessageTypeFlagsEXT types,
                                              const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    Severity s = Severity::Info;
    if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)
        s = Severity::Error;
    else if (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT)
        s = Severity::Warning;
    const bool validation = (types & VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT) != 0;
    static_cast<Context*>(user)->report(s, validation, data->pMessage ? data->pMessage : "");
    return VK_FALSE;
}

VkDebugUtilsMessengerCreateInfoEXT messenger_info(Context* ctx) {
    VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    info.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    info.pfnUserCallback = debug_callback;
    info.pUserData = ctx;
    return info;
}

} // namespace

DeviceRequirements device_requirements() {
    DeviceRequirements req;
    req.api_version = kApiVersion;
    req.extensions.assign(kRequiredExtensions.begin(), kRequiredExtensions.end());
    req.optional_extensions.assign(kOptionalExtensions.begin(), kOptionalExtensions.end());
    FeatureChain chain;
    for_each_feature(chain.f2.features, chain.f12, chain.f13,
                     [&](VkBool32&, const char* name) { req.features.push_back(name); });
    return req;
}

Status add_required_features(VkPhysicalDeviceFeatures2& features) {
    VkPhysicalDeviceVulkan12Features* f12 = nullptr;
    VkPhysicalDeviceVulkan13Features* f13 = nullptr;
    for (auto* s = static_cast<VkBaseOutStructure*>(features.pNext); s; s = s->pNext) {
        if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES)
            f12 = reinterpret_cast<VkPhysicalDeviceVulkan12Features*>(s);
        if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES)
            f13 = reinterpret_cast<VkPhysicalDeviceVulkan13Features*>(s);
    }
    std::string missing;
    if (!f12) append(missing, "VkPhysicalDeviceVulkan12Features");
    if (!f13) append(missing, "VkPhysicalDeviceVulkan13Features");
    if (!missing.empty())
        return Status::failure("the pNext chain of VkPhysicalDeviceFeatures2 lacks " + missing +
                               ", where gust's required features are set");
    for_each_feature(features.features, *f12, *f13, [](VkBool32& enable, const char*) { enable = VK_TRUE; });
    return {};
}

Status check_device_support(PFN_vkGetInstanceProcAddr get_instance_proc_addr, VkInstance instance,
                            VkPhysicalDevice physical_device) {
    if (!get_instance_proc_addr || !instance || !physical_device)
        return Status::failure("check_device_support needs vkGetInstanceProcAddr, an instance and a "
                               "physical device (one is null)");
    Dispatch vk;
    vk.vkGetInstanceProcAddr = get_instance_proc_addr;
    if (Status s = load_instance_functions(vk, instance); !s) return s;
    return check_support(vk, physical_device, std::pmr::new_delete_resource());
}

const char* to_string(VkResult result) {
    switch (result) {
    case VK_SUCCESS:
        return "VK_SUCCESS";
    case VK_NOT_READY:
        return "VK_NOT_READY";
    case VK_TIMEOUT:
        return "VK_TIMEOUT";
    case VK_INCOMPLETE:
        return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY:
        return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
        return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED:
        return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST:
        return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_LAYER_NOT_PRESENT:
        return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT:
        return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT:
        return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
        return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS:
        return "VK_ERROR_TOO_MANY_OBJECTS";
    default:
        return "VkResult error";
    }
}

Context::Context(std::pmr::memory_resource* memory)
    : host_memory_(memory),
      allocator_(memory), info_{.name = std::pmr::string(memory), .driver = std::pmr::string(memory)},
      device_names_(memory), released_(memory), last_message_(memory) {}

Result<std::unique_ptr<Context>> Context::create(const ContextDesc& desc) {
    std::pmr::memory_resource* memory = desc.memory ? desc.memory : std::pmr::new_delete_resource();
    std::unique_ptr<Context> ctx(new (memory) Context(memory));
    if (Status s = ctx->init(desc); !s) return s;
    return ctx;
}

Result<std::unique_ptr<Context>> Context::adopt(const HostDevice& host) {
    std::pmr::memory_resource* memory = host.memory ? host.memory : std::pmr::new_delete_resource();
    std::unique_ptr<Context> ctx(new (memory) Context(memory));
    if (Status s = ctx->init_adopted(host); !s) return s;
    return ctx;
}

void Context::report(Severity severity, bool validation, const std::string& message) {
    if (validation && severity != Severity::Info) {
        validation_messages_.fetch_add(1);
        std::lock_guard lock(message_mutex_);
        last_message_ = message;
    }
    if (on_message_) on_message_(severity, message);
}

std::string Context::last_validation_message() const {
    std::lock_guard lock(message_mutex_);
    return std::string(last_message_);
}

Status Context::init(const ContextDesc& desc) {
    on_message_ = desc.on_message;
    loader_ = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!loader_) return Status::failure("cannot load the Vulkan loader libvulkan.so.1 (install libvulkan1)");
    vk_.vkGetInstanceProcAddr =
        reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(loader_, "vkGetInstanceProcAddr"));
    if (!vk_.vkGetInstanceProcAddr) return Status::failure("libvulkan.so.1 has no vkGetInstanceProcAddr");
#define GUST_LOAD(name)                                                                                      \
    vk_.name = reinterpret_cast<PFN_##name>(vk_.vkGetInstanceProcAddr(VK_NULL_HANDLE, #name));
    GUST_VK_GLOBAL_FUNCTIONS(GUST_LOAD)
#undef GUST_LOAD

    std::uint32_t version = VK_API_VERSION_1_0;
    if (vk_.vkEnumerateInstanceVersion) vk_.vkEnumerateInstanceVersion(&version);
    if (version < VK_API_VERSION_1_3)
        return Status::failure("the Vulkan loader supports only " + version_string(version) +
                               "; gust needs Vulkan 1.3");

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
    app.apiVersion = VK_API_VERSION_1_3;
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

    if (Status s = load_instance_functions(vk_, instance_); !s) return s;
    if (debug_utils) {
#define GUST_LOAD(name) vk_.name = reinterpret_cast<PFN_##name>(vk_.vkGetInstanceProcAddr(instance_, #name));
        GUST_VK_DEBUG_FUNCTIONS(GUST_LOAD)
#undef GUST_LOAD
    }
    if (debug_utils && vk_.vkCreateDebugUtilsMessengerEXT)
        vk_.vkCreateDebugUtilsMessengerEXT(instance_, &messenger, allocator(), &messenger_);

    pipeline_cache_path_ = desc.pipeline_cache;
    std::string_view override_spec = desc.device;
    if (override_spec.empty())
        if (const char* env = std::getenv("GUST_DEVICE")) override_spec = env;
    if (Status s = pick_device(override_spec); !s) return s;
    return create_device();
}

Status Context::pick_device(std::string_view override_spec) {
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
        const bool usable = props.apiVersion >= VK_API_VERSION_1_3;
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
                                           ".x; gust needs 1.3");
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
        if (!override_spec.empty())
            return Status::failure("no Vulkan device matches '" + std::string(override_spec) +
                                   "'; devices: " + list);
        return Status::failure("no Vulkan 1.3 device found; devices: " + list);
    }
    return {};
}

Status Context::init_adopted(const HostDevice& host) {
    owns_device_ = false;
    std::string null_fields;
    if (!host.instance) append(null_fields, "instance");
    if (!host.physical_device) append(null_fields, "physical_device");
    if (!host.device) append(null_fields, "device");
    if (!host.get_instance_proc_addr) append(null_fields, "get_instance_proc_addr");
    if (!null_fields.empty()) return Status::failure("HostDevice: " + null_fields + " must not be null");
    on_message_ = host.on_message;
    queue_mutex_ = host.queue_mutex;
    instance_ = host.instance;
    physical_ = host.physical_device;

    vk_.vkGetInstanceProcAddr = host.get_instance_proc_addr;
#define GUST_LOAD(name)                                                                                      \
    vk_.name = reinterpret_cast<PFN_##name>(vk_.vkGetInstanceProcAddr(VK_NULL_HANDLE, #name));
    GUST_VK_GLOBAL_FUNCTIONS(GUST_LOAD)
#undef GUST_LOAD
    if (Status s = load_instance_functions(vk_, instance_); !s) return s;
    if (host.get_device_proc_addr) vk_.vkGetDeviceProcAddr = host.get_device_proc_addr;
    if (on_message_ || host.debug_utils) {
#define GUST_LOAD(name) vk_.name = reinterpret_cast<PFN_##name>(vk_.vkGetInstanceProcAddr(instance_, #name));
        GUST_VK_DEBUG_FUNCTIONS(GUST_LOAD)
#undef GUST_LOAD
    }
    if (on_message_) {
        if (!vk_.vkCreateDebugUtilsMessengerEXT || !vk_.vkDestroyDebugUtilsMessengerEXT)
            return Status::failure("HostDevice::on_message needs VK_EXT_debug_utils enabled on the host's "
                                   "instance");
        const VkDebugUtilsMessengerCreateInfoEXT info = messenger_info(this);
        if (VkResult r = vk_.vkCreateDebugUtilsMessengerEXT(instance_, &info, allocator(), &messenger_);
            r != VK_SUCCESS)
            return Status::failure(std::string("vkCreateDebugUtilsMessengerEXT failed: ") + to_string(r));
    }

    if (Status s = check_support(vk_, physical_, host_memory_); !s) return s;
    VkPhysicalDeviceProperties props;
    vk_.vkGetPhysicalDeviceProperties(physical_, &props);
    const std::string_view device = props.deviceName;
    const std::pmr::vector<VkQueueFamilyProperties> families = queue_families(vk_, physical_, host_memory_);
    if (host.queue_family >= families.size())
        return Status::failure("HostDevice::queue_family " + std::to_string(host.queue_family) +
                               " out of range (device '" + std::string(device) + "' has " +
                               std::to_string(families.size()) + " queue families)");
    const VkQueueFamilyProperties& family = families[host.queue_family];
    if (host.queue_index >= family.queueCount)
        return Status::failure("HostDevice::queue_index " + std::to_string(host.queue_index) +
                               " out of range (queue family " + std::to_string(host.queue_family) + " has " +
                               std::to_string(family.queueCount) + " queues)");
    if (!graphics_and_compute(family))
        return Status::failure("HostDevice::queue_family " + std::to_string(host.queue_family) +
                               " of device '" + std::string(device) +
                               "' does not support both graphics and compute");
    queue_family_ = host.queue_family;

    const std::pmr::vector<VkExtensionProperties> exts = device_extensions(vk_, physical_, host_memory_);
    std::string unsupported;
    for (const char* name : host.enabled_extensions)
        if (name && !has_extension(exts, name)) append(unsupported, name);
    if (!unsupported.empty())
        return Status::failure("HostDevice::enabled_extensions lists " + unsupported + ", which device '" +
                               std::string(device) + "' does not support");
    info_.conservative_rasterization =
        std::any_of(host.enabled_extensions.begin(), host.enabled_extensions.end(), [](const char* name) {
            return name && std::strcmp(name, VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME) == 0;
        });
    device_ = host.device;
    return finish_device(host.queue_index);
}

Status Context::create_device() {
    if (Status s = check_support(vk_, physical_, host_memory_); !s) return s;
    VkPhysicalDeviceProperties props;
    vk_.vkGetPhysicalDeviceProperties(physical_, &props);

    const std::pmr::vector<VkQueueFamilyProperties> families = queue_families(vk_, physical_, host_memory_);
    const auto family = std::find_if(families.begin(), families.end(), graphics_and_compute);
    if (family == families.end())
        return Status::failure(std::string("device '") + props.deviceName +
                               "' has no graphics+compute queue");
    queue_family_ = std::uint32_t(family - families.begin());

    const std::pmr::vector<VkExtensionProperties> exts = device_extensions(vk_, physical_, host_memory_);
    std::pmr::vector<const char*> enabled(kRequiredExtensions.begin(), kRequiredExtensions.end(),
                                          host_memory_);
    for (const char* name : kOptionalExtensions)
        if (has_extension(exts, name)) enabled.push_back(name);
    info_.conservative_rasterization = has_extension(exts, VK_EXT_CONSERVATIVE_RASTERIZATION_EXTENSION_NAME);

    FeatureChain features;
    for_each_feature(features.f2.features, features.f12, features.f13,
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
    return finish_device(0);
}

Status Context::finish_device(std::uint32_t queue_index) {
    std::string missing;
#define GUST_LOAD(name)                                                                                      \
    vk_.name = reinterpret_cast<PFN_##name>(vk_.vkGetDeviceProcAddr(device_, #name));                        \
    if (!vk_.name) append(missing, #name);
    GUST_VK_DEVICE_FUNCTIONS(GUST_LOAD)
#undef GUST_LOAD
    if (!missing.empty())
        return Status::failure("vkGetDeviceProcAddr returned null for " + missing +
                               " (is the device Vulkan 1.3?)");
    vk_.vkGetDeviceQueue(device_, queue_family_, queue_index, &queue_);
    vk_.vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

    VkPhysicalDeviceProperties props;
    vk_.vkGetPhysicalDeviceProperties(physical_, &props);
    VkPhysicalDeviceVulkan11Properties p11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_PROPERTIES};
    VkPhysicalDeviceVulkan12Properties p12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_PROPERTIES};
    p11.pNext = &p12;
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    p2.pNext = &p11;
    vk_.vkGetPhysicalDeviceProperties2(physical_, &p2);
    VkPhysicalDeviceMaintenance3Properties m3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
    p2.pNext = &m3;
    vk_.vkGetPhysicalDeviceProperties2(physical_, &p2);
    const std::pmr::vector<VkQueueFamilyProperties> families = queue_families(vk_, physical_, host_memory_);

    info_.name = props.deviceName;
    info_.type = type_name(props.deviceType);
    info_.api_version = props.apiVersion;
    info_.vendor_id = props.vendorID;
    info_.driver.assign(p12.driverName).append(" ").append(p12.driverInfo);
    info_.timestamp_period_ns =
        (families[queue_family_].timestampValidBits > 0 && props.limits.timestampComputeAndGraphics)
            ? props.limits.timestampPeriod
            : 0.0f;
    info_.max_storage_buffer_range = props.limits.maxStorageBufferRange;
    info_.max_allocation_size = m3.maxMemoryAllocationSize;
    info_.subgroup_size = p11.subgroupSize;
    info_.max_workgroup_size =
        std::min(props.limits.maxComputeWorkGroupInvocations, props.limits.maxComputeWorkGroupSize[0]);

    // A stale, foreign or damaged file costs nothing but the compile.
    std::pmr::vector<char> blob(host_memory_);
    if (!pipeline_cache_path_.empty())
        blob = read_pipeline_cache(std::string(pipeline_cache_path_), props, host_memory_);
    VkPipelineCacheCreateInfo cache_info{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
    cache_info.initialDataSize = blob.size();
    cache_info.pInitialData = blob.empty() ? nullptr : blob.data();
    if (VkResult r = vk_.vkCreatePipelineCache(device_, &cache_info, allocator(), &pipeline_cache_);
        r != VK_SUCCESS)
        return Status::failure(std::string("vkCreatePipelineCache failed: ") + to_string(r));
    pipeline_cache_loaded_ = !blob.empty();

    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT | VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool_info.queueFamilyIndex = queue_family_;
    if (VkResult r = vk_.vkCreateCommandPool(device_, &pool_info, allocator(), &pool_); r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateCommandPool failed: ") + to_string(r));
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if (VkResult r = vk_.vkCreateFence(device_, &fence_info, allocator(), &fence_); r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateFence failed: ") + to_string(r));
    return {};
}

void Context::wait_idle() const {
    if (!device_) return;
    // An adopted device is not waited on as a whole (its other queues are the host's), but the queue gust
    // was given is, as gust's blocking calls use it: commands gust recorded into the host's command
    // buffers (Submission::HostCommands) may still be running there, on gust's resources.
    if (owns_device_) {
        vk_.vkDeviceWaitIdle(device_);
    } else if (queue_) {
        std::unique_lock<std::mutex> lock;
        if (queue_mutex_) lock = std::unique_lock<std::mutex>(*queue_mutex_);
        vk_.vkQueueWaitIdle(queue_);
    }
}

Context::~Context() {
    if (device_ && vk_.vkDestroyDevice) {
        wait_idle();
        retire(UINT64_MAX);
        if (fence_) vk_.vkDestroyFence(device_, fence_, allocator());
        if (pipeline_cache_) vk_.vkDestroyPipelineCache(device_, pipeline_cache_, allocator());
        if (pool_) vk_.vkDestroyCommandPool(device_, pool_, allocator());
        if (owns_device_) vk_.vkDestroyDevice(device_, allocator());
    }
    if (messenger_) vk_.vkDestroyDebugUtilsMessengerEXT(instance_, messenger_, allocator());
    if (instance_ && owns_device_) vk_.vkDestroyInstance(instance_, allocator());
    if (loader_) dlclose(loader_);
}

Status Context::begin_one_time(VkCommandBuffer& cmd) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = pool_;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    if (VkResult r = vk_.vkAllocateCommandBuffers(device_, &alloc, &cmd); r != VK_SUCCESS)
        return Status::failure(std::string("vkAllocateCommandBuffers failed: ") + to_string(r));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    if (VkResult r = vk_.vkBeginCommandBuffer(cmd, &begin); r != VK_SUCCESS) {
        vk_.vkFreeCommandBuffers(device_, pool_, 1, &cmd);
        cmd = VK_NULL_HANDLE;
        return Status::failure(std::string("vkBeginCommandBuffer failed: ") + to_string(r));
    }
    if (!owns_device_) barrier(*this, cmd);
    return {};
}

void Context::abandon_one_time(VkCommandBuffer cmd) {
    vk_.vkFreeCommandBuffers(device_, pool_, 1, &cmd);
}

Status Context::end_one_time(VkCommandBuffer cmd) {
    // A recording that failed (out of memory part-way) is never submitted: the buffer is invalid.
    if (VkResult r = vk_.vkEndCommandBuffer(cmd); r != VK_SUCCESS) {
        vk_.vkFreeCommandBuffers(device_, pool_, 1, &cmd);
        return Status::failure(std::string("vkEndCommandBuffer failed: ") + to_string(r));
    }

    VkCommandBufferSubmitInfo cmd_info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
    cmd_info.commandBuffer = cmd;
    VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
    submit.commandBufferInfoCount = 1;
    submit.pCommandBufferInfos = &cmd_info;
    Status status;
    vk_.vkResetFences(device_, 1, &fence_);
    VkResult submitted = VK_SUCCESS;
    {
        std::unique_lock<std::mutex> lock;
        if (queue_mutex_) lock = std::unique_lock<std::mutex>(*queue_mutex_);
        submitted = vk_.vkQueueSubmit2(queue_, 1, &submit, fence_);
    }
    ++work_.submissions;
    if (submitted != VK_SUCCESS)
        status = Status::failure(std::string("vkQueueSubmit2 failed: ") + to_string(submitted));
    else if (++work_.waits; vk_.vkWaitForFences(device_, 1, &fence_, VK_TRUE, UINT64_MAX) != VK_SUCCESS)
        status = Status::failure("waiting for the GPU failed");
    vk_.vkFreeCommandBuffers(device_, pool_, 1, &cmd);
    return status;
}

Status Context::save_pipeline_cache() const {
    if (pipeline_cache_path_.empty() || !pipeline_cache_) return {};
    std::size_t bytes = 0;
    if (VkResult r = vk_.vkGetPipelineCacheData(device_, pipeline_cache_, &bytes, nullptr); r != VK_SUCCESS)
        return Status::failure(std::string("vkGetPipelineCacheData failed: ") + to_string(r));
    std::pmr::vector<char> blob(bytes, host_memory_);
    if (VkResult r = vk_.vkGetPipelineCacheData(device_, pipeline_cache_, &bytes, blob.data());
        r != VK_SUCCESS)
        return Status::failure(std::string("vkGetPipelineCacheData failed: ") + to_string(r));
    // Written beside the file under a name of this process's own and renamed over it, so that a reader
    // never sees half a cache, nor two writers one file.
    const std::filesystem::path path{std::string(pipeline_cache_path_)};
    std::error_code ec;
    // Only a missing or empty file, or one of ours (whole or damaged), is replaced: a path that names
    // anything else is a mistake, and the file is the user's.
    if (std::filesystem::exists(path, ec)) {
        if (!std::filesystem::is_regular_file(path, ec))
            return Status::failure(path.string() + ": not a regular file, so no pipeline cache was written");
        char magic[sizeof(kCacheMagic)] = {};
        std::ifstream in(path, std::ios::binary);
        in.read(magic, sizeof(magic));
        if (in.gcount() > 0 && (in.gcount() < std::streamsize(sizeof(magic)) ||
                                std::memcmp(magic, kCacheMagic, sizeof(magic)) != 0))
            return Status::failure(path.string() + ": not a gust pipeline cache, so it was left as it is");
    }
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
    const std::filesystem::path partial = path.string() + "." + std::to_string(getpid()) + ".partial";
    CacheFileHeader header{};
    std::memcpy(header.magic, kCacheMagic, sizeof(kCacheMagic));
    header.bytes = bytes;
    header.checksum = fnv1a(blob.data(), bytes);
    {
        std::ofstream out(partial, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(&header), sizeof(header));
        out.write(blob.data(), std::streamsize(bytes));
        if (!out) {
            out.close();
            std::filesystem::remove(partial, ec);
            return Status::failure(partial.string() + ": cannot write the pipeline cache");
        }
    }
    std::filesystem::rename(partial, path, ec);
    if (ec) {
        std::error_code ignored;
        std::filesystem::remove(partial, ignored);
        return Status::failure(path.string() + ": cannot write the pipeline cache (" + ec.message() + ")");
    }
    return {};
}

void Context::name(VkObjectType type, std::uint64_t handle, const char* name) const {
    if (!vk_.vkSetDebugUtilsObjectNameEXT || !name || handle == 0) return;
    VkDebugUtilsObjectNameInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT};
    info.objectType = type;
    info.objectHandle = handle;
    info.pObjectName = name;
    vk_.vkSetDebugUtilsObjectNameEXT(device_, &info);
}

void Context::begin_label(VkCommandBuffer cmd, const char* name) const {
    if (!vk_.vkCmdBeginDebugUtilsLabelEXT) return;
    VkDebugUtilsLabelEXT label{VK_STRUCTURE_TYPE_DEBUG_UTILS_LABEL_EXT};
    label.pLabelName = name;
    vk_.vkCmdBeginDebugUtilsLabelEXT(cmd, &label);
}

void Context::end_label(VkCommandBuffer cmd) const {
    if (vk_.vkCmdEndDebugUtilsLabelEXT) vk_.vkCmdEndDebugUtilsLabelEXT(cmd);
}

void Context::begin_frame(std::uint64_t frame) {
    deferred_ = true;
    recording_frame_ = frame;
}

void Context::retire(std::uint64_t completed) {
    std::size_t kept = 0;
    for (const Released& r : released_) {
        if (r.frame > completed) {
            released_[kept++] = r;
            continue;
        }
        vk_.vkDestroyBuffer(device_, r.buffer, allocator());
        vk_.vkFreeMemory(device_, r.memory, allocator());
    }
    released_.resize(kept);
}

void Context::release_later(VkBuffer buffer, VkDeviceMemory memory) noexcept {
    // Within the capacity reserve_release_slot kept, so push_back does not allocate: a buffer a recorded
    // frame still uses is never freed early for want of memory to remember it.
    released_.push_back({recording_frame_, buffer, memory});
}

Status Context::reserve_release_slot() noexcept {
    const std::size_t needed = released_.size() + live_buffers_ + 1;
    if (needed > released_.capacity()) {
        try {
            released_.reserve(std::max(needed, 2 * released_.capacity()));
        } catch (const std::exception&) {
            return Status::failure("host memory ran out keeping room to release a buffer");
        }
    }
    ++live_buffers_;
    return {};
}

void Context::drop_release_slot() noexcept {
    --live_buffers_;
}

std::uint32_t Context::find_memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags required,
                                        VkMemoryPropertyFlags preferred) const {
    std::uint32_t best = UINT32_MAX;
    int best_score = -1;
    for (std::uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
        const VkMemoryPropertyFlags flags = memory_.memoryTypes[i].propertyFlags;
        if (!(type_bits & (1u << i)) || (flags & required) != required) continue;
        const int score = __builtin_popcount(flags & preferred);
        if (score > best_score) {
            best_score = score;
            best = i;
        }
    }
    return best;
}

VkMemoryPropertyFlags Context::memory_flags(std::uint32_t type_index) const {
    return memory_.memoryTypes[type_index].propertyFlags;
}

} // namespace gust::gpu
