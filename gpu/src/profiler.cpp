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
    if (VkResult r = ctx.vk().vkCreateQueryPool(ctx.device(), &info, ctx.allocator(), &p.pool_);
        r != VK_SUCCESS)
        return Result<Profiler>::failure(std::string("vkCreateQueryPool failed: ") + to_string(r));
    ctx.name(VK_OBJECT_TYPE_QUERY_POOL, std::uint64_t(p.pool_), "gust timestamps");
    p.capacity_ = max_passes;
    p.names_ = static_cast<const char**>(
        ctx.memory()->allocate(kFrameSlots * max_passes * sizeof(const char*), alignof(const char*)));
    return p;
}

void Profiler::reset(VkCommandBuffer cmd) {
    slot_ = ctx_->deferred() ? std::uint32_t(ctx_->recording_frame() % kFrameSlots) : 0;
    counts_[slot_] = 0;
    // A blocking recording belongs to no frame, so read_frame() never returns it.
    frames_[slot_] = ctx_->deferred() ? ctx_->recording_frame() : kNoFrame;
    if (pool_) ctx_->vk().vkCmdResetQueryPool(cmd, pool_, slot_ * 2 * capacity_, 2 * capacity_);
}

void Profiler::begin(VkCommandBuffer cmd, const char* name) {
    ctx_->begin_label(cmd, name);
    std::uint32_t& count = counts_[slot_];
    if (!pool_ || count >= capacity_) return;
    ctx_->vk().vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_,
                                   slot_ * 2 * capacity_ + 2 * count);
    names_[slot_ * capacity_ + count++] = name;
}

void Profiler::end(VkCommandBuffer cmd) {
    ctx_->end_label(cmd);
    const std::uint32_t count = counts_[slot_];
    if (!pool_ || count == 0) return;
    ctx_->vk().vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_,
                                   slot_ * 2 * capacity_ + 2 * count - 1);
}

Timings Profiler::read() const {
    return read_slot(slot_);
}

Timings Profiler::read_frame(std::uint64_t frame) const {
    const auto slot = std::uint32_t(frame % kFrameSlots);
    if (frames_[slot] != frame) return Timings(ctx_ ? ctx_->memory() : std::pmr::get_default_resource());
    return read_slot(slot);
}

Timings Profiler::read_slot(std::uint32_t slot) const {
    Timings out(ctx_ ? ctx_->memory() : std::pmr::get_default_resource());
    const std::uint32_t count = counts_[slot];
    if (!pool_ || count == 0) return out;
    std::pmr::vector<std::uint64_t> ticks(2 * count, ctx_->memory());
    VkResult r = ctx_->vk().vkGetQueryPoolResults(
        ctx_->device(), pool_, slot * 2 * capacity_, std::uint32_t(ticks.size()),
        ticks.size() * sizeof(std::uint64_t), ticks.data(), sizeof(std::uint64_t), VK_QUERY_RESULT_64_BIT);
    if (r != VK_SUCCESS) return out;
    const double ms_per_tick = double(ctx_->info().timestamp_period_ns) * 1e-6;
    out.reserve(count);
    for (std::uint32_t i = 0; i < count; ++i)
        out.emplace_back(names_[slot * capacity_ + i], double(ticks[2 * i + 1] - ticks[2 * i]) * ms_per_tick);
    return out;
}

void Profiler::release() {
    if (ctx_ && pool_) ctx_->vk().vkDestroyQueryPool(ctx_->device(), pool_, ctx_->allocator());
    if (ctx_ && names_)
        ctx_->memory()->deallocate(names_, kFrameSlots * capacity_ * sizeof(const char*),
                                   alignof(const char*));
    pool_ = VK_NULL_HANDLE;
    names_ = nullptr;
}

Profiler::~Profiler() {
    release();
}

Profiler::Profiler(Profiler&& other) noexcept : Profiler() {
    *this = std::move(other);
}

Profiler& Profiler::operator=(Profiler&& other) noexcept {
    if (this != &other) {
        release();
        ctx_ = std::exchange(other.ctx_, nullptr);
        pool_ = std::exchange(other.pool_, VK_NULL_HANDLE);
        names_ = std::exchange(other.names_, nullptr);
        capacity_ = other.capacity_;
        slot_ = other.slot_;
        counts_ = other.counts_;
        frames_ = other.frames_;
    }
    return *this;
}

} // namespace gust::gpu
