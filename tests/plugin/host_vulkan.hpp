// A host engine's Vulkan setup as a test plays it: its own loader, instance (validation on, messages
// counted), device with gust's required features, one graphics+compute queue, and optionally a queue of an
// async compute family.
#pragma once

#include <atomic>
#include <gust/gust.hpp>
#include <string>
#include <vector>

namespace gust::test {

class HostVulkan {
  public:
    /// Creates everything; ok() says whether it worked and error() why not. With `external_memory` the device
    /// also enables VK_KHR_external_memory_fd, as an engine that imports gust's exported copies does. With
    /// `async_compute` the device also gets a queue of the first compute-only family, where it has one.
    explicit HostVulkan(bool external_memory = false, bool async_compute = false);
    ~HostVulkan();
    HostVulkan(const HostVulkan&) = delete;
    HostVulkan& operator=(const HostVulkan&) = delete;

    bool ok() const { return error_.empty(); }
    const std::string& error() const { return error_; }
    /// What gust::SystemDesc::host points at: the graphics+compute family's queue.
    const HostDevice& device() const { return host_; }
    /// The family of the async compute queue (queue 0 of it): a compute-only family with `async_compute`
    /// where the device has one, else device().queue_family.
    std::uint32_t compute_family() const { return compute_family_; }
    /// Validation-layer warnings and errors seen so far.
    int messages() const { return messages_.load(); }
    /// A device function of the host's device, by name.
    PFN_vkVoidFunction device_function(const char* name) const;
    /// Records `record` into a command buffer of the host's own pool, submits it and waits.
    bool run(void (*record)(VkCommandBuffer, void*), void* user);
    /// An engine's frame loop with `count` frames in flight (1..8): begin_frame() waits for the command
    /// buffer it began `count` calls ago and begins it again (null on failure); submit_frame() ends and
    /// submits it without waiting.
    bool start_frames(std::uint32_t count);
    VkCommandBuffer begin_frame();
    bool submit_frame();
    /// Waits for every submitted frame.
    bool finish_frames();

  private:
    static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                     VkDebugUtilsMessageTypeFlagsEXT,
                                                     const VkDebugUtilsMessengerCallbackDataEXT*, void*);
    void* loader_ = nullptr;
    HostDevice host_;
    std::uint32_t compute_family_ = 0;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    std::vector<VkCommandBuffer> frame_commands_;
    std::vector<VkFence> frame_fences_;
    std::uint64_t frames_ = 0;
    std::atomic<int> messages_{0};
    std::string error_;
};

} // namespace gust::test
