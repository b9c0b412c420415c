#include <algorithm>
#include <cmath>
#include <cstring>
#include <gust/voxelizer/voxel_world.hpp>

namespace gust {

namespace {

bool same_instance(const GpuInstance& a, const GpuInstance& b) {
    return a.mesh == b.mesh && a.model == b.model;
}

void append_ms(gpu::Timings& out, const char* prefix, const gpu::Timings& passes) {
    for (const auto& [name, ms] : passes)
        out.emplace_back(prefix, ms).first.append(name);
}

} // namespace

Result<std::unique_ptr<VoxelWorld>> VoxelWorld::create(gpu::Context& ctx, const WorldDesc& desc) {
    if (Status s = validate_grid(desc.grid); !s) return s;
    std::unique_ptr<VoxelWorld> world(new (ctx.memory()) VoxelWorld(ctx, desc));
    world->desc_.tree.res = desc.grid.res;
    auto static_voxelizer = Voxelizer::create(ctx);
    if (!static_voxelizer) return static_voxelizer.status();
    world->static_ = std::move(*static_voxelizer);
    auto dynamic_voxelizer = Voxelizer::create(ctx);
    if (!dynamic_voxelizer) return dynamic_voxelizer.status();
    world->dynamic_ = std::move(*dynamic_voxelizer);
    auto tree = SparseTree::create(ctx, world->desc_.tree);
    if (!tree) return tree.status();
    world->tree_ = std::move(*tree);
    return world;
}

void VoxelWorld::set_static(std::span<const GpuInstance> instances) {
    const bool same = instances.size() == static_set_.size() &&
                      std::equal(instances.begin(), instances.end(), static_set_.begin(), same_instance);
    if (!same) static_dirty_ = true;
    static_set_.assign(instances.begin(), instances.end());
}

Status VoxelWorld::move_grid(glm::vec3 origin) {
    if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z))
        return Status::failure("grid origin must be finite");
    if (origin == desc_.grid.origin) return Status{};
    desc_.grid.origin = origin;
    static_dirty_ = true;
    return Status{};
}

Result<WorldFrame> VoxelWorld::step(std::span<const GpuInstance> dynamic, float dt) {
    if (!(dt > 0.0f))
        return Result<WorldFrame>::failure("frame time must be > 0 s, got " + std::to_string(dt));
    WorldFrame out(ctx_->memory());
    out.frame = frame_;
    const bool rebuild = static_dirty_;
    if (rebuild) {
        auto stats = static_->voxelize(static_set_, desc_.grid, desc_.method);
        if (!stats) return stats.status();
        last_static_ = *stats;
        append_ms(out.ms, "voxelize_static_", stats->ms);
    }
    auto dyn = dynamic_->voxelize(dynamic, desc_.grid, desc_.method, dt);
    if (!dyn) return dyn.status();
    append_ms(out.ms, "voxelize_", dyn->ms);

    const FragmentSource static_source{static_->fragment_buffer().address(),
                                       static_->fragment_count_address(), static_->fragment_capacity()};
    const FragmentSource dynamic_source{dynamic_->fragment_buffer().address(),
                                        dynamic_->fragment_count_address(), dynamic_->fragment_capacity()};
    auto tree = tree_->update(rebuild ? &static_source : nullptr, &dynamic_source);
    if (!tree) return tree.status();
    // Refinement stopped where a pool ran out: grow both pools and rebuild this frame's tree from the
    // kept fragment lists, so no frame is left partial.
    if (rebuild) ++static_generation_;
    while (tree->exhausted > 0) {
        ++static_generation_;
        const std::uint32_t nodes = tree_->node_capacity(), masks = tree_->mask_capacity();
        if (Status s = tree_->reserve(nodes * 2, masks * 2); !s) return s;
        ++out.pool_growths;
        tree = tree_->update(&static_source, &dynamic_source);
        if (!tree) return tree.status();
    }
    static_dirty_ = false;
    append_ms(out.ms, "", tree->ms);
    out.static_rebuilt = rebuild;
    out.static_voxelize = last_static_;
    out.dynamic_voxelize = *dyn;
    out.tree = *tree;
    ++frame_;
    return out;
}

namespace {
/// Written by record_readback() ahead of the voxelizers' and the tree's counters.
struct ReadbackHeader {
    std::uint64_t frame;
    std::uint64_t recorded_in; ///< gpu::Context::recording_frame(), which the profilers' slots follow
    std::uint32_t static_rebuilt;
    std::uint32_t unused;
};
} // namespace

Status VoxelWorld::record(VkCommandBuffer cmd, std::span<const GpuInstance> dynamic, float dt) {
    if (!(dt > 0.0f)) return Status::failure("frame time must be > 0 s, got " + std::to_string(dt));
    const bool rebuild = static_dirty_;
    if (rebuild)
        if (Status s = static_->record(cmd, static_set_, desc_.grid, desc_.method, 0.0f); !s) return s;
    if (Status s = dynamic_->record(cmd, dynamic, desc_.grid, desc_.method, dt); !s) return s;
    const FragmentSource static_source{static_->fragment_buffer().address(),
                                       static_->fragment_count_address(), static_->fragment_capacity()};
    const FragmentSource dynamic_source{dynamic_->fragment_buffer().address(),
                                        dynamic_->fragment_count_address(), dynamic_->fragment_capacity()};
    if (Status s = tree_->record_update(cmd, rebuild ? &static_source : nullptr, &dynamic_source); !s)
        return s;
    static_dirty_ = false;
    if (rebuild) ++static_generation_;
    recorded_rebuild_ = rebuild;
    recorded_frame_ = frame_++;
    return {};
}

std::size_t VoxelWorld::readback_bytes() {
    return sizeof(ReadbackHeader) + 2 * Voxelizer::readback_bytes() + SparseTree::readback_bytes();
}

void VoxelWorld::record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const {
    const ReadbackHeader header{recorded_frame_, ctx_->recording_frame(), recorded_rebuild_ ? 1u : 0u, 0};
    ctx_->vk().vkCmdUpdateBuffer(cmd, dst, offset, sizeof(header), &header);
    offset += sizeof(header);
    static_->record_readback(cmd, dst, offset);
    dynamic_->record_readback(cmd, dst, offset + Voxelizer::readback_bytes());
    tree_->record_readback(cmd, dst, offset + 2 * Voxelizer::readback_bytes());
}

Result<WorldFrame> VoxelWorld::collect(const void* readback) {
    const auto* bytes = static_cast<const unsigned char*>(readback);
    ReadbackHeader header;
    std::memcpy(&header, bytes, sizeof(header));
    bytes += sizeof(header);
    WorldFrame out(ctx_->memory());
    out.frame = header.frame;
    out.static_rebuilt = header.static_rebuilt != 0;
    // The static counters stay as the last rebuild left them, so they are read every frame.
    auto fixed = static_->collect(bytes);
    if (!fixed) return fixed.status();
    auto moving = dynamic_->collect(bytes + Voxelizer::readback_bytes());
    if (!moving) return moving.status();
    out.tree = tree_->stats_from(bytes + 2 * Voxelizer::readback_bytes());
    if (out.static_rebuilt) append_ms(out.ms, "voxelize_static_", static_->timings(header.recorded_in));
    append_ms(out.ms, "voxelize_", dynamic_->timings(header.recorded_in));
    append_ms(out.ms, "", tree_->timings(header.recorded_in));
    out.static_voxelize = *fixed;
    out.dynamic_voxelize = *moving;
    // The static counters are new only in a frame that voxelized the static set.
    if (fixed->truncated && out.static_rebuilt) static_dirty_ = true;
    // Frames recorded before the pools grew ran out too: they do not grow them again.
    if (out.tree.exhausted > 0 && out.frame >= pools_grown_for_) {
        pools_grown_for_ = frame_;
        if (Status s = tree_->reserve(tree_->node_capacity() * 2, tree_->mask_capacity() * 2); !s) return s;
        ++out.pool_growths;
        static_dirty_ = true;
    }
    out.truncated = fixed->truncated || moving->truncated || out.tree.exhausted > 0;
    return out;
}

} // namespace gust
