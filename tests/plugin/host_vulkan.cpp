#include "host_vulkan.hpp"

#include <cstdio>
#include <dlfcn.h>
#include <vector>

namespace gust::test {

namespace {
template <class Fn> Fn load(PFN_vkGetInstanceProcAddr gipa, VkInstance instance, const char* name) {
    return reinterpret_cast<Fn>(gipa(instance, name));
}
template <class Fn>
Fn load_device(PFN_vkGetInstanceProcAddr gipa, VkInstance instance, VkDevice device, const char* name) {
    auto gdpa = load<PFN_vkGetDeviceProcAddr>(gipa, instance, "vkGetDeviceProcAddr");
    return reinterpret_cast<Fn>(gdpa(device, name));
}
} // namespace

VKAPI_ATTR VkBool32 VKAPI_CALL HostVulkan::on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                      VkDebugUtilsMessageTypeFlagsEXT,
                                                      const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                      void* user) {
    static_cast<HostVulkan*>(user)->messages_.fetch_add(1);
    std::fprintf(stderr, "host validation: %s\n", data->pMessage ? data->pMessage : "");
    return VK_FALSE;
}

HostVulkan::HostVulkan(bool external_memory, bool async_compute) {
    loader_ = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!loader_) {
        error_ = "no libvulkan.so.1";
        return;
    }
    auto gipa = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(loader_, "vkGetInstanceProcAddr"));
    host_.get_instance_proc_addr = gipa;
    const char* layer = "VK_LAYER_KHRONOS_validation";
    const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.apiVersion = VK_API_VERSION_1_3;
    VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    messenger.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    messenger.pfnUserCallback = on_message;
    messenger.pUserData = this;
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    info.enabledLayerCount = 1;
    info.ppEnabledLayerNames = &layer;
    info.enabledExtensionCount = 1;
    info.ppEnabledExtensionNames = &extension;
    if (load<PFN_vkCreateInstance>(gipa, VK_NULL_HANDLE, "vkCreateInstance")(&info, nullptr,
                                                                             &host_.instance) != VK_SUCCESS) {
        error_ = "vkCreateInstance failed (is the validation layer installed?)";
        return;
    }
    VkInstance instance = host_.instance;
    load<PFN_vkCreateDebugUtilsMessengerEXT>(gipa, instance, "vkCreateDebugUtilsMessengerEXT")(
        instance, &messenger, nullptr, &messenger_);
    auto enumerate = load<PFN_vkEnumeratePhysicalDevices>(gipa, instance, "vkEnumeratePhysicalDevices");
    auto families = load<PFN_vkGetPhysicalDeviceQueueFamilyProperties>(
        gipa, instance, "vkGetPhysicalDeviceQueueFamilyProperties");
    std::uint32_t count = 0;
    enumerate(instance, &count, nullptr);
    std::vector<VkPhysicalDevice> devices(count);
    enumerate(instance, &count, devices.data());
    for (VkPhysicalDevice device : devices) {
        families(device, &count, nullptr);
        std::vector<VkQueueFamilyProperties> props(count);
        families(device, &count, props.data());
        for (std::uint32_t i = 0; i < count && !host_.physical_device; ++i)
            if ((props[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
                (props[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
                host_.physical_device = device;
                host_.queue_family = i;
            }
        if (!host_.physical_device) continue;
        compute_family_ = host_.queue_family;
        for (std::uint32_t i = count; async_compute && i-- > 0;)
            if ((props[i].queueFlags & VK_QUEUE_COMPUTE_BIT) &&
                !(props[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && props[i].queueCount > 0)
                compute_family_ = i;
        break;
    }
    if (!host_.physical_device) {
        error_ = "no device with a graphics and compute queue";
        return;
    }
    VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &f13};
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
    // The host's own shader (shaders/cascade_wind.comp) reads arrays of vec3: a feature of its own, which
    // gust does not need.
    f12.scalarBlockLayout = VK_TRUE;
    if (Outcome added = add_required_features(features); !added) {
        error_ = added.message();
        return;
    }
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queues[2] = {{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO},
                                         {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO}};
    queues[0].queueFamilyIndex = host_.queue_family;
    queues[1].queueFamilyIndex = compute_family_;
    for (VkDeviceQueueCreateInfo& queue : queues) {
        queue.queueCount = 1;
        queue.pQueuePriorities = &priority;
    }
    VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    device_info.pNext = &features;
    device_info.queueCreateInfoCount = compute_family_ == host_.queue_family ? 1 : 2;
    device_info.pQueueCreateInfos = queues;
    const char* external = VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME;
    if (external_memory) {
        device_info.enabledExtensionCount = 1;
        device_info.ppEnabledExtensionNames = &external;
    }
    if (load<PFN_vkCreateDevice>(gipa, instance, "vkCreateDevice")(host_.physical_device, &device_info,
                                                                   nullptr, &host_.device) != VK_SUCCESS) {
        error_ = "vkCreateDevice failed";
        return;
    }
    load_device<PFN_vkGetDeviceQueue>(gipa, instance, host_.device,
                                      "vkGetDeviceQueue")(host_.device, host_.queue_family, 0, &queue_);
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.queueFamilyIndex = host_.queue_family;
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT; // frame() re-records its buffers
    load_device<PFN_vkCreateCommandPool>(gipa, instance, host_.device,
                                         "vkCreateCommandPool")(host_.device, &pool, nullptr, &pool_);
}

PFN_vkVoidFunction HostVulkan::device_function(const char* name) const {
    return load_device<PFN_vkVoidFunction>(host_.get_instance_proc_addr, host_.instance, host_.device, name);
}

bool HostVulkan::run(void (*record)(VkCommandBuffer, void*), void* user) {
    auto gipa = host_.get_instance_proc_addr;
    VkInstance instance = host_.instance;
    VkDevice device = host_.device;
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = pool_;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    if (load_device<PFN_vkAllocateCommandBuffers>(gipa, instance, device, "vkAllocateCommandBuffers")(
            device, &alloc, &cmd) != VK_SUCCESS)
        return false;
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    load_device<PFN_vkBeginCommandBuffer>(gipa, instance, device, "vkBeginCommandBuffer")(cmd, &begin);
    record(cmd, user);
    load_device<PFN_vkEndCommandBuffer>(gipa, instance, device, "vkEndCommandBuffer")(cmd);
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    const bool ok =
        load_device<PFN_vkQueueSubmit>(gipa, instance, device,
                                       "vkQueueSubmit")(queue_, 1, &submit, VK_NULL_HANDLE) == VK_SUCCESS &&
        load_device<PFN_vkQueueWaitIdle>(gipa, instance, device, "vkQueueWaitIdle")(queue_) == VK_SUCCESS;
    load_device<PFN_vkFreeCommandBuffers>(gipa, instance, device, "vkFreeCommandBuffers")(device, pool_, 1,
                                                                                          &cmd);
    return ok;
}

bool HostVulkan::start_frames(std::uint32_t count) {
    auto gipa = host_.get_instance_proc_addr;
    VkInstance instance = host_.instance;
    VkDevice device = host_.device;
    if (!frame_commands_.empty() || count < 1 || count > 8) return false;
    frame_commands_.resize(count);
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = pool_;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = count;
    if (load_device<PFN_vkAllocateCommandBuffers>(gipa, instance, device, "vkAllocateCommandBuffers")(
            device, &alloc, frame_commands_.data()) != VK_SUCCESS)
        return false;
    VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fence.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    frame_fences_.resize(count);
    for (VkFence& f : frame_fences_)
        if (load_device<PFN_vkCreateFence>(gipa, instance, device, "vkCreateFence")(device, &fence, nullptr,
                                                                                    &f) != VK_SUCCESS)
            return false;
    return true;
}

VkCommandBuffer HostVulkan::begin_frame() {
    auto gipa = host_.get_instance_proc_addr;
    VkInstance instance = host_.instance;
    VkDevice device = host_.device;
    if (frame_commands_.empty()) return VK_NULL_HANDLE;
    const std::size_t slot = frames_ % frame_commands_.size();
    VkFence fence = frame_fences_[slot];
    VkCommandBuffer cmd = frame_commands_[slot];
    if (load_device<PFN_vkWaitForFences>(gipa, instance, device, "vkWaitForFences")(
            device, 1, &fence, VK_TRUE, UINT64_MAX) != VK_SUCCESS)
        return VK_NULL_HANDLE;
    load_device<PFN_vkResetFences>(gipa, instance, device, "vkResetFences")(device, 1, &fence);
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    load_device<PFN_vkBeginCommandBuffer>(gipa, instance, device, "vkBeginCommandBuffer")(cmd, &begin);
    return cmd;
}

bool HostVulkan::submit_frame() {
    auto gipa = host_.get_instance_proc_addr;
    VkInstance instance = host_.instance;
    VkDevice device = host_.device;
    const std::size_t slot = frames_++ % frame_commands_.size();
    VkCommandBuffer cmd = frame_commands_[slot];
    load_device<PFN_vkEndCommandBuffer>(gipa, instance, device, "vkEndCommandBuffer")(cmd);
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    return load_device<PFN_vkQueueSubmit>(gipa, instance, device, "vkQueueSubmit")(
               queue_, 1, &submit, frame_fences_[slot]) == VK_SUCCESS;
}

bool HostVulkan::finish_frames() {
    auto gipa = host_.get_instance_proc_addr;
    if (frame_fences_.empty()) return true;
    return load_device<PFN_vkWaitForFences>(gipa, host_.instance, host_.device, "vkWaitForFences")(
               host_.device, std::uint32_t(frame_fences_.size()), frame_fences_.data(), VK_TRUE,
               UINT64_MAX) == VK_SUCCESS;
}

HostVulkan::~HostVulkan() {
    auto gipa = host_.get_instance_proc_addr;
    if (host_.device) {
        finish_frames();
        for (VkFence f : frame_fences_)
            load_device<PFN_vkDestroyFence>(gipa, host_.instance, host_.device,
                                            "vkDestroyFence")(host_.device, f, nullptr);
        if (pool_)
            load_device<PFN_vkDestroyCommandPool>(gipa, host_.instance, host_.device,
                                                  "vkDestroyCommandPool")(host_.device, pool_, nullptr);
        load_device<PFN_vkDestroyDevice>(gipa, host_.instance, host_.device, "vkDestroyDevice")(host_.device,
                                                                                                nullptr);
    }
    if (messenger_)
        load<PFN_vkDestroyDebugUtilsMessengerEXT>(gipa, host_.instance, "vkDestroyDebugUtilsMessengerEXT")(
            host_.instance, messenger_, nullptr);
    if (host_.instance)
        load<PFN_vkDestroyInstance>(gipa, host_.instance, "vkDestroyInstance")(host_.instance, nullptr);
    if (loader_) dlclose(loader_);
}

} // namespace gust::test
