// Device buffers addressed by pointer (VK_KHR_buffer_device_address, core in 1.2), so shaders take
// them through push constants and a buffer is not bound by maxStorageBufferRange (128 MiB on lavapipe).
#pragma once

#include <cstddef>
#include <cstdint>
#include <gust/gpu/context.hpp>
#include <span>

namespace gust::gpu {

/// Where a buffer's memory should live.
enum class MemoryUse {
    Device,  ///< GPU-local; mapped too when the device exposes such memory (lavapipe, ReBAR)
    Upload,  ///< host-visible, written by the CPU
    Readback ///< host-visible and cached, read by the CPU
};

/// A buffer with its own memory allocation. Move-only; destroys itself (the caller keeps the Context
/// alive longer and makes sure the GPU no longer uses it).
class Buffer {
  public:
    Buffer() = default;
    /// Creates a buffer of `size` bytes (> 0) named `name` for capture tools (a literal, or null). Storage,
    /// transfer and device-address usage are always added.
    static Result<Buffer> create(Context& ctx, VkDeviceSize size, MemoryUse use,
                                 VkBufferUsageFlags extra_usage = 0, const char* name = nullptr);
    ~Buffer();
    Buffer(Buffer&& other) noexcept;
    Buffer& operator=(Buffer&& other) noexcept;
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;

    VkBuffer handle() const { return buffer_; }
    /// GPU address for shaders (GLSL buffer_reference).
    VkDeviceAddress address() const { return address_; }
    VkDeviceSize size() const { return size_; }
    /// Host pointer when the memory is host-visible (coherent), else null.
    void* mapped() const { return mapped_; }
    explicit operator bool() const { return buffer_ != VK_NULL_HANDLE; }

  private:
    Context* ctx_ = nullptr;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkDeviceAddress address_ = 0;
    VkDeviceSize size_ = 0;
    void* mapped_ = nullptr;
    bool slot_ = false; ///< holds one of the context's release slots (Context::reserve_release_slot)
    void release();
};

/// Copies `bytes` from host memory into `dst` at `offset`: a memcpy when mapped, else through a
/// staging buffer (blocks until the copy is done).
Status upload(Context& ctx, Buffer& dst, const void* data, std::size_t bytes, std::size_t offset = 0);
/// Copies `bytes` from `src` at `offset` into host memory (blocks).
Status download(Context& ctx, const Buffer& src, void* data, std::size_t bytes, std::size_t offset = 0);

/// Most bytes one vkCmdUpdateBuffer takes.
constexpr std::size_t kMaxUpdateBytes = 65536;
/// Records `bytes` (a multiple of 4) of host data into `dst` at `offset` (a multiple of 4): the data is
/// copied into the command buffer now, so `data` may change once the call returns. Needs a barrier before
/// passes read `dst`.
void update(const Context& ctx, VkCommandBuffer cmd, const Buffer& dst, const void* data, std::size_t bytes,
            std::size_t offset = 0);

/// Records what a frame's readback holds for one module: the first `bytes` of `src` (its counters)
/// copied into `dst` at `offset`, then `after` (host words known when recording, a multiple of 4 bytes
/// of them) right behind them. Needs a barrier after the passes that wrote `src`.
void record_readback(const Context& ctx, VkCommandBuffer cmd, const Buffer& src, std::size_t bytes,
                     VkBuffer dst, VkDeviceSize offset, std::span<const std::uint32_t> after = {});

/// Full memory barrier between two recorded passes (compute/graphics/transfer/indirect).
void barrier(const Context& ctx, VkCommandBuffer cmd);

/// Barrier between two compute dispatches: shader writes made visible to shader reads and writes and
/// to indirect dispatch arguments. Cheaper than barrier() where a pass is many small dispatches.
void compute_barrier(const Context& ctx, VkCommandBuffer cmd);

} // namespace gust::gpu
