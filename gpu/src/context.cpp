// The Context itself, whichever way its device came (own_device.cpp, adopted_device.cpp): the device's
// queue, properties and command pool, one-time submissions, debug messages, names and labels, buffers
// retired by frame, and memory types.
#include "context_detail.hpp"
#include "vk_load.hpp"

#include <algorithm>
#include <dlfcn.h>
#include <gust/gpu/buffer.hpp>

namespace gust::gpu {

using namespace detail;

namespace {

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

} // namespace

VkDebugUtilsMessengerCreateInfoEXT detail::messenger_info(Context* ctx) {
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
    : host_memory_(memory), allocator_(memory),
      objects_before_(memory), info_{.name = std::pmr::string(memory), .driver = std::pmr::string(memory)},
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

Status Context::finish_device(std::uint32_t queue_index) {
    if (const std::string missing = load_device_functions(vk_, device_); !missing.empty())
        return Status::failure("vkGetDeviceProcAddr returned null for " + missing +
                               " (is the device Vulkan 1.2?)");
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
    info_.graphics_queue = (families[queue_family_].queueFlags & VK_QUEUE_GRAPHICS_BIT) != 0;
    info_.timestamp_period_ns =
        (families[queue_family_].timestampValidBits > 0 && props.limits.timestampComputeAndGraphics)
            ? props.limits.timestampPeriod
            : 0.0f;
    info_.max_storage_buffer_range = props.limits.maxStorageBufferRange;
    info_.max_allocation_size = m3.maxMemoryAllocationSize;
    info_.subgroup_size = p11.subgroupSize;
    info_.max_workgroup_size =
        std::min(props.limits.maxComputeWorkGroupInvocations, props.limits.maxComputeWorkGroupSize[0]);

    if (Status s = create_pipeline_cache(props); !s) return s;

    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT | VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool_info.queueFamilyIndex = queue_family_;
    if (VkResult r = vk_.vkCreateCommandPool(device_, &pool_info, allocator(), &pool_); r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateCommandPool failed: ") + to_string(r));
    name(VK_OBJECT_TYPE_COMMAND_POOL, std::uint64_t(pool_), "gust command pool");
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    if (VkResult r = vk_.vkCreateFence(device_, &fence_info, allocator(), &fence_); r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateFence failed: ") + to_string(r));
    name(VK_OBJECT_TYPE_FENCE, std::uint64_t(fence_), "gust submit fence");

    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    VkRenderPassCreateInfo pass_info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    pass_info.subpassCount = 1;
    pass_info.pSubpasses = &subpass;
    if (VkResult r = vk_.vkCreateRenderPass(device_, &pass_info, allocator(), &render_pass_); r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateRenderPass failed: ") + to_string(r));
    name(VK_OBJECT_TYPE_RENDER_PASS, std::uint64_t(render_pass_), "gust attachmentless pass");
    VkFramebufferCreateInfo framebuffer_info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    framebuffer_info.renderPass = render_pass_;
    framebuffer_info.width = kMaxFramebufferExtent;
    framebuffer_info.height = kMaxFramebufferExtent;
    framebuffer_info.layers = 1;
    if (VkResult r = vk_.vkCreateFramebuffer(device_, &framebuffer_info, allocator(), &framebuffer_);
        r != VK_SUCCESS)
        return Status::failure(std::string("vkCreateFramebuffer failed: ") + to_string(r));
    name(VK_OBJECT_TYPE_FRAMEBUFFER, std::uint64_t(framebuffer_), "gust attachmentless framebuffer");
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
        if (framebuffer_) vk_.vkDestroyFramebuffer(device_, framebuffer_, allocator());
        if (render_pass_) vk_.vkDestroyRenderPass(device_, render_pass_, allocator());
        if (pipeline_cache_) vk_.vkDestroyPipelineCache(device_, pipeline_cache_, allocator());
        if (pool_) vk_.vkDestroyCommandPool(device_, pool_, allocator());
        if (owns_device_) vk_.vkDestroyDevice(device_, allocator());
    }
    if (messenger_) vk_.vkDestroyDebugUtilsMessengerEXT(instance_, messenger_, allocator());
    if (instance_ && owns_device_) {
        keep_drivers_loaded(objects_before_);
        vk_.vkDestroyInstance(instance_, allocator());
    }
    if (loader_) dlclose(loader_);
}

Status Context::begin_one_time(VkCommandBuffer& cmd) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = pool_;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    if (VkResult r = vk_.vkAllocateCommandBuffers(device_, &alloc, &cmd); r != VK_SUCCESS)
        return Status::failure(std::string("vkAllocateCommandBuffers failed: ") + to_string(r));
    name(VK_OBJECT_TYPE_COMMAND_BUFFER, std::uint64_t(cmd), "gust submit_and_wait");
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    if (VkResult r = vk_.vkBeginCommandBuffer(cmd, &begin); r != VK_SUCCESS) {
        vk_.vkFreeCommandBuffers(device_, pool_, 1, &cmd);
        cmd = VK_NULL_HANDLE;
        return Status::failure(std::string("vkBeginCommandBuffer failed: ") + to_string(r));
    }
    count_barrier();
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

    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    Status status;
    vk_.vkResetFences(device_, 1, &fence_);
    VkResult submitted = VK_SUCCESS;
    {
        std::unique_lock<std::mutex> lock;
        if (queue_mutex_) lock = std::unique_lock<std::mutex>(*queue_mutex_);
        submitted = vk_.vkQueueSubmit(queue_, 1, &submit, fence_);
    }
    ++work_.submissions;
    if (submitted != VK_SUCCESS)
        status = Status::failure(std::string("vkQueueSubmit failed: ") + to_string(submitted));
    else if (++work_.waits; vk_.vkWaitForFences(device_, 1, &fence_, VK_TRUE, UINT64_MAX) != VK_SUCCESS)
        status = Status::failure("waiting for the GPU failed");
    vk_.vkFreeCommandBuffers(device_, pool_, 1, &cmd);
    return status;
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
