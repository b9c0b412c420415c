// One frame, in the order of docs/design.md: inputs, scroll, voxelize, tree, solid, wind, outputs, readback.
#include "frame.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <glm/gtc/type_ptr.hpp>

namespace gust::detail {

namespace {
Outcome device_failure(const Status& s) {
    return Outcome(ErrorCode::DeviceFailure, s.message());
}
/// The most cells the domain moves in one step (System::set_focus refuses larger moves of the focus).
constexpr float kMaxScrollCells = 1e6f;
} // namespace

Frame::~Frame() {
    if (sampler_) ctx_->vk().vkDestroySampler(ctx_->device(), sampler_, ctx_->allocator());
}

Outcome Frame::create_textures() {
    VkSamplerCreateInfo sampler{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    sampler.magFilter = sampler.minFilter = VK_FILTER_LINEAR;
    sampler.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    sampler.addressModeU = sampler.addressModeV = sampler.addressModeW =
        VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    if (ctx_->vk().vkCreateSampler(ctx_->device(), &sampler, ctx_->allocator(), &sampler_) != VK_SUCCESS)
        return Outcome(ErrorCode::DeviceFailure, "vkCreateSampler failed");
    ctx_->name(VK_OBJECT_TYPE_SAMPLER, std::uint64_t(sampler_), "gust wind sampler");
    const glm::uvec3 cells = solver_->desc().cells;
    for (std::size_t k = 0; k <= coarser_.size(); ++k) {
        // Names for capture tools, in a fixed buffer: host memory comes from the hooks only.
        char name[48], texels_name[64];
        if (k == 0)
            std::snprintf(name, sizeof(name), "gust wind texture");
        else
            std::snprintf(name, sizeof(name), "gust wind texture, cascade %zu", k);
        std::snprintf(texels_name, sizeof(texels_name), "%s texels", name);
        auto texels =
            gpu::Buffer::create(*ctx_, solver(k).cell_count() * 8, gpu::MemoryUse::Device, 0, texels_name);
        if (!texels) return device_failure(texels.status());
        gpu::ImageDesc image;
        image.extent = {cells.x, cells.y, cells.z};
        image.format = VK_FORMAT_R16G16B16A16_SFLOAT;
        // Sampled by the engine, written by gust's copy, and copied out by an engine that exports or captures
        // it.
        image.usage =
            VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
        image.volume = true;
        image.name = name;
        auto created = gpu::Image::create(*ctx_, image);
        if (!created) return device_failure(created.status());
        CascadeTexture& texture = textures_.emplace_back();
        texture.texels = std::move(*texels);
        texture.image = std::move(*created);
        WindTexture& t = published_.emplace_back();
        t.image = textures_[k].image.handle();
        t.view = textures_[k].image.view();
        t.sampler = sampler_;
        t.format = textures_[k].image.format();
        for (int a = 0; a < 3; ++a)
            t.extent[a] = cells[a];
        // The first fill (blocking, at creation); from then on each step's last pass writes them.
        Status s = solver(k).write_texels(textures_[k].texels,
                                          [&](VkCommandBuffer cmd) { record_texture_copy(cmd, k); });
        if (!s) return device_failure(s);
        solver(k).bind_texels(textures_[k].texels);
        publish_texture(k, true);
    }
    return {};
}

std::size_t Frame::snapshot_cells() const {
    std::size_t cells = 0;
    for (std::size_t k = 0; k <= coarser_.size(); ++k)
        cells += solver(k).cell_count();
    return cells;
}

Outcome Frame::scroll_for(const WindSolver& solver, glm::vec3 focus, glm::ivec3& cells) {
    // Follow the focus in whole cells: the wind scrolls, the voxel grid moves with it.
    const SolverDesc& d = solver.desc();
    const glm::vec3 wanted = focus - 0.5f * glm::vec3(d.cells) * d.cell_size;
    const glm::vec3 shift = glm::round((wanted - solver.origin()) / d.cell_size);
    if (glm::any(glm::greaterThan(glm::abs(shift), glm::vec3(kMaxScrollCells + 1.0f))))
        return Outcome(ErrorCode::InvalidArgument, "the focus moved more than a million cells in one step");
    cells = glm::ivec3(shift);
    return {};
}

Cascade* Frame::next_cascade() {
    // Cascade k steps every ratio^k frames with that many frames' time, so every cascade runs at the same
    // CFL number; when two are due in one frame, the most overdue goes first and the other waits a frame
    // (docs/solver.md, "Cascades").
    Cascade* due = nullptr;
    for (Cascade& c : coarser_) {
        ++c.waited;
        if (c.waited >= c.period && (!due || c.waited * due->period > due->waited * c.period)) due = &c;
    }
    return due;
}

Outcome Frame::record_cascade(VkCommandBuffer cmd, const FrameInputs& in, Cascade& c, FrameSlot& slot) {
    glm::ivec3 shift;
    if (Outcome o = scroll_for(*c.solver, in.focus, shift); !o) return o;
    // The field it leaves behind, which the finer cascades blend from until its next step.
    c.solver->record_keep_previous(cmd);
    if (shift != glm::ivec3(0)) {
        c.solver->record_scroll(cmd, shift);
        if (Status s = c.world->move_grid(c.solver->origin()); !s) return device_failure(s);
    }
    if (c.static_stale) c.world->set_static(static_set_);
    // A moving instance goes only into the cascades where it spans a voxel: a character is not voxelized
    // into cells of 32 m.
    moving_.clear();
    for (const GpuInstance& instance : in.dynamic) {
        const MeshSizes& sizes = instance.mesh->sizes();
        const glm::vec3 extent = glm::max(sizes.hi - sizes.lo, glm::vec3(0.0f));
        float span = 0.0f;
        for (int a = 0; a < 3; ++a)
            span = std::max(span, glm::length(glm::vec3(instance.model[a])) * extent[a]);
        if (span >= c.voxel_size) moving_.push_back(instance);
    }
    // The instances' motion is over this frame's dt. The cascade's step runs ahead to the end of the last
    // frame before its next turn (at this frame's dt), so the finer cascades read its wind in between: a
    // period of frames at a steady dt, and it makes up for a dt that changed.
    if (Status s = c.world->record(cmd, moving_, in.dt); !s) return device_failure(s);
    const SolidSource solid = solid_source(*c.world);
    const double target = time_ + double(in.dt) * double(c.period);
    const float dt = float(std::clamp(target - c.ahead, double(in.dt), double(kMaxStep)));
    if (Status s = c.solver->record_step(cmd, dt, &solid); !s) return device_failure(s);
    c.before = c.ahead;
    c.ahead += double(dt);
    c.world->record_readback(cmd, slot.readback.handle(), ReadbackLayout::cascade_world());
    c.solver->record_readback(cmd, slot.readback.handle(), ReadbackLayout::cascade_wind());
    c.static_stale = false;
    c.waited = 0;
    slot.cascade = int(&c - coarser_.data());
    record_texture_copy(cmd, std::size_t(slot.cascade) + 1);
    return {};
}

Outcome Frame::record(VkCommandBuffer cmd, const FrameInputs& in, FrameSlot& slot) {
    // Per-frame storage first, so that nothing is recorded when it cannot be had.
    const std::size_t readback = ReadbackLayout::bytes(in.points.size());
    if (!slot.readback || slot.readback.size() < readback) {
        auto grown = gpu::Buffer::create(*ctx_, readback, gpu::MemoryUse::Readback, 0, "gust frame readback");
        if (!grown) return device_failure(grown.status());
        slot.readback = std::move(*grown);
    }
    const std::size_t point_bytes = in.points.size() * sizeof(glm::vec3);
    if (point_bytes > 0 && slot.points.size() < point_bytes) {
        auto grown = gpu::Buffer::create(*ctx_, point_bytes, gpu::MemoryUse::Upload, 0, "gust query points");
        if (!grown) return device_failure(grown.status());
        slot.points = std::move(*grown);
    }
    if (snapshot_ && !slot.snapshot) {
        auto created =
            gpu::Buffer::create(*ctx_, snapshot_cells() * 8, gpu::MemoryUse::Readback, 0, "gust snapshot");
        if (!created) return device_failure(created.status());
        slot.snapshot = std::move(*created);
    }
    const gpu::WorkCounts before = ctx_->work();
    if (dispatch_profiler_) {
        dispatch_profiler_->reset(cmd);
        ctx_->time_dispatches(&*dispatch_profiler_);
    }
    // Whatever way the recording ends, the Context stops timing with it.
    const struct StopTiming {
        gpu::Context* ctx;
        ~StopTiming() { ctx->time_dispatches(nullptr); }
    } stop_timing{ctx_};

    // Inputs: whatever the host submitted before (its draws sampling the wind texture, gust's last frame)
    // comes before this frame's work; then the meshes posed from bones are skinned into their positions.
    gpu::barrier(*ctx_, cmd);
    world_->record_skinning(cmd, in.dynamic);
    if (rebind_) {
        solver_->record_bindings(cmd);
        for (Cascade& c : coarser_)
            c.solver->record_bindings(cmd);
        rebind_ = false;
    }
    // The coarser cascade whose turn it is, before the finest, which then reads its newest wind.
    slot.cascade = -1;
    if (in.fixed && !coarser_.empty()) {
        static_set_.assign(in.fixed->begin(), in.fixed->end());
        for (Cascade& c : coarser_)
            c.static_stale = true;
    }
    // A new ambient wind reaches every cascade in this frame, stepping or not (docs/solver.md, "Ambient
    // wind").
    for (Cascade& c : coarser_)
        c.solver->record_ambient_change(cmd);
    if (Cascade* c = next_cascade())
        if (Outcome o = record_cascade(cmd, in, *c, slot); !o) return o;
    // Where this frame's end lies between each coarser cascade's last two steps, for the cascades inside it.
    const double now = time_ + double(in.dt);
    for (Cascade& c : coarser_)
        c.solver->record_time_blend(cmd, c.ahead > c.before ? float((now - c.before) / (c.ahead - c.before))
                                                            : 1.0f);
    // Scroll: the wind moves in whole cells and the voxel grid follows the solver's origin.
    if (in.shift != glm::ivec3(0)) {
        solver_->record_scroll(cmd, in.shift);
        if (Status s = world_->move_grid(solver_->origin()); !s) return device_failure(s);
    }
    // Voxelize and tree: the static set when it changed (or the grid moved), the dynamic set every frame.
    if (in.fixed) world_->set_static(*in.fixed);
    if (Status s = world_->record(cmd, in.dynamic, in.dt); !s) return device_failure(s);
    // Solid and wind: the boundary from the tree, then the step; its last pass writes the texels.
    const SolidSource solid = solid_source(*world_);
    if (Status s = solver_->record_step(cmd, in.dt, &solid); !s) return device_failure(s);
    // Outputs: the texture, and the async queries asked since the last frame.
    record_texture_copy(cmd, 0);
    if (snapshot_)
        for (std::size_t k = 0, at = 0; k < textures_.size(); at += textures_[k].texels.size(), ++k)
            gpu::record_readback(*ctx_, cmd, textures_[k].texels, textures_[k].texels.size(),
                                 slot.snapshot.handle(), at);
    if (point_bytes > 0) {
        std::memcpy(slot.points.mapped(), in.points.data(), point_bytes);
        solver_->record_sample(cmd, slot.points.address(),
                               slot.readback.address() + ReadbackLayout::answers(),
                               std::uint32_t(in.points.size()), PointSample::Wind);
    }
    // Readback: the counters reach the host once the frame completes; the host's later commands (its
    // shaders sampling the wind texture) see every write of this frame.
    world_->record_readback(cmd, slot.readback.handle(), ReadbackLayout::world);
    solver_->record_readback(cmd, slot.readback.handle(), ReadbackLayout::wind());
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_HOST_READ_BIT;
    ctx_->vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                                    VK_PIPELINE_STAGE_ALL_COMMANDS_BIT | VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                                    &barrier, 0, nullptr, 0, nullptr);
    ctx_->count_barrier();

    slot.used = true;
    slot.frame = ctx_->recording_frame();
    slot.dispatches = ctx_->work().dispatches - before.dispatches;
    slot.stages = ctx_->work().stages - before.stages;
    ++recorded_;
    time_ += double(in.dt);
    slot.snapshot_recorded = snapshot_ != nullptr;
    for (std::size_t k = 0; k < textures_.size(); ++k)
        slot.snapshot_origins[k] = solver(k).origin();
    slot.snapshot_ambient = solver_->ambient();
    slot.snapshot_frame = recorded_;
    // The finest cascade's texels are new every frame, a coarser one's when it stepped.
    for (std::size_t k = 0; k < textures_.size(); ++k)
        publish_texture(k, k == 0 || int(k) == slot.cascade + 1);
    return {};
}

Outcome Frame::collect(const FrameSlot& slot, const gpu::WorkCounts& work, FrameStats& stats,
                       const glm::vec3*& answers) {
    const auto* bytes = static_cast<const unsigned char*>(slot.readback.mapped());
    auto world = world_->collect(bytes + ReadbackLayout::world);
    if (!world) return device_failure(world.status());
    WindStats wind = solver_->stats_from(bytes + ReadbackLayout::wind());
    wind.ms = solver_->timings(slot.frame);
    answers = reinterpret_cast<const glm::vec3*>(bytes + ReadbackLayout::answers());
    stats_from(*world, wind, work, stats);
    if (slot.cascade >= 0) {
        // A coarser cascade's pools grow as the finest one's do; its stats stay its own, but a diverged
        // solve there is said, and its passes' times join the frame's under "cascade_".
        const Cascade& c = coarser_[std::size_t(slot.cascade)];
        auto coarse = c.world->collect(bytes + ReadbackLayout::cascade_world());
        if (!coarse) return device_failure(coarse.status());
        if (c.solver->stats_from(bytes + ReadbackLayout::cascade_wind()).diverged)
            log(LogLevel::Warning, "cascade " + std::to_string(slot.cascade + 1) +
                                       ": the pressure solve diverged and was stopped, so its wind was not "
                                       "projected (docs/solver.md, \"Stability\")");
        for (const auto& [pass, ms] : coarse->ms)
            stats.ms.emplace_back("cascade_", ms).first.append(pass);
        for (const auto& [pass, ms] : c.solver->timings(slot.frame))
            stats.ms.emplace_back("cascade_wind_", ms).first.append(pass);
    }
    if (dispatch_profiler_) {
        const gpu::Timings timed = dispatch_profiler_->read_frame(slot.frame);
        stats.ms.assign(timed.begin(), timed.end());
    }
    return {};
}

Outcome Frame::time_dispatches(bool on) {
    if (!on) {
        dispatch_profiler_.reset();
        return {};
    }
    if (dispatch_profiler_) return {};
    auto created = gpu::Profiler::create(*ctx_, kTimedDispatches);
    if (!created) return device_failure(created.status());
    dispatch_profiler_.emplace(std::move(*created));
    return {};
}

void Frame::publish_snapshot(const FrameSlot& slot) {
    if (!snapshot_ || !slot.snapshot_recorded) return;
    // A bounded copy (the texels to floats); when every free copy is held by a reader, this frame is
    // skipped and readers keep the previous one.
    SnapshotData* d = snapshot_->begin_write();
    if (!d) return;
    const auto* half = static_cast<const std::uint16_t*>(slot.snapshot.mapped());
    for (std::size_t i = 0; i < d->cells.size(); ++i, half += 4)
        d->cells[i] = {half_to_float(half[0]), half_to_float(half[1]), half_to_float(half[2]),
                       half_to_float(half[3])};
    d->levels.clear();
    for (std::size_t k = 0, first = 0; k < textures_.size(); first += solver(k).cell_count(), ++k) {
        const SolverDesc& desc = solver(k).desc();
        d->levels.push_back({.origin = slot.snapshot_origins[k],
                             .cell_size = desc.cell_size,
                             .extent = glm::ivec3(desc.cells),
                             .first = first});
    }
    d->ambient = slot.snapshot_ambient;
    d->frame = slot.snapshot_frame;
    snapshot_->publish(d);
}

void Frame::stats_from(const WorldFrame& world, const WindStats& wind, const gpu::WorkCounts& work,
                       FrameStats& st) const {
    st.dispatches = work.dispatches;
    st.stages = work.stages;
    st.submissions = std::uint32_t(work.submissions);
    st.waits = std::uint32_t(work.waits);
    const TreeStats& tree = world.tree;
    st.frame = world.frame;
    st.fragments = world.static_voxelize.fragments + world.dynamic_voxelize.fragments;
    st.voxels = tree.voxels;
    st.nodes = tree.nodes;
    st.refined = tree.refined;
    st.coarsened = tree.coarsened;
    st.pool_bytes = tree.pool_bytes;
    st.fragment_bytes = st.fragments * 4 + world.dynamic_voxelize.fragments * 8;
    const std::uint64_t res = world_->grid().res;
    st.dense_bytes = res * res * res * 4;
    st.divergence_before = float(wind.divergence_before);
    st.divergence_after = float(wind.divergence_after);
    st.residual = float(wind.residual);
    st.cycles = wind.cycles;
    st.converged = wind.converged;
    st.diverged = wind.diverged;
    st.sealed_cells = wind.sealed_cells;
    st.rejected_triangles = std::uint32_t(world.dynamic_voxelize.rejected +
                                          (world.static_rebuilt ? world.static_voxelize.rejected : 0));
    st.cut_cells = wind.cut_cells;
    st.fluid_cells = wind.fluid_cells;
    st.free_node_blocks = tree.free_node_blocks;
    st.free_mask_blocks = tree.free_mask_blocks;
    st.exhausted = tree.exhausted;
    st.pool_growths = world.pool_growths;
    st.static_rebuilt = world.static_rebuilt;
    st.nodes_per_level.assign(tree.nodes_per_level.begin(), tree.nodes_per_level.end());
    st.ms.assign(world.ms.begin(), world.ms.end());
    for (const auto& [pass, ms] : wind.ms)
        st.ms.emplace_back("wind_", ms).first.append(pass);
    if (world.pool_growths > 0)
        log(LogLevel::Info, "the voxel tree's pools grew " + std::to_string(world.pool_growths) + " times");
    if (world.truncated)
        log(LogLevel::Warning,
            "frame " + std::to_string(world.frame) +
                ": a fragment list or tree pool ran out, so its solids were partial; grown "
                "for the frames recorded from now on");
    if (wind.diverged)
        log(LogLevel::Warning,
            "frame " + std::to_string(world.frame) +
                ": the pressure solve diverged and was stopped, so the frame's wind was not "
                "projected (docs/solver.md, \"Stability\")");
}

void Frame::log(LogLevel level, const std::string& message) const {
    if (hooks_->log) hooks_->log(hooks_->user, level, message.c_str());
}

void Frame::record_texture_copy(VkCommandBuffer cmd, std::size_t k) {
    gpu::Image& image = textures_[k].image;
    // The copy writes every texel, so the old ones are discarded: a host that moved the image to its
    // graphics queue family to sample it need not give it back (docs/api.md "Async compute").
    image.discard();
    image.transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    image.copy_from(cmd, textures_[k].texels);
    image.transition(cmd, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
}

void Frame::publish_texture(std::size_t k, bool stepped) {
    // World position -> [0, 1]^3 over the cascade's grid as it stands after this frame's scroll (or
    // after a shift of the world's origin, which moves a grid without a step).
    const WindSolver& s = solver(k);
    const SolverDesc& d = s.desc();
    const glm::vec3 size = glm::vec3(d.cells) * d.cell_size, origin = s.origin();
    glm::mat4 m(1.0f);
    for (int a = 0; a < 3; ++a) {
        m[a][a] = 1.0f / size[a];
        m[3][a] = -origin[a] / size[a];
    }
    WindTexture& t = published_[k];
    std::memcpy(t.world_to_texture.m, glm::value_ptr(m), sizeof(t.world_to_texture.m));
    if (stepped) t.frame = recorded_;
}

} // namespace gust::detail
