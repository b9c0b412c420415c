// 2D and 3D images with one view, for the wind field the host samples and for debug views.
#pragma once

#include <cstdint>
#include <gust/gpu/buffer.hpp>

namespace gust::gpu {

/// What to create: a 2D image when extent.depth == 1 and `volume` is false, else a 3D image.
struct ImageDesc {
    VkExtent3D extent{1, 1, 1};
    VkFormat format = VK_FORMAT_R32G32B32A32_SFLOAT;
    VkImageUsageFlags usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
                              VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    bool volume = false; ///< force a 3D image even when depth is 1
    /// Memory another VkDevice on the same physical device can import (VK_KHR_external_memory_fd, an opaque
    /// fd; the Context must have external_memory()): a dedicated allocation, handed out by export_fd().
    bool exportable = false;
    /// Name of the image and its view in frame captures (a literal, or null); see Context::name().
    const char* name = nullptr;
};

/// A device-local image, its memory and a view of the whole image. Move-only; starts in
/// VK_IMAGE_LAYOUT_UNDEFINED and tracks the layout set through transition().
class Image {
  public:
    Image() = default;
    /// Creates the image and its view, both named desc.name; fails with a message when the format or size
    /// is unsupported.
    static Result<Image> create(Context& ctx, const ImageDesc& desc);
    ~Image();
    Image(Image&& other) noexcept;
    Image& operator=(Image&& other) noexcept;
    Image(const Image&) = delete;
    Image& operator=(const Image&) = delete;

    VkImage handle() const { return image_; }
    VkImageView view() const { return view_; }
    VkExtent3D extent() const { return extent_; }
    VkFormat format() const { return format_; }
    VkImageLayout layout() const { return layout_; }
    VkImageUsageFlags usage() const { return usage_; }
    /// Bytes and memory type of the image's allocation: an importer of export_fd() allocates the same.
    VkDeviceSize allocation_size() const { return allocation_size_; }
    std::uint32_t memory_type() const { return memory_type_; }
    /// ImageDesc::exportable: a new file descriptor for the image's memory (opaque fd), the caller's to
    /// close or to import (vkAllocateMemory with VkImportMemoryFdInfoKHR takes it over).
    Result<int> export_fd() const;

    /// Records a full barrier moving the whole image to `layout` (previous contents kept unless UNDEFINED).
    void transition(VkCommandBuffer cmd, VkImageLayout layout);
    /// The contents are not needed any more: the next transition starts from VK_IMAGE_LAYOUT_UNDEFINED, which
    /// needs no ownership acquired from another queue family (Vulkan's queue family ownership rules).
    void discard() { layout_ = VK_IMAGE_LAYOUT_UNDEFINED; }
    /// Records a full barrier to `layout` that releases the image from the Context's queue family to
    /// VK_QUEUE_FAMILY_EXTERNAL: another VkDevice reads it next (ImageDesc::exportable). gust writes it again
    /// only after discard().
    void release_to_external(VkCommandBuffer cmd, VkImageLayout layout);
    /// Records a copy of tightly packed texels from `src` into the image (must be TRANSFER_DST_OPTIMAL).
    void copy_from(VkCommandBuffer cmd, const Buffer& src) const;
    /// Records a copy of the image (TRANSFER_SRC_OPTIMAL) into `dst`, tightly packed.
    void copy_to(VkCommandBuffer cmd, const Buffer& dst) const;

  private:
    Context* ctx_ = nullptr;
    VkImage image_ = VK_NULL_HANDLE;
    VkImageView view_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkExtent3D extent_{};
    VkFormat format_ = VK_FORMAT_UNDEFINED;
    VkImageLayout layout_ = VK_IMAGE_LAYOUT_UNDEFINED;
    VkImageUsageFlags usage_ = 0;
    VkDeviceSize allocation_size_ = 0;
    std::uint32_t memory_type_ = 0;
    void release();
    void barrier(VkCommandBuffer cmd, VkImageLayout layout, std::uint32_t src_family,
                 std::uint32_t dst_family);
};

} // namespace gust::gpu
