#include "display.hpp"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <algorithm>
#include <stb/stb_image_write.h>
#include <stdexcept>

namespace sample {

Swapchain::Swapchain(VulkanHost& vk, GLFWwindow* window) : vk_(vk), window_(window) {
    check(glfwCreateWindowSurface(vk_.instance(), window_, nullptr, &surface_), "glfwCreateWindowSurface");
    VkBool32 supported = VK_FALSE;
    vkGetPhysicalDeviceSurfaceSupportKHR(vk_.physical_device(), vk_.queue_family(), surface_, &supported);
    if (!supported) throw VulkanError("the device's queue cannot present to this window");
    VkSemaphoreCreateInfo semaphore{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    check(vkCreateSemaphore(vk_.device(), &semaphore, nullptr, &acquired_), "vkCreateSemaphore");
    create();
}

Swapchain::~Swapchain() {
    vkDeviceWaitIdle(vk_.device());
    destroy_images();
    vkDestroySwapchainKHR(vk_.device(), swapchain_, nullptr);
    vkDestroySemaphore(vk_.device(), acquired_, nullptr);
    vkDestroySurfaceKHR(vk_.instance(), surface_, nullptr);
}

void Swapchain::destroy_images() {
    for (VkImageView v : views_)
        vkDestroyImageView(vk_.device(), v, nullptr);
    for (VkSemaphore s : rendered_)
        vkDestroySemaphore(vk_.device(), s, nullptr);
    views_.clear();
    rendered_.clear();
    images_.clear();
}

void Swapchain::create() {
    VkPhysicalDevice physical = vk_.physical_device();
    VkSurfaceCapabilitiesKHR caps;
    check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(physical, surface_, &caps),
          "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
    std::uint32_t count = 0;
    vkGetPhysicalDeviceSurfaceFormatsKHR(physical, surface_, &count, nullptr);
    std::vector<VkSurfaceFormatKHR> formats(count);
    vkGetPhysicalDeviceSurfaceFormatsKHR(physical, surface_, &count, formats.data());
    if (formats.empty()) throw VulkanError("the window offers no surface format");
    VkSurfaceFormatKHR chosen = formats[0];
    for (const VkSurfaceFormatKHR& f : formats)
        if ((f.format == VK_FORMAT_B8G8R8A8_SRGB || f.format == VK_FORMAT_R8G8B8A8_SRGB) &&
            f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR)
            chosen = f;
    // The render pass is made once for one format; a re-created swapchain keeps the first choice.
    if (format_ == VK_FORMAT_UNDEFINED) format_ = chosen.format;
    int width = 0, height = 0;
    glfwGetFramebufferSize(window_, &width, &height);
    extent_ = caps.currentExtent.width != UINT32_MAX
                  ? caps.currentExtent
                  : VkExtent2D{std::clamp(static_cast<std::uint32_t>(width), caps.minImageExtent.width,
                                          caps.maxImageExtent.width),
                               std::clamp(static_cast<std::uint32_t>(height), caps.minImageExtent.height,
                                          caps.maxImageExtent.height)};
    std::uint32_t images = std::max(caps.minImageCount + 1, 2u);
    if (caps.maxImageCount) images = std::min(images, caps.maxImageCount);
    VkSwapchainKHR old = swapchain_;
    VkSwapchainCreateInfoKHR info{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
    info.surface = surface_;
    info.minImageCount = images;
    info.imageFormat = format_;
    info.imageColorSpace = chosen.colorSpace;
    info.imageExtent = extent_;
    info.imageArrayLayers = 1;
    info.imageUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
    info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.preTransform = caps.currentTransform;
    info.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
    info.presentMode = VK_PRESENT_MODE_FIFO_KHR;
    info.clipped = VK_TRUE;
    info.oldSwapchain = old;
    check(vkCreateSwapchainKHR(vk_.device(), &info, nullptr, &swapchain_), "vkCreateSwapchainKHR");
    if (old) vkDestroySwapchainKHR(vk_.device(), old, nullptr);
    vkGetSwapchainImagesKHR(vk_.device(), swapchain_, &count, nullptr);
    images_.resize(count);
    vkGetSwapchainImagesKHR(vk_.device(), swapchain_, &count, images_.data());
    for (VkImage image : images_) {
        VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
        view.image = image;
        view.viewType = VK_IMAGE_VIEW_TYPE_2D;
        view.format = format_;
        view.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        VkImageView v = VK_NULL_HANDLE;
        check(vkCreateImageView(vk_.device(), &view, nullptr, &v), "vkCreateImageView");
        views_.push_back(v);
        VkSemaphoreCreateInfo semaphore{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
        VkSemaphore s = VK_NULL_HANDLE;
        check(vkCreateSemaphore(vk_.device(), &semaphore, nullptr, &s), "vkCreateSemaphore");
        rendered_.push_back(s);
    }
}

bool Swapchain::acquire(Target& target, bool& recreated) {
    recreated = false;
    int width = 0, height = 0;
    glfwGetFramebufferSize(window_, &width, &height);
    if (width == 0 || height == 0) return false;
    const VkResult result =
        vkAcquireNextImageKHR(vk_.device(), swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index_);
    if (result == VK_ERROR_OUT_OF_DATE_KHR) {
        vkDeviceWaitIdle(vk_.device());
        destroy_images();
        create();
        recreated = true;
        return false;
    }
    if (result != VK_SUBOPTIMAL_KHR) check(result, "vkAcquireNextImageKHR");
    target = {images_[index_], views_[index_], extent_};
    return true;
}

void Swapchain::submit_and_present(VkCommandBuffer cmd, VkFence fence, bool& recreated) {
    recreated = false;
    const VkPipelineStageFlags wait_stage = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.waitSemaphoreCount = 1;
    submit.pWaitSemaphores = &acquired_;
    submit.pWaitDstStageMask = &wait_stage;
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    submit.signalSemaphoreCount = 1;
    submit.pSignalSemaphores = &rendered_[index_];
    check(vkQueueSubmit(vk_.queue(), 1, &submit, fence), "vkQueueSubmit");
    VkPresentInfoKHR present{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    present.waitSemaphoreCount = 1;
    present.pWaitSemaphores = &rendered_[index_];
    present.swapchainCount = 1;
    present.pSwapchains = &swapchain_;
    present.pImageIndices = &index_;
    const VkResult result = vkQueuePresentKHR(vk_.queue(), &present);
    if (result == VK_ERROR_OUT_OF_DATE_KHR || result == VK_SUBOPTIMAL_KHR) {
        vkDeviceWaitIdle(vk_.device());
        destroy_images();
        create();
        recreated = true;
    } else {
        check(result, "vkQueuePresentKHR");
    }
}

Offscreen::Offscreen(VulkanHost& vk, VkExtent2D extent) : vk_(vk) {
    image_ = vk_.create_image(kFormat, {extent.width, extent.height, 1},
                              VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                              VK_IMAGE_ASPECT_COLOR_BIT);
    readback_ = vk_.create_buffer(VkDeviceSize(extent.width) * extent.height * 4,
                                  VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
}

Offscreen::~Offscreen() {
    vkDeviceWaitIdle(vk_.device());
    vk_.destroy(readback_);
    vk_.destroy(image_);
}

void Offscreen::record_readback(VkCommandBuffer cmd) {
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = image_.extent;
    vkCmdCopyImageToBuffer(cmd, image_.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.buffer, 1,
                           &copy);
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
}

void Offscreen::submit(VkCommandBuffer cmd, VkFence fence) {
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    check(vkQueueSubmit(vk_.queue(), 1, &submit, fence), "vkQueueSubmit");
}

void Offscreen::write_png(const std::filesystem::path& path) const {
    const int width = static_cast<int>(image_.extent.width), height = static_cast<int>(image_.extent.height);
    // RGBA to RGB: the alpha channel carries nothing a viewer should blend with.
    std::vector<unsigned char> rgb(std::size_t(width) * height * 3);
    const auto* rgba = static_cast<const unsigned char*>(readback_.mapped);
    for (std::size_t i = 0; i < std::size_t(width) * height; ++i)
        for (int c = 0; c < 3; ++c)
            rgb[3 * i + c] = rgba[4 * i + c];
    // No row filter and stb's lightest compression: half the encoding time of its defaults, for files about
    // as large. The pause between frames that the encoding makes slows the next frame on a CPU device.
    stbi_write_force_png_filter = 0;
    stbi_write_png_compression_level = 5;
    if (!stbi_write_png(path.c_str(), width, height, 3, rgb.data(), width * 3))
        throw std::runtime_error("cannot write " + path.string());
}

} // namespace sample
