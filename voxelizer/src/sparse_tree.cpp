#include "tree/tree_io.h"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <gust/voxelizer/sparse_tree.hpp>

namespace gust {

namespace {
#include "gust_shaders/tree_begin_comp.h"
#include "gust_shaders/tree_clear_comp.h"
#include "gust_shaders/tree_coarsen_comp.h"
#include "gust_shaders/tree_fragments_comp.h"
#include "gust_shaders/tree_leaf_comp.h"
#include "gust_shaders/tree_visit_comp.h"

using shaderio::BlockRecord;
using shaderio::kMaxLevels;
using shaderio::TreeBindings;
using shaderio::TreePush;
using shaderio::TreeState;

template <std::size_t N> std::span<const std::uint32_t> words(const std::uint32_t (&a)[N]) {
    return {a, N};
}

/// Scratch lists never shrink below this many entries.
constexpr std::uint64_t kMinScratch = 1024;

} // namespace

Result<std::unique_ptr<SparseTree>> SparseTree::create(gpu::Context& ctx, const TreeDesc& desc) {
    std::uint32_t log2_b = 0;
    switch (desc.branching) {
    case 2:
        log2_b = 1;
        break;
    case 4:
        log2_b = 2;
        break;
    case 8:
        log2_b = 3;
        break;
    default:
        return Result<std::unique_ptr<SparseTree>>::failure("branching must be 2, 4 or 8, got " +
                                                            std::to_string(desc.branching));
    }
    std::uint32_t levels = 0;
    std::uint32_t size = 1;
    while (size < desc.res && levels < kMaxLevels) {
        size <<= log2_b;
        ++levels;
    }
    if (desc.res < desc.branching || desc.res > kMaxRes || size != desc.res)
        return Result<std::unique_ptr<SparseTree>>::failure(
            "tree resolution " + std::to_string(desc.res) + " must be a power of the branching factor " +
            std::to_string(desc.branching) + " in [" + std::to_string(desc.branching) + ", " +
            std::to_string(kMaxRes) + "]");
    if (desc.fragment_shift > 10 || (std::uint64_t(desc.res) << desc.fragment_shift) > kMaxRes)
        return Result<std::unique_ptr<SparseTree>>::failure(
            "fragment_shift " + std::to_string(desc.fragment_shift) + " puts the fragment grid beyond " +
            std::to_string(kMaxRes) + " voxels per axis");
    // A tiny scene at 8 voxels per cell ran out of the branching-4 sizes in an octree in its eighth frame.
    const std::uint32_t octree = desc.branching == 2 ? 4u : 1u;
    const std::uint32_t node_blocks = desc.node_blocks != 0 ? desc.node_blocks : 1024u * octree;
    const std::uint32_t mask_blocks = desc.mask_blocks != 0 ? desc.mask_blocks : 4096u * octree;

    std::unique_ptr<SparseTree> tree(new (ctx.memory()) SparseTree(ctx));
    tree->log2_b_ = log2_b;
    tree->levels_ = levels;
    tree->hysteresis_ = desc.hysteresis;
    tree->fragment_shift_ = desc.fragment_shift;
    struct Stage {
        gpu::Pipeline* pipeline;
        const char* name;
        std::span<const std::uint32_t> code;
    };
    const Stage stages[] = {{&tree->begin_, "gust tree_begin", words(tree_begin_comp)},
                            {&tree->fragments_, "gust tree_fragments", words(tree_fragments_comp)},
                            {&tree->clear_, "gust tree_clear", words(tree_clear_comp)},
                            {&tree->visit_, "gust tree_visit", words(tree_visit_comp)},
                            {&tree->leaf_, "gust tree_leaf", words(tree_leaf_comp)},
                            {&tree->coarsen_, "gust tree_coarsen", words(tree_coarsen_comp)}};
    for (const Stage& stage : stages) {
        auto pipeline = gpu::Pipeline::compute(ctx, stage.name, stage.code, sizeof(TreePush));
        if (!pipeline) return pipeline.status();
        *stage.pipeline = std::move(*pipeline);
    }
    auto state = gpu::Buffer::create(ctx, sizeof(TreeState), gpu::MemoryUse::Readback,
                                     VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, "gust tree state");
    if (!state) return state.status();
    tree->state_ = std::move(*state);
    const std::pair<gpu::Buffer*, const char*> bindings[] = {
        {&tree->static_bindings_, "gust tree static bindings"},
        {&tree->dynamic_bindings_, "gust tree dynamic bindings"}};
    for (const auto& [buffer, name] : bindings) {
        auto b = gpu::Buffer::create(ctx, sizeof(TreeBindings), gpu::MemoryUse::Device, 0, name);
        if (!b) return b.status();
        *buffer = std::move(*b);
    }
    auto profiler = gpu::Profiler::create(ctx);
    if (!profiler) return profiler.status();
    tree->profiler_ = std::move(*profiler);
    if (Status s = tree->allocate_pools(node_blocks, mask_blocks); !s) return s;
    if (Status s = tree->ensure_scratch(kMinScratch); !s) return s;
    TreeState empty{};
    empty.node_blocks_used = 1;
    empty.mask_blocks_used = 1;
    std::memcpy(tree->state_.mapped(), &empty, sizeof(empty));
    Status cleared = ctx.submit_and_wait([&](VkCommandBuffer cmd) {
        ctx.vk().vkCmdFillBuffer(cmd, tree->nodes_.handle(), 0, VK_WHOLE_SIZE, 0);
    });
    if (!cleared) return cleared;
    return tree;
}

Status SparseTree::allocate_pools(std::uint32_t node_blocks, std::uint32_t mask_blocks) {
    const std::uint64_t children = 1ull << (3 * log2_b_);
    const std::uint64_t stride = shaderio::mask_stride(log2_b_);
    const std::uint64_t list = std::uint64_t(node_blocks) + mask_blocks;
    struct Want {
        gpu::Buffer* buffer;
        VkDeviceSize bytes;
        const char* name;
    };
    const Want wants[] = {{&nodes_, node_blocks * children * sizeof(glm::uvec2), "gust tree nodes"},
                          {&masks_, mask_blocks * stride * sizeof(std::uint32_t), "gust tree masks"},
                          {&node_free_, node_blocks * sizeof(std::uint32_t), "gust tree node free list"},
                          {&mask_free_, mask_blocks * sizeof(std::uint32_t), "gust tree mask free list"},
                          {&records_[0], list * sizeof(BlockRecord), "gust tree records even"},
                          {&records_[1], list * sizeof(BlockRecord), "gust tree records odd"},
                          {&leaves_[0], list * sizeof(std::uint32_t), "gust tree leaves even"},
                          {&leaves_[1], list * sizeof(std::uint32_t), "gust tree leaves odd"}};
    // All or nothing: a failed allocation leaves the old pools in place.
    std::pmr::vector<gpu::Buffer> fresh(ctx_.memory());
    for (const Want& want : wants) {
        auto b = gpu::Buffer::create(ctx_, want.bytes, gpu::MemoryUse::Device, 0, want.name);
        if (!b) return b.status();
        fresh.push_back(std::move(*b));
    }
    // Moving over a buffer releases it; while frames are in flight the Context keeps it until the frames
    // recorded so far completed (Context::retire).
    for (std::size_t i = 0; i < fresh.size(); ++i)
        *wants[i].buffer = std::move(fresh[i]);
    node_blocks_ = node_blocks;
    mask_blocks_ = mask_blocks;
    return {};
}

Status SparseTree::reserve(std::uint32_t node_blocks, std::uint32_t mask_blocks) {
    node_blocks = std::max(node_blocks, node_blocks_);
    mask_blocks = std::max(mask_blocks, mask_blocks_);
    if (node_blocks == node_blocks_ && mask_blocks == mask_blocks_) return {};
    // Block indices are baked into the nodes, so a copy would keep the tree; but every caller grows
    // because a frame ran out, and that frame is rebuilt anyway. Not copying keeps growth free of a
    // submission of its own, which a frame recorded into the host's command buffer cannot wait for.
    if (Status s = allocate_pools(node_blocks, mask_blocks); !s) return s;
    rebuild_pending_ = true;
    return {};
}

TreePools SparseTree::full_pools() const {
    // Every node refined: node blocks for the root's block and every internal node, a mask block for
    // every node of the last level (plus the unused block 0).
    std::uint64_t nodes = 1, level_nodes = 1;
    for (std::uint32_t level = 0; level + 1 < levels_; ++level) {
        nodes += level_nodes;
        level_nodes <<= 3 * log2_b_;
    }
    const std::uint64_t limit = UINT32_MAX;
    return {std::uint32_t(std::min(nodes, limit)), std::uint32_t(std::min(level_nodes + 1, limit))};
}

Status SparseTree::ensure_scratch(std::uint64_t fragments) {
    if (fragments <= scratch_capacity_) return {};
    const std::uint64_t capacity = std::max(fragments, kMinScratch);
    auto buffer = gpu::Buffer::create(ctx_, capacity * sizeof(std::uint32_t), gpu::MemoryUse::Device, 0,
                                      "gust tree fragment nodes");
    if (!buffer) return buffer.status();
    frag_node_ = std::move(*buffer);
    scratch_capacity_ = capacity;
    return {};
}

void SparseTree::write_bindings(VkCommandBuffer cmd, const gpu::Buffer& bindings,
                                const FragmentSource& source) {
    TreeBindings b{};
    b.state = state_.address();
    b.nodes = nodes_.address();
    b.masks = masks_.address();
    b.node_free = node_free_.address();
    b.mask_free = mask_free_.address();
    b.fragments = source.keys;
    b.fragment_count = source.count;
    b.frag_node = frag_node_.address();
    b.records[0] = records_[0].address();
    b.records[1] = records_[1].address();
    b.leaves[0] = leaves_[0].address();
    b.leaves[1] = leaves_[1].address();
    b.fragment_capacity = std::uint32_t(std::min<std::uint64_t>(source.capacity, scratch_capacity_));
    b.node_capacity = node_blocks_;
    b.mask_capacity = mask_blocks_;
    b.list_capacity = node_blocks_ + mask_blocks_;
    b.log2_branching = log2_b_;
    b.levels = levels_;
    b.hysteresis = hysteresis_;
    b.key_shift = fragment_shift_;
    gpu::update(ctx_, cmd, bindings, &b, sizeof(b));
}

void SparseTree::record_insert(VkCommandBuffer cmd, const gpu::Buffer& bindings, bool pinned, bool sized) {
    TreePush push{bindings.address(), frame_, 0, pinned ? 1u : 0u, 0};
    auto once = [&](const gpu::Pipeline& p) {
        p.bind(cmd, &push, sizeof(push));
        p.dispatch(cmd, 1, 1, 1);
        gpu::barrier(ctx_, cmd);
    };
    auto indirect = [&](const gpu::Pipeline& p, std::size_t offset) {
        p.bind(cmd, &push, sizeof(push));
        p.dispatch_indirect(cmd, state_.handle(), offset);
        gpu::barrier(ctx_, cmd);
    };
    if (!sized) once(fragments_);
    // One stage a level: each fragment steps down to its node and marks it, the first to reach a node
    // without children giving it its block. tree_begin visited the root of an insertion it sized.
    for (std::uint32_t level = sized ? 1 : 0; level < levels_; ++level) {
        push.level = level;
        indirect(visit_, offsetof(TreeState, fragments_dispatch));
    }
    // No barrier after the leaf pass: the caller orders it before what follows.
    leaf_.bind(cmd, &push, sizeof(push));
    leaf_.dispatch_indirect(cmd, state_.handle(), offsetof(TreeState, fragments_dispatch));
}

Status SparseTree::prepare(const FragmentSource* rebuild_static, const FragmentSource* dynamic) {
    if (rebuild_pending_ && !rebuild_static)
        return Status::failure("the tree's pools grew: its next update must rebuild it from the static "
                               "fragments (rebuild_static), since the new pools hold nothing");
    std::uint64_t needed = 0;
    for (const FragmentSource* s : {rebuild_static, dynamic})
        if (s) needed = std::max(needed, s->capacity);
    return ensure_scratch(needed);
}

Result<TreeStats> SparseTree::update(const FragmentSource* rebuild_static, const FragmentSource* dynamic) {
    if (Status s = prepare(rebuild_static, dynamic); !s) return s;
    Status done =
        ctx_.submit_and_wait([&](VkCommandBuffer cmd) { record_passes(cmd, rebuild_static, dynamic); });
    if (!done) return done;
    TreeState state{};
    std::memcpy(&state, state_.mapped(), sizeof(state));
    TreeStats stats = stats_of(state, frame_);
    stats.ms = profiler_.read();
    return stats;
}

Status SparseTree::record_update(VkCommandBuffer cmd, const FragmentSource* rebuild_static,
                                 const FragmentSource* dynamic) {
    if (Status s = prepare(rebuild_static, dynamic); !s) return s;
    record_passes(cmd, rebuild_static, dynamic);
    return {};
}

namespace {
/// What record_readback() writes: the counters, then the frame number the update stamped.
struct Readback {
    TreeState state;
    std::uint32_t frame;
    std::uint32_t unused;
};
} // namespace

std::size_t SparseTree::readback_bytes() {
    return sizeof(Readback);
}

void SparseTree::record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const {
    static_assert(offsetof(Readback, frame) == sizeof(TreeState));
    const std::uint32_t frame[2] = {frame_, 0};
    gpu::record_readback(ctx_, cmd, state_, sizeof(TreeState), dst, offset, frame);
}

void SparseTree::record_passes(VkCommandBuffer cmd, const FragmentSource* rebuild_static,
                               const FragmentSource* dynamic) {
    const FragmentSource none{};
    if (rebuild_static) write_bindings(cmd, static_bindings_, *rebuild_static);
    write_bindings(cmd, dynamic_bindings_, dynamic ? *dynamic : none);
    ++frame_;
    const auto& vk = ctx_.vk();
    profiler_.reset(cmd);
    profiler_.begin(cmd, "tree_begin");
    if (rebuild_static) {
        rebuild_pending_ = false;
        TreeState empty{};
        empty.node_blocks_used = 1;
        empty.mask_blocks_used = 1;
        vk.vkCmdUpdateBuffer(cmd, state_.handle(), 0, sizeof(empty), &empty);
        vk.vkCmdFillBuffer(cmd, nodes_.handle(), 0, (1ull << (3 * log2_b_)) * sizeof(glm::uvec2), 0);
    }
    gpu::barrier(ctx_, cmd);
    // A frame that inserts only dynamic fragments has them sized and their root visited by tree_begin, so
    // that the visit of the level below the root runs beside the clearing.
    const bool sized = dynamic && !rebuild_static;
    TreePush push{dynamic_bindings_.address(), frame_, 0, 0, sized ? shaderio::kSizeFragments : 0u};
    begin_.bind(cmd, &push, sizeof(push));
    begin_.dispatch(cmd, 1, 1, 1);
    gpu::barrier(ctx_, cmd);
    push.size_fragments = 0;
    clear_.bind(cmd, &push, sizeof(push));
    clear_.dispatch_indirect(cmd, state_.handle(), offsetof(TreeState, leaves_dispatch));
    // An insertion's passes up to the leaf pass (behind their barriers) touch no live leaf's words, so
    // they run beside the clearing (the first of them with it); only the coarsening, which frees leaves,
    // waits for it.
    if (!rebuild_static && !dynamic) gpu::barrier(ctx_, cmd);
    profiler_.end(cmd);
    if (rebuild_static) {
        profiler_.begin(cmd, "tree_static");
        record_insert(cmd, static_bindings_, true, false);
        if (dynamic) gpu::barrier(ctx_, cmd);
        profiler_.end(cmd);
    }
    if (dynamic) {
        profiler_.begin(cmd, "tree_dynamic");
        record_insert(cmd, dynamic_bindings_, false, sized);
        profiler_.end(cmd);
    }
    // The coarsening runs beside the last leaf pass: it frees only blocks whose owners went unreached for
    // more than the hysteresis, and the leaf pass writes only leaves reached this frame (their whole paths
    // marked by the visits before it); the two count into different fields of the state.
    profiler_.begin(cmd, "tree_coarsen");
    coarsen_.bind(cmd, &push, sizeof(push));
    coarsen_.dispatch_indirect(cmd, state_.handle(), offsetof(TreeState, records_dispatch));
    gpu::barrier(ctx_, cmd);
    profiler_.end(cmd);
}

gpu::Timings SparseTree::timings(std::uint64_t frame) const {
    return profiler_.read_frame(frame);
}

TreeStats SparseTree::stats_from(const void* readback) const {
    Readback r{};
    std::memcpy(&r, readback, sizeof(r));
    return stats_of(r.state, r.frame);
}

TreeStats SparseTree::stats_of(const TreeState& st, std::uint32_t frame) const {
    TreeStats out(ctx_.memory());
    out.frame = frame;
    const std::uint64_t children = 1ull << (3 * log2_b_);
    const std::uint64_t stride = shaderio::mask_stride(log2_b_);
    out.nodes = 1;
    for (std::uint32_t level = 0; level < levels_; ++level) {
        const bool leaf = level + 1 == levels_;
        const std::uint64_t count = leaf ? st.blocks_per_level[level] : st.blocks_per_level[level] * children;
        out.nodes_per_level.push_back(count);
        if (!leaf) out.nodes += count;
    }
    out.refined = st.refined;
    out.coarsened = st.coarsened;
    out.exhausted = st.exhausted;
    out.free_node_blocks = st.node_free_top;
    out.free_mask_blocks = st.mask_free_top;
    out.node_blocks_used = st.node_blocks_used;
    out.mask_blocks_used = st.mask_blocks_used;
    const std::uint64_t live_nodes = st.node_blocks_used - st.node_free_top;
    const std::uint64_t live_masks = st.mask_blocks_used - 1 - st.mask_free_top;
    out.pool_bytes = live_nodes * children * sizeof(glm::uvec2) + live_masks * stride * sizeof(std::uint32_t);
    out.capacity_bytes = nodes_.size() + masks_.size();
    out.voxels = std::uint64_t(st.static_voxels) + st.dynamic_voxels;
    return out;
}

Result<std::pmr::vector<glm::uvec2>> SparseTree::node_pool() const {
    TreeState st{};
    std::memcpy(&st, state_.mapped(), sizeof(st));
    std::pmr::vector<glm::uvec2> nodes(std::size_t(st.node_blocks_used) << (3 * log2_b_), ctx_.memory());
    if (Status s = gpu::download(ctx_, nodes_, nodes.data(), nodes.size() * sizeof(glm::uvec2)); !s) return s;
    return nodes;
}

template <class Visit> Status SparseTree::walk(std::span<const glm::uvec2> nodes, Visit&& visit) const {
    const std::uint32_t children = 1u << (3 * log2_b_);
    const std::size_t blocks = nodes.size() / children;
    if (blocks == 0) return Status::failure("the tree's node pool does not hold the root's block");
    struct Visited {
        std::uint32_t node;
        glm::uvec3 min; ///< in voxels
    };
    std::pmr::vector<Visited> level_nodes(ctx_.memory()), next(ctx_.memory());
    level_nodes.push_back({0, glm::uvec3(0)});
    // A block linked twice (or the root's block linked as a child) would mean a corrupt pool; refusing
    // it bounds the walk.
    std::pmr::vector<bool> reached(blocks, false, ctx_.memory());
    reached[0] = true;
    std::uint32_t extent = 1u << (log2_b_ * levels_);
    for (std::uint32_t level = 0; !level_nodes.empty(); ++level, extent >>= log2_b_) {
        const bool bricks = level + 1 == levels_;
        next.clear();
        for (const Visited& v : level_nodes) {
            const glm::uvec2 node = nodes[v.node];
            TreeNodeView view;
            view.level = level;
            view.min = v.min;
            view.extent = extent;
            view.state = node.y == shaderio::kPinned       ? TreeNodeView::State::Static
                         : frame_ != 0 && node.y == frame_ ? TreeNodeView::State::Reached
                                                           : TreeNodeView::State::Stale;
            view.refined = node.x != 0;
            if (Status s = visit(view, node.x); !s) return s;
            if (bricks || node.x == 0) continue;
            if (node.x >= blocks || reached[node.x])
                return Status::failure("the tree's node pool is corrupt: node " + std::to_string(v.node) +
                                       " at level " + std::to_string(level) + " links block " +
                                       std::to_string(node.x) +
                                       (node.x >= blocks ? " of " + std::to_string(blocks) + " in use"
                                                         : ", which another node links too"));
            reached[node.x] = true;
            const std::uint32_t child_extent = extent >> log2_b_;
            for (std::uint32_t c = 0; c < children; ++c)
                next.push_back(
                    {node.x * children + c, v.min + shaderio::slot_offset(c, log2_b_) * child_extent});
        }
        level_nodes.swap(next);
    }
    return {};
}

Result<std::pmr::vector<TreeNodeView>> SparseTree::nodes() const {
    std::pmr::vector<TreeNodeView> out(ctx_.memory());
    if (rebuild_pending_) {
        // The grown pools hold nothing until the next update rebuilds the tree: an empty root.
        TreeNodeView root;
        root.extent = 1u << (log2_b_ * levels_);
        out.push_back(root);
        return out;
    }
    auto pool = node_pool();
    if (!pool) return pool.status();
    Status walked = walk(*pool, [&](const TreeNodeView& view, std::uint32_t) {
        out.push_back(view);
        return Status{};
    });
    if (!walked) return walked;
    return out;
}

Result<std::pmr::vector<std::uint32_t>> SparseTree::leaf_voxels() const {
    std::pmr::vector<std::uint32_t> out(ctx_.memory());
    if (rebuild_pending_) return out;
    TreeState st{};
    std::memcpy(&st, state_.mapped(), sizeof(st));
    const std::uint32_t children = 1u << (3 * log2_b_);
    const std::uint32_t stride = shaderio::mask_stride(log2_b_);
    const std::uint32_t words = shaderio::mask_words(log2_b_);
    auto nodes = node_pool();
    if (!nodes) return nodes.status();
    std::pmr::vector<std::uint32_t> masks(std::size_t(st.mask_blocks_used) * stride, ctx_.memory());
    if (Status s = gpu::download(ctx_, masks_, masks.data(), masks.size() * sizeof(std::uint32_t)); !s)
        return s;
    std::pmr::vector<bool> reached(st.mask_blocks_used, false, ctx_.memory());
    Status walked = walk(*nodes, [&](const TreeNodeView& view, std::uint32_t block) {
        if (view.level + 1 != levels_ || block == 0) return Status{};
        if (block >= st.mask_blocks_used || reached[block])
            return Status::failure("the tree's mask pool is corrupt: a brick at level " +
                                   std::to_string(view.level) + " links mask block " + std::to_string(block) +
                                   (block >= st.mask_blocks_used
                                        ? " of " + std::to_string(st.mask_blocks_used) + " in use"
                                        : ", which another brick links too"));
        reached[block] = true;
        const std::uint32_t* m = &masks[std::size_t(block) * stride];
        for (std::uint32_t bit = 0; bit < children; ++bit)
            if (((m[bit / 32] | m[words + bit / 32]) >> (bit % 32)) & 1u) {
                const glm::uvec3 v = view.min + shaderio::slot_offset(bit, log2_b_);
                out.push_back(pack_voxel(v.x, v.y, v.z));
            }
        return Status{};
    });
    if (!walked) return walked;
    std::sort(out.begin(), out.end());
    return out;
}

} // namespace gust
