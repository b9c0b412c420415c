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
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
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

void Image::transition(VkCommandBuffer cmd, VkImageLayout layout) {
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    b.oldLayout = layout_;
    b.newLayout = layout;
    b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
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
        format_ = other.format_;
        layout_ = other.layout_;
    }
    return *this;
}

} // namespace gust::gpu
