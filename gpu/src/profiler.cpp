#include <gust/gpu/profiler.hpp>
#include <utility>

namespace gust::gpu {

Result<Profiler> Profiler::create(Context& ctx, std::uint32_t max_passes) {
    Profiler p;
    p.ctx_ = &ctx;
    if (ctx.info().timestamp_period_ns <= 0.0f) return p;
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = kFrameSlots * 2 * max_passes;
    if (VkResult r = ctx.vk().vkCreateQueryPool(ctx.device(), &info, nullptr, &p.pool_); r != VK_SUCCESS)
        return Result<Profiler>::failure(std::string("vkCreateQueryPool failed: ") + to_string(r));
    p.capacity_ = max_passes;
    return p;
}

void Profiler::reset(VkCommandBuffer cmd) {
    slot_ = ctx_->deferred() ? std::uint32_t(ctx_->recording_frame() % kFrameSlots) : 0;
    names_[slot_].clear();
    // A blocking recording belongs to no frame, so read_frame() never returns it.
    frames_[slot_] = ctx_->deferred() ? ctx_->recording_frame() : kNoFrame;
    if (pool_) ctx_->vk().vkCmdResetQueryPool(cmd, pool_, slot_ * 2 * capacity_, 2 * capacity_);
}

void Profiler::begin(VkCommandBuffer cmd, std::string name) {
    std::vector<std::string>& names = names_[slot_];
    if (!pool_ || names.size() >= capacity_) return;
    ctx_->vk().vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_,
                                    std::uint32_t(slot_ * 2 * capacity_ + 2 * names.size()));
    names.push_back(std::move(name));
}

void Profiler::end(VkCommandBuffer cmd) {
    const std::vector<std::string>& names = names_[slot_];
    if (!pool_ || names.empty()) return;
    ctx_->vk().vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool_,
                                    std::uint32_t(slot_ * 2 * capacity_ + 2 * names.size() - 1));
}

std::vector<std::pair<std::string, double>> Profiler::read() const {
    return read_slot(slot_);
}

std::vector<std::pair<std::string, double>> Profiler::read_frame(std::uint64_t frame) const {
    const auto slot = std::uint32_t(frame % kFrameSlots);
    if (frames_[slot] != frame) return {};
    return read_slot(slot);
}

std::vector<std::pair<std::string, double>> Profiler::read_slot(std::uint32_t slot) const {
    std::vector<std::pair<std::string, double>> out;
    const std::vector<std::string>& names = names_[slot];
    if (!pool_ || names.empty()) return out;
    std::vector<std::uint64_t> ticks(2 * names.size());
    VkResult r = ctx_->vk().vkGetQueryPoolResults(
        ctx_->device(), pool_, slot * 2 * capacity_, std::uint32_t(ticks.size()),
        ticks.size() * sizeof(std::uint64_t), ticks.data(), sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT);
    if (r != VK_SUCCESS) return out;
    const double ms_per_tick = double(ctx_->info().timestamp_period_ns) * 1e-6;
    for (std::size_t i = 0; i < names.size(); ++i)
        out.emplace_back(names[i], double(ticks[2 * i + 1] - ticks[2 * i]) * ms_per_tick);
    return out;
}

void Profiler::release() {
    if (ctx_ && pool_) ctx_->vk().vkDestroyQueryPool(ctx_->device(), pool_, nullptr);
    pool_ = VK_NULL_HANDLE;
}

Profiler::~Profiler() {
    release();
}

Profiler::Profiler(Profiler&& other) noexcept {
    *this = std::move(other);
}

Profiler& Profiler::operator=(Profiler&& other) noexcept {
    if (this != &other) {
        release();
        ctx_ = std::exchange(other.ctx_, nullptr);
        pool_ = std::exchange(other.pool_, VK_NULL_HANDLE);
        capacity_ = other.capacity_;
        slot_ = other.slot_;
        names_ = std::move(other.names_);
        frames_ = other.frames_;
    }
    return *this;
}

} // namespace gust::gpu
