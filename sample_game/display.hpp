// Where frames go: a GLFW window's swapchain, or an offscreen image copied to PNG files.
#pragma once

#include "vk_host.hpp"

#include <filesystem>
#include <vector>

struct GLFWwindow;

namespace sample {

/// The image this frame renders into.
struct Target {
    VkImage image = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
    VkExtent2D extent{};
};

/// A window's swapchain (FIFO: the frame rate is capped by the display, as a game's would be).
class Swapchain {
  public:
    Swapchain(VulkanHost& vk, GLFWwindow* window);
    ~Swapchain();
    Swapchain(const Swapchain&) = delete;
    Swapchain& operator=(const Swapchain&) = delete;

    VkFormat format() const { return format_; }
    std::uint32_t image_count() const { return static_cast<std::uint32_t>(images_.size()); }
    /// The next image; false when the window is minimised or the swapchain had to be re-created (skip
    /// the frame; `recreated` tells the renderer to drop its framebuffers).
    bool acquire(Target& target, bool& recreated);
    /// Submits `cmd` after the acquire and presents; signals `fence` when the GPU is done.
    void submit_and_present(VkCommandBuffer cmd, VkFence fence, bool& recreated);

  private:
    void create();
    void destroy_images();

    VulkanHost& vk_;
    GLFWwindow* window_;
    VkSurfaceKHR surface_ = VK_NULL_HANDLE;
    VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
    VkFormat format_ = VK_FORMAT_UNDEFINED;
    VkExtent2D extent_{};
    std::vector<VkImage> images_;
    std::vector<VkImageView> views_;
    std::vector<VkSemaphore> rendered_; ///< one per image: presentation may still wait on the last one
    VkSemaphore acquired_ = VK_NULL_HANDLE;
    std::uint32_t index_ = 0;
};

/// An offscreen colour image whose frames are read back into memory and written as PNG.
class Offscreen {
  public:
    static constexpr VkFormat kFormat = VK_FORMAT_R8G8B8A8_SRGB;
    Offscreen(VulkanHost& vk, VkExtent2D extent);
    ~Offscreen();
    Offscreen(const Offscreen&) = delete;
    Offscreen& operator=(const Offscreen&) = delete;

    Target target() const { return {image_.image, image_.view, {image_.extent.width, image_.extent.height}}; }
    /// Records the copy of the rendered image (in TRANSFER_SRC layout) into the readback buffer.
    void record_readback(VkCommandBuffer cmd);
    /// Submits `cmd`, signalling `fence`.
    void submit(VkCommandBuffer cmd, VkFence fence);
    /// Writes the last read-back frame as an 8-bit RGB PNG; throws std::runtime_error on failure.
    void write_png(const std::filesystem::path& path) const;

  private:
    VulkanHost& vk_;
    Image image_;
    Buffer readback_;
};

} // namespace sample
