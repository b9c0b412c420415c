// GPU timestamps around named passes, read back after the submission completes.
#pragma once

#include <array>
#include <cstdint>
#include <gust/gpu/context.hpp>
#include <gust/gpu/host_memory.hpp>

namespace gust::gpu {

/// Records begin/end timestamps per named pass. One recording at a time; reuse with reset(). With
/// frames in flight (Context::begin_frame) each recorded frame writes its own set of queries, one of
/// kFrameSlots kept round by frame number, so a frame's timings can be read once it has completed.
class Profiler {
  public:
    /// Frames whose timings are kept: up to 8 in flight and the one being recorded.
    static constexpr std::uint32_t kFrameSlots = 9;

    /// Up to `max_passes` passes per recording. A device without timestamps yields empty results.
    static Result<Profiler> create(Context& ctx, std::uint32_t max_passes = 32);
    Profiler() {
        frames_.fill(kNoFrame);
        counts_.fill(0);
    }
    ~Profiler();
    Profiler(Profiler&& other) noexcept;
    Profiler& operator=(Profiler&& other) noexcept;
    Profiler(const Profiler&) = delete;
    Profiler& operator=(const Profiler&) = delete;

    /// Resets the queries of this recording (the frame being recorded, when frames are in flight);
    /// record before the first begin().
    void reset(VkCommandBuffer cmd);
    /// Starts the pass `name`, a string that outlives the Profiler (a literal); passes do not nest.
    void begin(VkCommandBuffer cmd, const char* name);
    /// Ends the current pass.
    void end(VkCommandBuffer cmd);
    /// Milliseconds per pass of the last recording, in recording order, once its commands completed
    /// (in the Context's host memory).
    Timings read() const;
    /// The same for the recording made while Context::begin_frame(`frame`) was current; empty when
    /// nothing was recorded in that frame, or its slot was recorded again since.
    Timings read_frame(std::uint64_t frame) const;

  private:
    Context* ctx_ = nullptr;
    VkQueryPool pool_ = VK_NULL_HANDLE;
    std::uint32_t capacity_ = 0;
    std::uint32_t slot_ = 0;
    /// Pass names, capacity_ per slot, in the Context's host memory.
    const char** names_ = nullptr;
    std::array<std::uint32_t, kFrameSlots> counts_; ///< passes begun per slot
    static constexpr std::uint64_t kNoFrame = ~std::uint64_t(0);
    std::array<std::uint64_t, kFrameSlots> frames_; ///< the frame each slot was recorded in, or kNoFrame
    Timings read_slot(std::uint32_t slot) const;
    void release();
};

} // namespace gust::gpu
