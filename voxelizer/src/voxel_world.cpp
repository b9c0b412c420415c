#include "tree/tree_io.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <gust/voxelizer/voxel_world.hpp>
#include <gust/voxelizer/voxelize_cost.hpp>

namespace gust {

namespace {

bool same_instance(const GpuInstance& a, const GpuInstance& b) {
    return a.mesh == b.mesh && a.model == b.model;
}

void append_ms(gpu::Timings& out, const char* prefix, const gpu::Timings& passes) {
    for (const auto& [name, ms] : passes)
        out.emplace_back(prefix, ms).first.append(name);
}

/// Margin over the expected node/triangle pairs, as the voxelizer sizes its fragment list.
constexpr double kNodeHeadroom = 1.25;
constexpr double kNodeSlack = 8.0;

/// Blocks a tree of branching 2^log2_b and `levels` levels over `grid` takes for the surfaces of `sets`,
/// from their meshes' sizes. A level's reached nodes are at most the node/triangle pairs a voxelization
/// whose voxels are that level's nodes receives (voxelize_work on the coarser grid, an expected value, so
/// with a margin); at most all of the level's nodes, and at most the next finer level's (a reached
/// node has a reached child). Not a bound, but pairs count a node once per triangle, so it rarely falls
/// short.
TreePools estimate_pools(std::span<const std::span<const GpuInstance>> sets, const GridDesc& grid,
                         std::uint32_t log2_b, std::uint32_t levels) {
    double reached[shaderio::kMaxLevels] = {};
    for (std::uint32_t level = 0; level < levels; ++level) {
        GridDesc coarse = grid;
        coarse.res = 1u << (log2_b * level);
        coarse.voxel_size = grid.voxel_size * float(grid.res / coarse.res);
        VoxelizeWork work;
        for (std::span<const GpuInstance> set : sets)
            for (const GpuInstance& inst : set)
                work += voxelize_work(inst.mesh->sizes(), inst.model, coarse);
        const double all = std::pow(double(coarse.res), 3.0);
        reached[level] = std::min(all, std::ceil(kNodeHeadroom * work.fragments + kNodeSlack));
    }
    for (std::uint32_t level = levels - 1; level-- > 0;)
        reached[level] = std::min(reached[level], reached[level + 1]);
    double nodes = 1.0;
    for (std::uint32_t level = 0; level + 1 < levels; ++level)
        nodes += reached[level];
    const double limit = double(UINT32_MAX);
    return {std::uint32_t(std::min(nodes, limit)), std::uint32_t(std::min(reached[levels - 1] + 1.0, limit))};
}

} // namespace

Result<std::unique_ptr<VoxelWorld>> VoxelWorld::create(gpu::Context& ctx, const WorldDesc& desc) {
    if (Status s = validate_grid(desc.grid); !s) return s;
    std::unique_ptr<VoxelWorld> world(new (ctx.memory()) VoxelWorld(ctx, desc));
    world->desc_.tree.res = desc.grid.res;
    world->estimate_pools_ = desc.tree.node_blocks == 0 && desc.tree.mask_blocks == 0;
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
    if (!same) static_dirty_ = static_whole_ = true;
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

VoxelWorld::StaticPlan VoxelWorld::plan_static() const {
    StaticPlan plan;
    if (!static_dirty_) return plan;
    plan.voxelize = true;
    if (static_whole_) return plan;
    // Whole voxels from where the set was last voxelized whole, so that rounding does not add up over
    // many scrolls.
    const GridDesc& grid = desc_.grid;
    for (int a = 0; a < 3; ++a) {
        const double voxels = (double(grid.origin[a]) - double(static_anchor_[a])) / double(grid.voxel_size);
        const double whole = std::round(voxels);
        if (!(std::abs(voxels - whole) <= kWholeVoxelTolerance) || std::abs(whole) > double(1 << 30))
            return plan;
        plan.at[a] = int(whole);
    }
    plan.shift = plan.at - static_at_;
    if (plan.shift == glm::ivec3(0)) {
        // Back on the lattice point it was voxelized at: the kept list holds this grid's voxels.
        plan.voxelize = false;
        return plan;
    }
    for (int a = 0; a < 3; ++a) {
        const std::uint32_t keep = grid.keep[a] == 0 ? grid.res : std::min(grid.keep[a], grid.res);
        // Nothing kept on this axis: the whole pass is cheaper than the shift and the slabs.
        if (std::abs(std::int64_t(plan.shift[a])) >= std::int64_t(keep)) return plan;
    }
    plan.slabs = true;
    return plan;
}

void VoxelWorld::voxelized_static(const StaticPlan& plan, bool slabs) {
    static_whole_ = false;
    if (slabs) {
        static_at_ = plan.at;
        return;
    }
    static_anchor_ = desc_.grid.origin;
    static_at_ = glm::ivec3(0);
}

Result<bool> VoxelWorld::grow_pools(TreePools wanted, bool ran_out) {
    const TreePools now = tree_->pools(), full = tree_->full_pools();
    TreePools target{std::max(now.node_blocks, wanted.node_blocks),
                     std::max(now.mask_blocks, wanted.mask_blocks)};
    // Doubling (rather than growing by what ran out, which a frame does not report per pool) keeps the
    // number of rebuilt frames logarithmic in the size the scene needs.
    if (ran_out) {
        target.node_blocks = std::uint32_t(std::min<std::uint64_t>(2ull * now.node_blocks, UINT32_MAX));
        target.mask_blocks = std::uint32_t(std::min<std::uint64_t>(2ull * now.mask_blocks, UINT32_MAX));
    }
    target.node_blocks = std::max(now.node_blocks, std::min(target.node_blocks, full.node_blocks));
    target.mask_blocks = std::max(now.mask_blocks, std::min(target.mask_blocks, full.mask_blocks));
    if (target.node_blocks == now.node_blocks && target.mask_blocks == now.mask_blocks) {
        if (ran_out)
            return Result<bool>::failure("the tree's pools ran out at " + std::to_string(now.node_blocks) +
                                         " node and " + std::to_string(now.mask_blocks) +
                                         " mask blocks, as many as a full tree takes");
        return false;
    }
    if (Status s = tree_->reserve(target.node_blocks, target.mask_blocks); !s) return s;
    rebuild_tree_ = true;
    return true;
}

Result<bool> VoxelWorld::grow_for(std::span<const GpuInstance> dynamic) {
    if (!estimate_pools_) return false;
    const std::span<const GpuInstance> sets[] = {static_set_, dynamic};
    const std::uint32_t log2_b = std::uint32_t(std::countr_zero(tree_->branching()));
    return grow_pools(estimate_pools(sets, desc_.grid, log2_b, tree_->depth()), false);
}

Result<WorldFrame> VoxelWorld::step(std::span<const GpuInstance> dynamic, float dt) {
    if (!(dt > 0.0f))
        return Result<WorldFrame>::failure("frame time must be > 0 s, got " + std::to_string(dt));
    WorldFrame out(ctx_->memory());
    out.frame = frame_;
    auto grown = grow_for(dynamic);
    if (!grown) return grown.status();
    out.pool_growths += *grown ? 1u : 0u;
    const StaticPlan plan = plan_static();
    const bool voxelize_static = plan.voxelize;
    // Until this step completes: one that fails after its static list changed has the next voxelize whole.
    if (voxelize_static) static_whole_ = true;
    if (plan.slabs) {
        auto stats = static_->voxelize_slabs(static_set_, desc_.grid, desc_.method, plan.shift);
        if (!stats) return stats.status();
        // A list that overflowed holds a partial set: voxelized whole below, into the grown list.
        out.static_slabs = !stats->truncated;
        if (out.static_slabs) {
            last_static_ = *stats;
            append_ms(out.ms, "voxelize_static_", stats->ms);
        }
    }
    if (voxelize_static && !out.static_slabs) {
        auto stats = static_->voxelize(static_set_, desc_.grid, desc_.method);
        if (!stats) return stats.status();
        if (plan.slabs) ++stats->retries;
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
    // The static fragment list is kept from the last voxelization, so a rebuild after growth needs none.
    const bool rebuild = voxelize_static || rebuild_tree_;
    auto tree = tree_->update(rebuild ? &static_source : nullptr, &dynamic_source);
    if (!tree) return tree.status();
    if (rebuild) ++static_generation_;
    // Refinement stopped where a pool ran out: grow and rebuild this frame's tree from the kept fragment
    // lists, so no step returns a partial tree.
    while (tree->exhausted > 0) {
        auto more = grow_pools({}, true);
        if (!more) return more.status();
        ++static_generation_;
        ++out.pool_growths;
        tree = tree_->update(&static_source, &dynamic_source);
        if (!tree) return tree.status();
    }
    if (voxelize_static) voxelized_static(plan, out.static_slabs);
    static_dirty_ = false;
    rebuild_tree_ = false;
    append_ms(out.ms, "", tree->ms);
    out.static_rebuilt = rebuild || out.pool_growths > 0;
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
    std::uint32_t static_voxelized : 1;
    std::uint32_t static_slabs : 1;   ///< ... only in the slabs a scroll uncovered
    std::uint32_t static_rebuilt : 1; ///< the tree was rebuilt (static set voxelized, or pools grown)
    std::uint32_t unused : 29;
    std::uint32_t pool_growths; ///< before the frame was recorded
};
} // namespace

Status VoxelWorld::record(VkCommandBuffer cmd, std::span<const GpuInstance> dynamic, float dt) {
    if (!(dt > 0.0f)) return Status::failure("frame time must be > 0 s, got " + std::to_string(dt));
    auto grown = grow_for(dynamic);
    if (!grown) return grown.status();
    const StaticPlan plan = plan_static();
    const bool voxelize_static = plan.voxelize;
    const bool rebuild = voxelize_static || rebuild_tree_;
    if (voxelize_static) static_whole_ = true;
    if (plan.slabs) {
        if (Status s = static_->record_slabs(cmd, static_set_, desc_.grid, desc_.method, plan.shift); !s)
            return s;
    } else if (voxelize_static) {
        if (Status s = static_->record(cmd, static_set_, desc_.grid, desc_.method, 0.0f); !s) return s;
    }
    if (Status s = dynamic_->record(cmd, dynamic, desc_.grid, desc_.method, dt); !s) return s;
    const FragmentSource static_source{static_->fragment_buffer().address(),
                                       static_->fragment_count_address(), static_->fragment_capacity()};
    const FragmentSource dynamic_source{dynamic_->fragment_buffer().address(),
                                        dynamic_->fragment_count_address(), dynamic_->fragment_capacity()};
    if (Status s = tree_->record_update(cmd, rebuild ? &static_source : nullptr, &dynamic_source); !s)
        return s;
    if (voxelize_static) voxelized_static(plan, plan.slabs);
    static_dirty_ = false;
    rebuild_tree_ = false;
    if (rebuild) ++static_generation_;
    recorded_voxelized_ = voxelize_static;
    recorded_slabs_ = plan.slabs;
    recorded_rebuild_ = rebuild;
    recorded_growths_ = *grown ? 1u : 0u;
    recorded_frame_ = frame_++;
    return {};
}

std::size_t VoxelWorld::readback_bytes() {
    return sizeof(ReadbackHeader) + 2 * Voxelizer::readback_bytes() + SparseTree::readback_bytes();
}

void VoxelWorld::record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const {
    ReadbackHeader header{};
    header.frame = recorded_frame_;
    header.recorded_in = ctx_->recording_frame();
    header.static_voxelized = recorded_voxelized_ ? 1u : 0u;
    header.static_slabs = recorded_slabs_ ? 1u : 0u;
    header.static_rebuilt = recorded_rebuild_ ? 1u : 0u;
    header.pool_growths = recorded_growths_;
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
    out.static_slabs = header.static_slabs != 0;
    out.pool_growths = header.pool_growths;
    const bool voxelized = header.static_voxelized != 0;
    // The static counters stay as the last rebuild left them, so they are read every frame.
    auto fixed = static_->collect(bytes);
    if (!fixed) return fixed.status();
    auto moving = dynamic_->collect(bytes + Voxelizer::readback_bytes());
    if (!moving) return moving.status();
    out.tree = tree_->stats_from(bytes + 2 * Voxelizer::readback_bytes());
    if (voxelized) append_ms(out.ms, "voxelize_static_", static_->timings(header.recorded_in));
    append_ms(out.ms, "voxelize_", dynamic_->timings(header.recorded_in));
    append_ms(out.ms, "", tree_->timings(header.recorded_in));
    out.static_voxelize = *fixed;
    out.dynamic_voxelize = *moving;
    // The static counters are new only in a frame that voxelized the static set.
    // A slab pass's list holds a partial set then, so the set is voxelized whole.
    if (fixed->truncated && voxelized) static_dirty_ = static_whole_ = true;
    // Frames recorded before the pools grew ran out too: they do not grow them again.
    if (out.tree.exhausted > 0 && out.frame >= pools_grown_for_) {
        pools_grown_for_ = frame_;
        auto grown = grow_pools({}, true);
        if (!grown) return grown.status();
        ++out.pool_growths;
    }
    out.truncated = fixed->truncated || moving->truncated || out.tree.exhausted > 0;
    return out;
}

} // namespace gust
