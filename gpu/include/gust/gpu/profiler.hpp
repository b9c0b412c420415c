// GPU timestamps around named passes, read back after the submission completes.
#pragma once

#include <cstdint>
#include <gust/gpu/context.hpp>
#include <string>
#include <utility>
#include <vector>

namespace gust::gpu {

/// Records begin/end timestamps per named pass. One recording at a time; reuse with reset().
class Profiler {
  public:
    /// Up to `max_passes` passes per recording. A device without timestamps, or a Context with frames in
    /// flight (Context::deferred), yields empty results.
    static Result<Profiler> create(Context& ctx, std::uint32_t max_passes = 32);
    Profiler() = default;
    ~Profiler();
    Profiler(Profiler&& other) noexcept;
    Profiler& operator=(Profiler&& other) noexcept;
    Profiler(const Profiler&) = delete;
    Profiler& operator=(const Profiler&) = delete;

    /// Resets the queries; record before the first begin().
    void reset(VkCommandBuffer cmd);
    /// Starts the pass `name` (passes do not nest).
    void begin(VkCommandBuffer cmd, std::string name);
    /// Ends the current pass.
    void end(VkCommandBuffer cmd);
    /// Milliseconds per pass, in recording order, once the commands have completed.
    std::vector<std::pair<std::string, double>> read() const;

  private:
    Context* ctx_ = nullptr;
    VkQueryPool pool_ = VK_NULL_HANDLE;
    std::uint32_t capacity_ = 0;
    std::vector<std::string> names_;
    void release();
};

} // namespace gust::gpu
