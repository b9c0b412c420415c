// Context::adopt(): a host engine's instance, device and queue, checked and loaded through the host's
// entry points; gust creates nothing here but its debug messenger (HostDevice::on_message).
#include "context_detail.hpp"
#include "vk_load.hpp"

#include <algorithm>
#include <cstring>

namespace gust::gpu {

using namespace detail;

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
    load_global_functions(vk_);
    if (Status s = load_instance_table(vk_, instance_); !s) return s;
    if (host.get_device_proc_addr) vk_.vkGetDeviceProcAddr = host.get_device_proc_addr;
    if (on_message_ || host.debug_utils) {
        load_debug_functions(vk_, instance_);
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
    if (!(family.queueFlags & VK_QUEUE_COMPUTE_BIT))
        return Status::failure("HostDevice::queue_family " + std::to_string(host.queue_family) +
                               " of device '" + std::string(device) + "' does not support compute");
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

} // namespace gust::gpu
