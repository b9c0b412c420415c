// The sample's own Vulkan: the instance, device and queue a game engine would own, created with the
// features gust asks for so that gust can adopt the device and share its wind texture.
#pragma once

#include <cstdint>
#include <gust/gust.hpp>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

namespace sample {

/// A failed Vulkan call or a missing capability; caught in main and printed.
struct VulkanError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Throws VulkanError naming `what` when `result` is not VK_SUCCESS.
void check(VkResult result, const char* what);

/// A buffer with its own memory (a sample needs few, so no sub-allocation).
struct Buffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkDeviceSize size = 0;
    void* mapped = nullptr; ///< host-visible buffers stay mapped
};

/// An image with its own memory and one view.
struct Image {
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
    VkFormat format = VK_FORMAT_UNDEFINED;
    VkExtent3D extent{};
};

/// Instance, device, one graphics+compute queue and a command pool.
class VulkanHost {
  public:
    /// `instance_extensions`: what the window system needs (GLFW), empty headless. With `validation`, the
    /// Khronos layer is enabled and every message it sends is printed and counted.
    VulkanHost(std::span<const char* const> instance_extensions, bool validation, bool want_swapchain);
    ~VulkanHost();
    VulkanHost(const VulkanHost&) = delete;
    VulkanHost& operator=(const VulkanHost&) = delete;

    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physical_device() const { return physical_; }
    VkDevice device() const { return device_; }
    VkQueue queue() const { return queue_; }
    std::uint32_t queue_family() const { return family_; }
    VkCommandPool command_pool() const { return pool_; }
    const VkPhysicalDeviceProperties& properties() const { return properties_; }
    /// The handles gust adopts.
    gust::HostDevice gust_host() const;
    /// Validation messages seen so far (0 without validation).
    std::uint32_t validation_messages() const { return messages_; }

    /// A buffer; `host_visible` ones are mapped and coherent.
    Buffer create_buffer(VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible);
    void destroy(Buffer& buffer);
    /// A 2D or 3D image (depth 1: 2D) in UNDEFINED layout with a view of `aspect`.
    Image create_image(VkFormat format, VkExtent3D extent, VkImageUsageFlags usage,
                       VkImageAspectFlags aspect);
    void destroy(Image& image);
    /// Records with `record` into a one-time command buffer, submits it and waits.
    template <class F> void submit_now(F&& record) {
        VkCommandBuffer cmd = begin_one_time();
        record(cmd);
        end_one_time(cmd);
    }
    VkShaderModule create_shader(std::span<const std::uint32_t> spirv);

  private:
    VkCommandBuffer begin_one_time();
    void end_one_time(VkCommandBuffer cmd);
    std::uint32_t memory_type(std::uint32_t bits, VkMemoryPropertyFlags wanted) const;
    static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                     void* user);

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memory_{};
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    std::uint32_t family_ = 0;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    std::uint32_t messages_ = 0;
};

/// A layout transition of a whole colour or depth image (stages and accesses as given).
void transition(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                VkImageLayout to, VkPipelineStageFlags src_stage, VkAccessFlags src_access,
                VkPipelineStageFlags dst_stage, VkAccessFlags dst_access);

} // namespace sample
