#include <gust/gpu/image.hpp>
#include <utility>

namespace gust::gpu {

Result<Image> Image::create(Context& ctx, const ImageDesc& desc) {
    if (desc.extent.width == 0 || desc.extent.height == 0 || desc.extent.depth == 0)
        return Result<Image>::failure("cannot create an image with a zero extent");
    const bool volume = desc.volume || desc.extent.depth > 1;
    const auto& vk = ctx.vk();
    Image img;
    img.ctx_ = &ctx;
    img.extent_ = desc.extent;
    img.format_ = desc.format;
    img.usage_ = desc.usage;
    if (desc.exportable && !ctx.external_memory())
        return Result<Image>::failure("an exportable image needs VK_KHR_external_memory_fd on gust's device");
    const VkExternalMemoryHandleTypeFlagBits handle = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    if (desc.exportable) {
        // The device must export and import such an image's memory as an opaque fd, the importer being
        // another VkDevice on the same physical device.
        VkPhysicalDeviceExternalImageFormatInfo external_info{
            VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_IMAGE_FORMAT_INFO};
        external_info.handleType = handle;
        VkPhysicalDeviceImageFormatInfo2 format_info{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_IMAGE_FORMAT_INFO_2,
                                                     &external_info};
        format_info.format = desc.format;
        format_info.type = volume ? VK_IMAGE_TYPE_3D : VK_IMAGE_TYPE_2D;
        format_info.tiling = VK_IMAGE_TILING_OPTIMAL;
        format_info.usage = desc.usage;
        VkExternalImageFormatProperties external_props{VK_STRUCTURE_TYPE_EXTERNAL_IMAGE_FORMAT_PROPERTIES};
        VkImageFormatProperties2 props{VK_STRUCTURE_TYPE_IMAGE_FORMAT_PROPERTIES_2, &external_props};
        const VkExternalMemoryFeatureFlags both =
            VK_EXTERNAL_MEMORY_FEATURE_EXPORTABLE_BIT | VK_EXTERNAL_MEMORY_FEATURE_IMPORTABLE_BIT;
        if (vk.vkGetPhysicalDeviceImageFormatProperties2(ctx.physical_device(), &format_info, &props) !=
                VK_SUCCESS ||
            (external_props.externalMemoryProperties.externalMemoryFeatures & both) != both)
            return Result<Image>::failure("the device cannot export and import this image's memory as an "
                                          "opaque fd");
    }
    VkExternalMemoryImageCreateInfo external{VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_IMAGE_CREATE_INFO};
    external.handleTypes = handle;
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.pNext = desc.exportable ? &external : nullptr;
    info.imageType = volume ? VK_IMAGE_TYPE_3D : VK_IMAGE_TYPE_2D;
    info.format = desc.format;
    info.extent = desc.extent;
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = desc.usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    if (VkResult r = vk.vkCreateImage(ctx.device(), &info, ctx.allocator(), &img.image_); r != VK_SUCCESS)
        return Result<Image>::failure(std::string("vkCreateImage failed: ") + to_string(r));
    ctx.name(VK_OBJECT_TYPE_IMAGE, std::uint64_t(img.image_), desc.name);
    VkMemoryRequirements req;
    vk.vkGetImageMemoryRequirements(ctx.device(), img.image_, &req);
    const std::uint32_t type =
        ctx.find_memory_type(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (type == UINT32_MAX) return Result<Image>::failure("no memory type for an image");
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = type;
    // An importer must allocate as the exporter did, dedicated included: always dedicated, one rule for all.
    VkMemoryDedicatedAllocateInfo dedicated{VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO};
    dedicated.image = img.image_;
    VkExportMemoryAllocateInfo exported{VK_STRUCTURE_TYPE_EXPORT_MEMORY_ALLOCATE_INFO, &dedicated};
    exported.handleTypes = handle;
    if (desc.exportable) alloc.pNext = &exported;
    img.allocation_size_ = req.size;
    img.memory_type_ = type;
    if (VkResult r = vk.vkAllocateMemory(ctx.device(), &alloc, ctx.allocator(), &img.memory_);
        r != VK_SUCCESS)
        return Result<Image>::failure("cannot allocate " + std::to_string(req.size) +
                                      " bytes: " + to_string(r));
    vk.vkBindImageMemory(ctx.device(), img.image_, img.memory_, 0);
    ctx.name(VK_OBJECT_TYPE_DEVICE_MEMORY, std::uint64_t(img.memory_), desc.name);
    VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view.image = img.image_;
    view.viewType = volume ? VK_IMAGE_VIEW_TYPE_3D : VK_IMAGE_VIEW_TYPE_2D;
    view.format = desc.format;
    view.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    if (VkResult r = vk.vkCreateImageView(ctx.device(), &view, ctx.allocator(), &img.view_); r != VK_SUCCESS)
        return Result<Image>::failure(std::string("vkCreateImageView failed: ") + to_string(r));
    ctx.name(VK_OBJECT_TYPE_IMAGE_VIEW, std::uint64_t(img.view_), desc.name);
    return img;
}

Result<int> Image::export_fd() const {
    if (!ctx_ || !ctx_->external_memory() || !memory_)
        return Result<int>::failure("the image's memory is not exportable");
    VkMemoryGetFdInfoKHR info{VK_STRUCTURE_TYPE_MEMORY_GET_FD_INFO_KHR};
    info.memory = memory_;
    info.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    int fd = -1;
    if (VkResult r = ctx_->vk().vkGetMemoryFdKHR(ctx_->device(), &info, &fd); r != VK_SUCCESS)
        return Result<int>::failure(std::string("vkGetMemoryFdKHR failed: ") + to_string(r));
    return fd;
}

void Image::transition(VkCommandBuffer cmd, VkImageLayout layout) {
    barrier(cmd, layout, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED);
}

void Image::release_to_external(VkCommandBuffer cmd, VkImageLayout layout) {
    barrier(cmd, layout, ctx_->queue_family(), VK_QUEUE_FAMILY_EXTERNAL);
}

void Image::barrier(VkCommandBuffer cmd, VkImageLayout layout, std::uint32_t src_family,
                    std::uint32_t dst_family) {
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
    // A release's destination access is the acquiring side's to state (Vulkan ignores it here).
    b.dstAccessMask =
        dst_family == VK_QUEUE_FAMILY_EXTERNAL ? 0 : VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    b.oldLayout = layout_;
    b.newLayout = layout;
    b.srcQueueFamilyIndex = src_family;
    b.dstQueueFamilyIndex = dst_family;
    b.image = image_;
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    ctx_->vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                                    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
    ctx_->count_barrier();
    layout_ = layout;
}

void Image::copy_from(VkCommandBuffer cmd, const Buffer& src) const {
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = extent_;
    ctx_->vk().vkCmdCopyBufferToImage(cmd, src.handle(), image_, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                                      &region);
}

void Image::copy_to(VkCommandBuffer cmd, const Buffer& dst) const {
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = extent_;
    ctx_->vk().vkCmdCopyImageToBuffer(cmd, image_, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, dst.handle(), 1,
                                      &region);
}

void Image::release() {
    if (!ctx_) return;
    const auto& vk = ctx_->vk();
    if (view_) vk.vkDestroyImageView(ctx_->device(), view_, ctx_->allocator());
    if (image_) vk.vkDestroyImage(ctx_->device(), image_, ctx_->allocator());
    if (memory_) vk.vkFreeMemory(ctx_->device(), memory_, ctx_->allocator());
    view_ = VK_NULL_HANDLE;
    image_ = VK_NULL_HANDLE;
    memory_ = VK_NULL_HANDLE;
}

Image::~Image() {
    release();
}

Image::Image(Image&& other) noexcept {
    *this = std::move(other);
}

Image& Image::operator=(Image&& other) noexcept {
    if (this != &other) {
        release();
        ctx_ = std::exchange(other.ctx_, nullptr);
        image_ = std::exchange(other.image_, VK_NULL_HANDLE);
        view_ = std::exchange(other.view_, VK_NULL_HANDLE);
        memory_ = std::exchange(other.memory_, VK_NULL_HANDLE);
        extent_ = other.extent_;
        usage_ = other.usage_;
        allocation_size_ = other.allocation_size_;
        memory_type_ = other.memory_type_;
        format_ = other.format_;
        layout_ = other.layout_;
    }
    return *this;
}

} // namespace gust::gpu
