#include <algorithm>
#include <cstring>
#include <gust/gpu/buffer.hpp>
#include <utility>

namespace gust::gpu {

Result<Buffer> Buffer::create(Context& ctx, VkDeviceSize size, MemoryUse use, VkBufferUsageFlags extra_usage,
                              const char* name) {
    if (size == 0) return Result<Buffer>::failure("cannot create a buffer of 0 bytes");
    if (ctx.info().max_allocation_size && size > ctx.info().max_allocation_size)
        return Result<Buffer>::failure("buffer of " + std::to_string(size) + " bytes exceeds the device's " +
                                       std::to_string(ctx.info().max_allocation_size) +
                                       "-byte allocation limit");
    const auto& vk = ctx.vk();
    Buffer b;
    b.ctx_ = &ctx;
    b.size_ = size;
    if (Status s = ctx.reserve_release_slot(); !s) return s;
    b.slot_ = true;
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = size;
    info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                 VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | extra_usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    if (VkResult r = vk.vkCreateBuffer(ctx.device(), &info, ctx.allocator(), &b.buffer_); r != VK_SUCCESS)
        return Result<Buffer>::failure(std::string("vkCreateBuffer failed: ") + to_string(r));
    ctx.name(VK_OBJECT_TYPE_BUFFER, std::uint64_t(b.buffer_), name);

    VkMemoryRequirements req;
    vk.vkGetBufferMemoryRequirements(ctx.device(), b.buffer_, &req);
    VkMemoryPropertyFlags required = 0;
    VkMemoryPropertyFlags preferred = 0;
    switch (use) {
    case MemoryUse::Device:
        preferred = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
        break;
    case MemoryUse::Upload:
        required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        break;
    case MemoryUse::Readback:
        required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        preferred = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
        break;
    }
    const std::uint32_t type = ctx.find_memory_type(req.memoryTypeBits, required, preferred);
    if (type == UINT32_MAX) return Result<Buffer>::failure("no suitable memory type for a buffer");

    VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    alloc.pNext = &flags;
    alloc.allocationSize = req.size;
    alloc.memoryTypeIndex = type;
    if (VkResult r = vk.vkAllocateMemory(ctx.device(), &alloc, ctx.allocator(), &b.memory_); r != VK_SUCCESS)
        return Result<Buffer>::failure("cannot allocate " + std::to_string(req.size) +
                                       " bytes: " + to_string(r));
    vk.vkBindBufferMemory(ctx.device(), b.buffer_, b.memory_, 0);
    ctx.name(VK_OBJECT_TYPE_DEVICE_MEMORY, std::uint64_t(b.memory_), name);

    const VkMemoryPropertyFlags got = ctx.memory_flags(type);
    const VkMemoryPropertyFlags mappable =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    if ((got & mappable) == mappable)
        vk.vkMapMemory(ctx.device(), b.memory_, 0, VK_WHOLE_SIZE, 0, &b.mapped_);

    VkBufferDeviceAddressInfo address{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    address.buffer = b.buffer_;
    b.address_ = vk.vkGetBufferDeviceAddress(ctx.device(), &address);
    return b;
}

void Buffer::release() {
    if (!ctx_) return;
    const auto& vk = ctx_->vk();
    if (ctx_->deferred() && buffer_) {
        ctx_->release_later(buffer_, memory_);
    } else {
        if (buffer_) vk.vkDestroyBuffer(ctx_->device(), buffer_, ctx_->allocator());
        if (memory_) vk.vkFreeMemory(ctx_->device(), memory_, ctx_->allocator());
    }
    if (std::exchange(slot_, false)) ctx_->drop_release_slot();
    buffer_ = VK_NULL_HANDLE;
    memory_ = VK_NULL_HANDLE;
    mapped_ = nullptr;
}

Buffer::~Buffer() {
    release();
}

Buffer::Buffer(Buffer&& other) noexcept {
    *this = std::move(other);
}

Buffer& Buffer::operator=(Buffer&& other) noexcept {
    if (this != &other) {
        release();
        ctx_ = std::exchange(other.ctx_, nullptr);
        buffer_ = std::exchange(other.buffer_, VK_NULL_HANDLE);
        memory_ = std::exchange(other.memory_, VK_NULL_HANDLE);
        address_ = std::exchange(other.address_, 0);
        size_ = std::exchange(other.size_, 0);
        mapped_ = std::exchange(other.mapped_, nullptr);
        slot_ = std::exchange(other.slot_, false);
    }
    return *this;
}

Status upload(Context& ctx, Buffer& dst, const void* data, std::size_t bytes, std::size_t offset) {
    if (bytes == 0) return {};
    if (offset + bytes > dst.size()) return Status::failure("upload past the end of a buffer");
    if (dst.mapped()) {
        std::memcpy(static_cast<char*>(dst.mapped()) + offset, data, bytes);
        return {};
    }
    auto staging = Buffer::create(ctx, bytes, MemoryUse::Upload, 0, "gust staging");
    if (!staging) return staging.status();
    std::memcpy(staging->mapped(), data, bytes);
    return ctx.submit_and_wait([&](VkCommandBuffer cmd) {
        VkBufferCopy region{0, offset, bytes};
        ctx.vk().vkCmdCopyBuffer(cmd, staging->handle(), dst.handle(), 1, &region);
    });
}

Status download(Context& ctx, const Buffer& src, void* data, std::size_t bytes, std::size_t offset) {
    if (bytes == 0) return {};
    if (offset + bytes > src.size()) return Status::failure("download past the end of a buffer");
    if (src.mapped()) {
        std::memcpy(data, static_cast<const char*>(src.mapped()) + offset, bytes);
        return {};
    }
    auto staging = Buffer::create(ctx, bytes, MemoryUse::Readback, 0, "gust download staging");
    if (!staging) return staging.status();
    Status s = ctx.submit_and_wait([&](VkCommandBuffer cmd) {
        VkBufferCopy region{offset, 0, bytes};
        ctx.vk().vkCmdCopyBuffer(cmd, src.handle(), staging->handle(), 1, &region);
    });
    if (!s) return s;
    std::memcpy(data, staging->mapped(), bytes);
    return {};
}

void update(const Context& ctx, VkCommandBuffer cmd, const Buffer& dst, const void* data, std::size_t bytes,
            std::size_t offset) {
    const auto* from = static_cast<const unsigned char*>(data);
    for (std::size_t done = 0; done < bytes; done += kMaxUpdateBytes) {
        const std::size_t size = std::min(kMaxUpdateBytes, bytes - done);
        ctx.vk().vkCmdUpdateBuffer(cmd, dst.handle(), offset + done, size, from + done);
    }
}

void record_readback(const Context& ctx, VkCommandBuffer cmd, const Buffer& src, std::size_t bytes,
                     VkBuffer dst, VkDeviceSize offset, std::span<const std::uint32_t> after) {
    const VkBufferCopy region{0, offset, bytes};
    ctx.vk().vkCmdCopyBuffer(cmd, src.handle(), dst, 1, &region);
    if (!after.empty())
        ctx.vk().vkCmdUpdateBuffer(cmd, dst, offset + bytes, after.size_bytes(), after.data());
}

void barrier(const Context& ctx, VkCommandBuffer cmd) {
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
    ctx.vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                                  0, 1, &mb, 0, nullptr, 0, nullptr);
    ctx.count_barrier();
}

void compute_barrier(const Context& ctx, VkCommandBuffer cmd) {
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    mb.dstAccessMask =
        VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_INDIRECT_COMMAND_READ_BIT;
    ctx.vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT,
                                  0, 1, &mb, 0, nullptr, 0, nullptr);
    ctx.count_barrier();
}

} // namespace gust::gpu
