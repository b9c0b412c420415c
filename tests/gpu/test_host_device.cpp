// The host-device tier: each test plays a host engine that loads Vulkan itself, creates its own
// validated instance and device with gust's requirements, and hands them to gpu::Context::adopt.
#include <atomic>
#include <cstring>
#include <dlfcn.h>
#include <future>
#include <gtest/gtest.h>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/context.hpp>
#include <gust/gpu/image.hpp>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace gust::test {
namespace {

// What the host's entry-point wrappers forward to, record and change. Global because Vulkan entry
// points carry no user pointer; reset by every test's SetUp.
struct Intercept {
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
    PFN_vkGetDeviceProcAddr get_device_proc_addr = nullptr;
    PFN_vkGetPhysicalDeviceProperties get_properties = nullptr;
    PFN_vkGetPhysicalDeviceFeatures2 get_features = nullptr;
    PFN_vkQueueSubmit queue_submit = nullptr;
    PFN_vkCreateBuffer create_buffer = nullptr;
    PFN_vkCreateImage create_image = nullptr;
    PFN_vkCreateImageView create_image_view = nullptr;
    PFN_vkSetDebugUtilsObjectNameEXT set_object_name = nullptr;
    std::uint32_t reported_api_version = 0; // non-zero: vkGetPhysicalDeviceProperties reports this
    bool hide_geometry_shader = false;      // vkGetPhysicalDeviceFeatures2 reports geometryShader off
    std::mutex* queue_mutex = nullptr;      // checked during every vkQueueSubmit
    int submits = 0;
    int submits_holding_mutex = 0;
    std::set<std::string> instance_names;     // asked of vkGetInstanceProcAddr with an instance
    std::set<std::string> device_names;       // asked of the vkGetDeviceProcAddr the instance returns
    std::set<std::string> given_device_names; // asked of HostDevice::get_device_proc_addr
    using Object = std::pair<VkObjectType, std::uint64_t>;
    std::set<Object> created;                   // buffers, images and image views created
    std::map<Object, std::string> object_names; // given through vkSetDebugUtilsObjectNameEXT
};
Intercept intercept;

VKAPI_ATTR void VKAPI_CALL host_get_properties(VkPhysicalDevice physical, VkPhysicalDeviceProperties* props) {
    intercept.get_properties(physical, props);
    if (intercept.reported_api_version) props->apiVersion = intercept.reported_api_version;
}

VKAPI_ATTR void VKAPI_CALL host_get_features(VkPhysicalDevice physical, VkPhysicalDeviceFeatures2* features) {
    intercept.get_features(physical, features);
    if (intercept.hide_geometry_shader) features->features.geometryShader = VK_FALSE;
}

VKAPI_ATTR VkResult VKAPI_CALL host_queue_submit(VkQueue queue, std::uint32_t count,
                                                 const VkSubmitInfo* submits, VkFence fence) {
    ++intercept.submits;
    if (intercept.queue_mutex) {
        // Asked from another thread: try_lock on a mutex the calling thread holds is undefined.
        const bool held = std::async(std::launch::async, [] {
                              if (!intercept.queue_mutex->try_lock()) return true;
                              intercept.queue_mutex->unlock();
                              return false;
                          }).get();
        intercept.submits_holding_mutex += held;
    }
    return intercept.queue_submit(queue, count, submits, fence);
}

VKAPI_ATTR VkResult VKAPI_CALL host_create_buffer(VkDevice device, const VkBufferCreateInfo* info,
                                                  const VkAllocationCallbacks* allocator, VkBuffer* buffer) {
    const VkResult r = intercept.create_buffer(device, info, allocator, buffer);
    if (r == VK_SUCCESS) intercept.created.emplace(VK_OBJECT_TYPE_BUFFER, std::uint64_t(*buffer));
    return r;
}

VKAPI_ATTR VkResult VKAPI_CALL host_create_image(VkDevice device, const VkImageCreateInfo* info,
                                                 const VkAllocationCallbacks* allocator, VkImage* image) {
    const VkResult r = intercept.create_image(device, info, allocator, image);
    if (r == VK_SUCCESS) intercept.created.emplace(VK_OBJECT_TYPE_IMAGE, std::uint64_t(*image));
    return r;
}

VKAPI_ATTR VkResult VKAPI_CALL host_create_image_view(VkDevice device, const VkImageViewCreateInfo* info,
                                                      const VkAllocationCallbacks* allocator,
                                                      VkImageView* view) {
    const VkResult r = intercept.create_image_view(device, info, allocator, view);
    if (r == VK_SUCCESS) intercept.created.emplace(VK_OBJECT_TYPE_IMAGE_VIEW, std::uint64_t(*view));
    return r;
}

VKAPI_ATTR VkResult VKAPI_CALL host_set_object_name(VkDevice device,
                                                    const VkDebugUtilsObjectNameInfoEXT* info) {
    intercept.object_names[{info->objectType, info->objectHandle}] =
        info->pObjectName ? info->pObjectName : "";
    return intercept.set_object_name(device, info);
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL host_get_device_proc_addr(VkDevice device, const char* name) {
    intercept.device_names.insert(name);
    if (std::strcmp(name, "vkQueueSubmit") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_queue_submit);
    if (std::strcmp(name, "vkCreateBuffer") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_create_buffer);
    if (std::strcmp(name, "vkCreateImage") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_create_image);
    if (std::strcmp(name, "vkCreateImageView") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_create_image_view);
    return intercept.get_device_proc_addr(device, name);
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL host_given_get_device_proc_addr(VkDevice device, const char* name) {
    intercept.given_device_names.insert(name);
    return intercept.get_device_proc_addr(device, name);
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL host_get_instance_proc_addr(VkInstance instance, const char* name) {
    if (instance) intercept.instance_names.insert(name);
    if (std::strcmp(name, "vkGetPhysicalDeviceProperties") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_get_properties);
    if (std::strcmp(name, "vkGetPhysicalDeviceFeatures2") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_get_features);
    if (std::strcmp(name, "vkGetDeviceProcAddr") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_get_device_proc_addr);
    if (std::strcmp(name, "vkSetDebugUtilsObjectNameEXT") == 0)
        return reinterpret_cast<PFN_vkVoidFunction>(host_set_object_name);
    return intercept.get_instance_proc_addr(instance, name);
}

// A host engine: its own loader handle, validated instance with a messenger that counts validation
// warnings and errors, and a device created with gust's requirements. TearDown destroys the device
// after the test destroyed gust's Context, so objects gust leaked are validation errors.
class HostDeviceTest : public ::testing::Test {
  protected:
    void SetUp() override {
        loader_ = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        ASSERT_NE(loader_, nullptr);
        gipa_ = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(loader_, "vkGetInstanceProcAddr"));
        ASSERT_NE(gipa_, nullptr);
        auto create_instance =
            reinterpret_cast<PFN_vkCreateInstance>(gipa_(VK_NULL_HANDLE, "vkCreateInstance"));

        const char* layer = "VK_LAYER_KHRONOS_validation";
        const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
        VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
        app.pApplicationName = "gust host test";
        app.apiVersion = VK_API_VERSION_1_3;
        VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        messenger.messageSeverity =
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
        messenger.pfnUserCallback = on_message;
        messenger.pUserData = this;
        VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
        info.pNext = &messenger;
        info.pApplicationInfo = &app;
        info.enabledLayerCount = 1;
        info.ppEnabledLayerNames = &layer;
        info.enabledExtensionCount = 1;
        info.ppEnabledExtensionNames = &extension;
        ASSERT_EQ(create_instance(&info, nullptr, &instance_), VK_SUCCESS);
        load(vkDestroyInstance_, "vkDestroyInstance");
        load(vkDestroyDebugUtilsMessengerEXT_, "vkDestroyDebugUtilsMessengerEXT");
        PFN_vkCreateDebugUtilsMessengerEXT create_messenger = nullptr;
        load(create_messenger, "vkCreateDebugUtilsMessengerEXT");
        ASSERT_EQ(create_messenger(instance_, &messenger, nullptr, &messenger_), VK_SUCCESS);

        intercept = Intercept{};
        intercept.get_instance_proc_addr = gipa_;
        load(intercept.get_properties, "vkGetPhysicalDeviceProperties");
        load(intercept.get_features, "vkGetPhysicalDeviceFeatures2");
        load(intercept.get_device_proc_addr, "vkGetDeviceProcAddr");
        load(intercept.set_object_name, "vkSetDebugUtilsObjectNameEXT");

        // The first device gust can use, with its first graphics+compute queue family.
        PFN_vkEnumeratePhysicalDevices enumerate = nullptr;
        PFN_vkGetPhysicalDeviceQueueFamilyProperties get_families = nullptr;
        load(enumerate, "vkEnumeratePhysicalDevices");
        load(get_families, "vkGetPhysicalDeviceQueueFamilyProperties");
        std::uint32_t count = 0;
        enumerate(instance_, &count, nullptr);
        std::vector<VkPhysicalDevice> devices(count);
        enumerate(instance_, &count, devices.data());
        for (VkPhysicalDevice device : devices) {
            if (!gpu::check_device_support(gipa_, instance_, device)) continue;
            get_families(device, &count, nullptr);
            families_.resize(count);
            get_families(device, &count, families_.data());
            for (std::uint32_t i = 0; i < count && !physical_; ++i)
                if ((families_[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
                    (families_[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
                    physical_ = device;
                    family_ = i;
                }
            if (physical_) break;
        }
        ASSERT_NE(physical_, VK_NULL_HANDLE) << "no device meets gust's requirements";
        intercept.get_properties(physical_, &properties_);

        VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
        VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &f13};
        VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
        const Status added = gpu::add_required_features(features);
        ASSERT_TRUE(added) << added.message();
        const float priority = 1.0f;
        VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        queue.queueFamilyIndex = family_;
        queue.queueCount = 1;
        queue.pQueuePriorities = &priority;
        VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        device_info.pNext = &features;
        device_info.queueCreateInfoCount = 1;
        device_info.pQueueCreateInfos = &queue;
        PFN_vkCreateDevice create_device = nullptr;
        load(create_device, "vkCreateDevice");
        ASSERT_EQ(create_device(physical_, &device_info, nullptr, &device_), VK_SUCCESS);
        vkDestroyDevice_ =
            reinterpret_cast<PFN_vkDestroyDevice>(intercept.get_device_proc_addr(device_, "vkDestroyDevice"));
        auto get_queue = reinterpret_cast<PFN_vkGetDeviceQueue>(
            intercept.get_device_proc_addr(device_, "vkGetDeviceQueue"));
        get_queue(device_, family_, 0, &queue_);
        intercept.queue_submit =
            reinterpret_cast<PFN_vkQueueSubmit>(intercept.get_device_proc_addr(device_, "vkQueueSubmit"));
        intercept.create_buffer =
            reinterpret_cast<PFN_vkCreateBuffer>(intercept.get_device_proc_addr(device_, "vkCreateBuffer"));
        intercept.create_image =
            reinterpret_cast<PFN_vkCreateImage>(intercept.get_device_proc_addr(device_, "vkCreateImage"));
        intercept.create_image_view = reinterpret_cast<PFN_vkCreateImageView>(
            intercept.get_device_proc_addr(device_, "vkCreateImageView"));
    }

    void TearDown() override {
        if (device_) vkDestroyDevice_(device_, nullptr);
        if (messenger_) vkDestroyDebugUtilsMessengerEXT_(instance_, messenger_, nullptr);
        if (instance_) vkDestroyInstance_(instance_, nullptr);
        if (loader_) dlclose(loader_);
        if (!expect_validation_messages_) {
            std::lock_guard lock(message_mutex_);
            EXPECT_EQ(validation_messages_.load(), 0) << "validation layer: " << last_message_;
        }
    }

    /// What a host hands gust: everything but get_device_proc_addr, which gust loads itself.
    gpu::HostDevice host_device() const {
        gpu::HostDevice host;
        host.instance = instance_;
        host.physical_device = physical_;
        host.device = device_;
        host.queue_family = family_;
        host.queue_index = 0;
        host.get_instance_proc_addr = host_get_instance_proc_addr;
        return host;
    }

    template <class Fn> void load(Fn& fn, const char* name) {
        fn = reinterpret_cast<Fn>(gipa_(instance_, name));
        ASSERT_NE(fn, nullptr) << name;
    }

    static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                     void* user) {
        auto* self = static_cast<HostDeviceTest*>(user);
        self->validation_messages_.fetch_add(1);
        std::lock_guard lock(self->message_mutex_);
        self->last_message_ = data->pMessage ? data->pMessage : "";
        return VK_FALSE;
    }

    void* loader_ = nullptr;
    PFN_vkGetInstanceProcAddr gipa_ = nullptr;
    PFN_vkDestroyInstance vkDestroyInstance_ = nullptr;
    PFN_vkDestroyDebugUtilsMessengerEXT vkDestroyDebugUtilsMessengerEXT_ = nullptr;
    PFN_vkDestroyDevice vkDestroyDevice_ = nullptr;
    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties properties_{};
    std::vector<VkQueueFamilyProperties> families_;
    std::uint32_t family_ = 0;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    std::atomic<int> validation_messages_{0};
    std::mutex message_mutex_;
    std::string last_message_;
    bool expect_validation_messages_ = false;
};

TEST_F(HostDeviceTest, adoptsAHostDeviceAndRunsCommands) {
    int forwarded = 0;
    gpu::HostDevice host = host_device();
    host.on_message = [&](gpu::Severity, const std::string&) { ++forwarded; };
    auto adopted = gpu::Context::adopt(host);
    ASSERT_TRUE(adopted) << adopted.message();
    gpu::Context& ctx = **adopted;
    EXPECT_FALSE(ctx.owns_device());
    EXPECT_EQ(ctx.instance(), instance_);
    EXPECT_EQ(ctx.physical_device(), physical_);
    EXPECT_EQ(ctx.device(), device_);
    EXPECT_EQ(ctx.queue(), queue_);
    EXPECT_EQ(ctx.queue_family(), family_);
    EXPECT_EQ(ctx.info().name, properties_.deviceName);
    EXPECT_EQ(ctx.info().api_version, properties_.apiVersion);
    EXPECT_GT(ctx.info().max_allocation_size, 0u);

    constexpr std::uint32_t kWords = 64;
    {
        auto buffer = gpu::Buffer::create(ctx, kWords * 4, gpu::MemoryUse::Readback);
        ASSERT_TRUE(buffer) << buffer.message();
        ASSERT_TRUE(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
            ctx.vk().vkCmdFillBuffer(cmd, buffer->handle(), 0, kWords * 2, 0x01234567u);
            ctx.vk().vkCmdFillBuffer(cmd, buffer->handle(), kWords * 2, kWords * 2, 0x89abcdefu);
        }));
        std::vector<std::uint32_t> words(kWords);
        ASSERT_TRUE(gpu::download(ctx, *buffer, words.data(), kWords * 4));
        for (std::uint32_t i = 0; i < kWords; ++i)
            ASSERT_EQ(words[i], i < kWords / 2 ? 0x01234567u : 0x89abcdefu) << "word " << i;
    }
    EXPECT_EQ(ctx.validation_messages(), 0u) << ctx.last_validation_message();
    EXPECT_EQ(forwarded, 0);
    adopted->reset();
}

TEST_F(HostDeviceTest, loadsEveryFunctionThroughTheHostsEntryPoints) {
    auto adopted = gpu::Context::adopt(host_device());
    ASSERT_TRUE(adopted) << adopted.message();
    EXPECT_TRUE(intercept.instance_names.count("vkGetPhysicalDeviceMemoryProperties"));
    EXPECT_TRUE(intercept.device_names.count("vkQueueSubmit"));
    EXPECT_TRUE(intercept.device_names.count("vkCmdFillBuffer"));
    EXPECT_FALSE(intercept.instance_names.count("vkCmdFillBuffer"));
    ASSERT_TRUE((*adopted)->submit_and_wait([](VkCommandBuffer) {}));
    EXPECT_EQ(intercept.submits, 1);
}

TEST_F(HostDeviceTest, usesTheHostsGetDeviceProcAddrWhenGiven) {
    gpu::HostDevice host = host_device();
    host.get_device_proc_addr = host_given_get_device_proc_addr;
    auto adopted = gpu::Context::adopt(host);
    ASSERT_TRUE(adopted) << adopted.message();
    EXPECT_TRUE(intercept.given_device_names.count("vkCmdFillBuffer"));
    EXPECT_FALSE(intercept.device_names.count("vkCmdFillBuffer"));
}

TEST_F(HostDeviceTest, namesEveryBufferAndImageForCaptureTools) {
    gpu::HostDevice host = host_device();
    host.debug_utils = true;
    auto adopted = gpu::Context::adopt(host);
    ASSERT_TRUE(adopted) << adopted.message();
    gpu::Context& ctx = **adopted;
    {
        auto buffer = gpu::Buffer::create(ctx, 256, gpu::MemoryUse::Device, 0, "test buffer");
        ASSERT_TRUE(buffer) << buffer.message();
        // Where device memory is not host-visible, both copies go through a staging buffer gust creates.
        std::vector<std::uint32_t> words(64, 7u);
        ASSERT_TRUE(gpu::upload(ctx, *buffer, words.data(), 256));
        ASSERT_TRUE(gpu::download(ctx, *buffer, words.data(), 256));
        gpu::ImageDesc desc;
        desc.extent = {4, 4, 1};
        desc.name = "test image";
        auto image = gpu::Image::create(ctx, desc);
        ASSERT_TRUE(image) << image.message();
        ctx.name(VK_OBJECT_TYPE_QUEUE, std::uint64_t(queue_), "test queue");

        const auto name_of = [](VkObjectType type, std::uint64_t handle) {
            const auto it = intercept.object_names.find({type, handle});
            return it == intercept.object_names.end() ? std::string("(none)") : it->second;
        };
        EXPECT_EQ(name_of(VK_OBJECT_TYPE_BUFFER, std::uint64_t(buffer->handle())), "test buffer");
        EXPECT_EQ(name_of(VK_OBJECT_TYPE_IMAGE, std::uint64_t(image->handle())), "test image");
        EXPECT_EQ(name_of(VK_OBJECT_TYPE_IMAGE_VIEW, std::uint64_t(image->view())), "test image");
        EXPECT_EQ(name_of(VK_OBJECT_TYPE_QUEUE, std::uint64_t(queue_)), "test queue");
        // The buffer, the image, its view and, where the buffer is not host-visible (not on lavapipe), the
        // staging buffers.
        EXPECT_GE(intercept.created.size(), 3u);
        for (const auto& [type, handle] : intercept.created)
            EXPECT_NE(name_of(type, handle), "(none)") << "object type " << type << " has no name";
    }
    EXPECT_EQ(ctx.validation_messages(), 0u) << ctx.last_validation_message();
}

TEST_F(HostDeviceTest, destroysOnlyWhatItCreated) {
    auto adopted = gpu::Context::adopt(host_device());
    ASSERT_TRUE(adopted) << adopted.message();
    ASSERT_TRUE((*adopted)->submit_and_wait([](VkCommandBuffer) {}));
    adopted->reset();
    // The host's device still works: its queue runs a submission after gust is gone.
    auto wait_idle =
        reinterpret_cast<PFN_vkQueueWaitIdle>(intercept.get_device_proc_addr(device_, "vkQueueWaitIdle"));
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    EXPECT_EQ(intercept.queue_submit(queue_, 1, &submit, VK_NULL_HANDLE), VK_SUCCESS);
    EXPECT_EQ(wait_idle(queue_), VK_SUCCESS);
}

TEST_F(HostDeviceTest, submissionsHoldTheHostsQueueMutex) {
    std::mutex queue_mutex;
    gpu::HostDevice host = host_device();
    host.queue_mutex = &queue_mutex;
    intercept.queue_mutex = &queue_mutex;
    auto adopted = gpu::Context::adopt(host);
    ASSERT_TRUE(adopted) << adopted.message();
    ASSERT_TRUE((*adopted)->submit_and_wait([](VkCommandBuffer) {}));
    ASSERT_TRUE((*adopted)->submit_and_wait([](VkCommandBuffer) {}));
    EXPECT_EQ(intercept.submits, 2);
    EXPECT_EQ(intercept.submits_holding_mutex, 2);
    EXPECT_TRUE(queue_mutex.try_lock()) << "gust still holds the queue mutex";
    queue_mutex.unlock();
}

TEST_F(HostDeviceTest, usesConservativeRasterizationOnlyWhenTheHostEnabledIt) {
    auto adopted = gpu::Context::adopt(host_device());
    ASSERT_TRUE(adopted) << adopted.message();
    EXPECT_FALSE((*adopted)->info().conservative_rasterization);
}

TEST_F(HostDeviceTest, forwardsValidationMessagesToTheCallback) {
    expect_validation_messages_ = true;
    int forwarded = 0;
    gpu::HostDevice host = host_device();
    host.on_message = [&](gpu::Severity severity, const std::string&) {
        forwarded += severity == gpu::Severity::Error;
    };
    auto adopted = gpu::Context::adopt(host);
    ASSERT_TRUE(adopted) << adopted.message();
    gpu::Context& ctx = **adopted;
    // Deliberate misuse: a zero-sized buffer violates VUID-VkBufferCreateInfo-size-00912.
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    VkBuffer buffer = VK_NULL_HANDLE;
    ctx.vk().vkCreateBuffer(ctx.device(), &info, nullptr, &buffer);
    if (buffer) ctx.vk().vkDestroyBuffer(ctx.device(), buffer, nullptr);
    EXPECT_GE(ctx.validation_messages(), 1u);
    EXPECT_GE(forwarded, 1);
    EXPECT_GE(validation_messages_.load(), 1);
}

TEST_F(HostDeviceTest, rejectsNullHandles) {
    const char* fields[] = {"instance", "physical_device", "device", "get_instance_proc_addr"};
    for (int i = 0; i < 4; ++i) {
        gpu::HostDevice host = host_device();
        if (i == 0) host.instance = VK_NULL_HANDLE;
        if (i == 1) host.physical_device = VK_NULL_HANDLE;
        if (i == 2) host.device = VK_NULL_HANDLE;
        if (i == 3) host.get_instance_proc_addr = nullptr;
        auto adopted = gpu::Context::adopt(host);
        ASSERT_FALSE(adopted) << fields[i];
        EXPECT_NE(adopted.message().find(std::string("HostDevice: ") + fields[i] + " must not be null"),
                  std::string::npos)
            << adopted.message();
    }
}

TEST_F(HostDeviceTest, rejectsQueueFamilyOutOfRange) {
    gpu::HostDevice host = host_device();
    host.queue_family = std::uint32_t(families_.size());
    auto adopted = gpu::Context::adopt(host);
    ASSERT_FALSE(adopted);
    EXPECT_NE(adopted.message().find("queue_family " + std::to_string(families_.size()) + " out of range"),
              std::string::npos)
        << adopted.message();
}

TEST_F(HostDeviceTest, rejectsQueueIndexOutOfRange) {
    gpu::HostDevice host = host_device();
    host.queue_index = families_[family_].queueCount;
    auto adopted = gpu::Context::adopt(host);
    ASSERT_FALSE(adopted);
    EXPECT_NE(adopted.message().find("queue_index " + std::to_string(host.queue_index) + " out of range"),
              std::string::npos)
        << adopted.message();
}

TEST_F(HostDeviceTest, rejectsAPhysicalDeviceBelowVulkan12) {
    intercept.reported_api_version = VK_MAKE_API_VERSION(0, 1, 1, 0);
    auto adopted = gpu::Context::adopt(host_device());
    ASSERT_FALSE(adopted);
    EXPECT_NE(adopted.message().find("supports only Vulkan 1.1"), std::string::npos) << adopted.message();
}

TEST_F(HostDeviceTest, rejectsADeviceLackingARequiredFeatureNamingIt) {
    intercept.hide_geometry_shader = true;
    auto adopted = gpu::Context::adopt(host_device());
    ASSERT_FALSE(adopted);
    EXPECT_NE(adopted.message().find("geometryShader"), std::string::npos) << adopted.message();
    const Status support = gpu::check_device_support(host_get_instance_proc_addr, instance_, physical_);
    ASSERT_FALSE(support);
    EXPECT_NE(support.message().find("lacks required features: geometryShader"), std::string::npos)
        << support.message();
    EXPECT_EQ(support.message().find("bufferDeviceAddress"), std::string::npos) << support.message();
}

TEST_F(HostDeviceTest, rejectsEnabledExtensionsTheDeviceDoesNotSupport) {
    gpu::HostDevice host = host_device();
    static constexpr const char* kUnknown[] = {"VK_GUST_no_such_extension"};
    host.enabled_extensions = kUnknown;
    auto adopted = gpu::Context::adopt(host);
    ASSERT_FALSE(adopted);
    EXPECT_NE(adopted.message().find("VK_GUST_no_such_extension"), std::string::npos) << adopted.message();
}

TEST_F(HostDeviceTest, checkDeviceSupportAcceptsTheHostsDevice) {
    const Status support = gpu::check_device_support(host_get_instance_proc_addr, instance_, physical_);
    EXPECT_TRUE(support) << support.message();
}

TEST(DeviceRequirements, listTheFeaturesAndExtensionsGustUses) {
    const gpu::DeviceRequirements req = gpu::device_requirements();
    std::vector<std::string> features(req.features.begin(), req.features.end());
    // Nothing Godot 4's Vulkan 1.2 device lacks (docs/godot.md): no synchronization2, dynamic rendering,
    // maintenance4 or scalarBlockLayout.
    const std::vector<std::string> expected = {"geometryShader", "fragmentStoresAndAtomics",
                                               "vertexPipelineStoresAndAtomics", "shaderInt64",
                                               "bufferDeviceAddress"};
    EXPECT_EQ(features, expected);
    EXPECT_EQ(req.api_version, VK_API_VERSION_1_2);
    EXPECT_TRUE(req.extensions.empty());
    ASSERT_EQ(req.optional_extensions.size(), 1u);
    EXPECT_STREQ(req.optional_extensions[0], "VK_EXT_conservative_rasterization");
}

TEST(DeviceRequirements, addRequiredFeaturesSetsThemAndKeepsTheHostsOwn) {
    VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES, &f13};
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &f11};
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    features.features.samplerAnisotropy = VK_TRUE;
    f11.multiview = VK_TRUE;
    ASSERT_TRUE(gpu::add_required_features(features));
    EXPECT_TRUE(features.features.geometryShader);
    EXPECT_TRUE(features.features.vertexPipelineStoresAndAtomics);
    EXPECT_TRUE(features.features.shaderInt64);
    EXPECT_TRUE(f12.bufferDeviceAddress);
    EXPECT_TRUE(features.features.samplerAnisotropy);
    EXPECT_TRUE(f11.multiview);
    EXPECT_FALSE(features.features.tessellationShader);
    EXPECT_FALSE(f12.descriptorIndexing);
    EXPECT_FALSE(f12.scalarBlockLayout);
    EXPECT_FALSE(f13.synchronization2);
    EXPECT_FALSE(f13.dynamicRendering);
}

TEST(DeviceRequirements, addRequiredFeaturesRejectsAChainWithoutVulkan12Features) {
    VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f11};
    const Status added = gpu::add_required_features(features);
    ASSERT_FALSE(added);
    EXPECT_NE(added.message().find("VkPhysicalDeviceVulkan12Features"), std::string::npos) << added.message();
    EXPECT_FALSE(features.features.geometryShader);
}

TEST(DeviceRequirements, checkDeviceSupportRejectsNullArguments) {
    const Status support = gpu::check_device_support(nullptr, VK_NULL_HANDLE, VK_NULL_HANDLE);
    ASSERT_FALSE(support);
    EXPECT_NE(support.message().find("null"), std::string::npos) << support.message();
}

} // namespace
} // namespace gust::test
