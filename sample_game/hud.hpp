// Dear ImGui on the sample's device: set-up, a new frame per frame, and drawing into the render pass.
#pragma once

#include "vk_host.hpp"

struct GLFWwindow;

namespace sample {

class Hud {
  public:
    /// With a window, input comes from GLFW (its callbacks are chained after the game's); without one
    /// the HUD is laid out for `extent` and drawn into the offscreen frames.
    Hud(VulkanHost& vk, VkRenderPass pass, std::uint32_t image_count, GLFWwindow* window, VkExtent2D extent);
    ~Hud();
    Hud(const Hud&) = delete;
    Hud& operator=(const Hud&) = delete;

    /// Starts a frame (ImGui calls may follow until draw()); `dt` in seconds.
    void begin_frame(float dt);
    /// Records the frame's widgets into `cmd` inside the render pass.
    void draw(VkCommandBuffer cmd);
    /// Whether ImGui wants the mouse or keyboard (the game then ignores them).
    bool wants_mouse() const;
    bool wants_keyboard() const;

  private:
    VulkanHost& vk_;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    GLFWwindow* window_;
    VkExtent2D extent_;
};

} // namespace sample
