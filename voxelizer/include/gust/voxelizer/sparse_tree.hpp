// A sparse voxel tree of branching b per axis, kept on the GPU from frame to frame: refined where
// fragments arrive, coarsened where they have been gone for K frames (docs/design.md "Sparse tree").
#pragma once

#include <cstdint>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/host_memory.hpp>
#include <gust/gpu/pipeline.hpp>
#include <gust/gpu/profiler.hpp>
#include <gust/voxelizer/grid.hpp>
#include <memory>
#include <memory_resource>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace gust {

namespace shaderio {
struct TreeState;
}

/// Shape and initial capacity of a tree.
struct TreeDesc {
    std::uint32_t branching = 4; ///< children per axis: 2 (octree), 4 or 8
    std::uint32_t res = 256;     ///< voxels per axis, a power of `branching` in [branching, 1024]
    /// Initial node-pool capacity, in blocks of branching^3 nodes; 0: sized for the branching (1,024 blocks,
    /// four times as many for an octree, whose 2^3-voxel bricks take four times as many for one surface).
    std::uint32_t node_blocks = 0;
    /// Initial leaf-mask capacity, in blocks (one per leaf brick); 0: sized for the branching (4,096, four
    /// times as many for an octree).
    std::uint32_t mask_blocks = 0;
    std::uint32_t hysteresis = 8; ///< K: blocks whose owner went more than K frames unreached are coarsened
    /// Fragments come from a grid finer by 2^fragment_shift per axis (a shallower tree over the same
    /// fragments, as the seed's depth table builds); 0 for fragments at `res`.
    std::uint32_t fragment_shift = 0;
};

/// Blocks in each of the tree's pools.
struct TreePools {
    std::uint32_t node_blocks = 0; ///< blocks of branching^3 nodes (block 0 holds the root)
    std::uint32_t mask_blocks = 0; ///< leaf-mask blocks, one per leaf brick (block 0 is never used)
};

/// One node of the tree, decoded on the host (SparseTree::nodes), for debug views and tests.
struct TreeNodeView {
    /// What reached the node in the last update.
    enum class State : std::uint8_t {
        Stale,   ///< no fragment reached it in the last update (coarsened after K such updates)
        Reached, ///< a dynamic fragment reached it in the last update
        Static,  ///< static fragments reached it: kept until the tree is rebuilt
    };
    std::uint32_t level = 0;    ///< 0: the root; depth - 1: leaf bricks of branching^3 voxels
    glm::uvec3 min{0};          ///< min corner, in the tree's voxels
    std::uint32_t extent = 0;   ///< voxels per axis: branching^(depth - level)
    State state = State::Stale; ///< what reached it in the last update
    bool refined = false;       ///< has a child block (a leaf brick: an occupancy mask)
};

/// A fragment list on the device, as the voxelizer leaves it.
struct FragmentSource {
    VkDeviceAddress keys = 0;   ///< uint[capacity] packed voxel keys
    VkDeviceAddress count = 0;  ///< uint fragment count (clamped to capacity when read)
    std::uint64_t capacity = 0; ///< slots at `keys`
};

/// What one update did, and what the tree holds after it.
struct TreeStats {
    /// `memory` holds the lists.
    explicit TreeStats(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
        : nodes_per_level(memory), ms(memory) {}
    std::uint32_t frame = 0; ///< the number the update stamped on the nodes it reached (1 for the first)
    std::pmr::vector<std::uint64_t>
        nodes_per_level;                ///< allocated nodes at levels 1..depth-1, then leaf bricks
    std::uint64_t nodes = 0;            ///< sum of nodes_per_level plus the root
    std::uint64_t voxels = 0;           ///< voxels set in leaves (static or dynamic)
    std::uint32_t refined = 0;          ///< blocks handed out this update
    std::uint32_t coarsened = 0;        ///< blocks taken back this update
    std::uint32_t exhausted = 0;        ///< refinements refused because a pool was full (tree is partial)
    std::uint32_t free_node_blocks = 0; ///< node blocks on the free list
    std::uint32_t free_mask_blocks = 0; ///< mask blocks on the free list
    std::uint32_t node_blocks_used = 0; ///< high-water mark of the node pool (live + free blocks)
    std::uint32_t mask_blocks_used =
        0;                            ///< high-water mark of the mask pool (live + free blocks, + 1 reserved)
    std::uint64_t pool_bytes = 0;     ///< bytes of live node and mask blocks
    std::uint64_t capacity_bytes = 0; ///< bytes the pools hold
    gpu::Timings ms;                  ///< GPU milliseconds per pass (empty without timestamps)
};

/// The tree. Thread-compatible; the Context must outlive it.
class SparseTree : public gpu::HostObject {
  public:
    /// Fails on a branching other than 2, 4, 8, a res that is not a power of it in [branching, 1024], or
    /// a fragment grid finer than 1024.
    static Result<std::unique_ptr<SparseTree>> create(gpu::Context& ctx, const TreeDesc& desc);

    /// One frame: when `rebuild_static` is given, the tree is emptied and those fragments are inserted
    /// as static (never coarsened); then `dynamic` fragments (may be null) are inserted, last frame's
    /// dynamic occupancy is replaced, and stale blocks are coarsened. Blocks until the GPU is done. Fails
    /// without `rebuild_static` while rebuild_pending().
    Result<TreeStats> update(const FragmentSource* rebuild_static, const FragmentSource* dynamic);
    /// Frames in flight: records update() into `cmd` without waiting; its stats come from
    /// record_readback() and stats_from() once the frame completed.
    Status record_update(VkCommandBuffer cmd, const FragmentSource* rebuild_static,
                         const FragmentSource* dynamic);
    /// Bytes record_readback() writes.
    static std::size_t readback_bytes();
    /// Records a copy of the tree's counters (after the recorded update) into `dst` at `offset`.
    void record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const;
    /// The stats of a recorded update from its readback.
    TreeStats stats_from(const void* readback) const;
    /// GPU milliseconds per pass of the update recorded while gpu::Context::begin_frame(`frame`) was
    /// current, once that frame completed; empty if none was recorded then.
    gpu::Timings timings(std::uint64_t frame) const;

    /// Grows the pools to at least these many blocks (never shrinks) with new buffers, without copying
    /// and without waiting: the old ones are released (retired by frame index while frames are in
    /// flight). The tree then holds nothing, and its next update must rebuild it (`rebuild_static` given;
    /// rebuild_pending()). Does nothing when the pools are that large already.
    Status reserve(std::uint32_t node_blocks, std::uint32_t mask_blocks);
    /// True after reserve() grew the pools and before the update that rebuilds the tree.
    bool rebuild_pending() const { return rebuild_pending_; }
    /// Blocks the pools hold.
    TreePools pools() const { return {node_blocks_, mask_blocks_}; }
    /// The most blocks a tree of this shape can use (every node refined): growing beyond it gains nothing.
    TreePools full_pools() const;

    /// Packed keys (sorted) of every voxel set in a leaf, static or dynamic (downloads the tree; blocks).
    /// Fails on a corrupt pool (a block linked twice or beyond those in use).
    Result<std::pmr::vector<std::uint32_t>> leaf_voxels() const;
    /// Every node of every allocated block, decoded level by level: the root, then all of level 1, and
    /// so on, so that a prefix of the list holds the coarse levels whole. Downloads the node pool
    /// (blocks until the GPU is done). Fails, rather than loop or read out of range, on a corrupt pool: a
    /// child block linked twice, or beyond the blocks in use.
    Result<std::pmr::vector<TreeNodeView>> nodes() const;

    /// The node pool's blocks in use (uvec2 per node: child block, touched; layout in
    /// shaders/tree/tree_io.h), downloaded for debug views and tests. Blocks until the GPU is done.
    Result<std::pmr::vector<glm::uvec2>> node_pool() const;
    /// The frame number the last update stamped on the nodes it reached (`touched`); 0 before the first.
    std::uint32_t frame() const { return frame_; }

    /// Device address of the node pool (uvec2 per node, layout in shaders/tree/tree_io.h).
    VkDeviceAddress node_address() const { return nodes_.address(); }
    /// Device address of the leaf mask pool.
    VkDeviceAddress mask_address() const { return masks_.address(); }
    std::uint32_t depth() const { return levels_; }
    std::uint32_t branching() const { return 1u << log2_b_; }
    std::uint32_t node_capacity() const { return node_blocks_; }
    std::uint32_t mask_capacity() const { return mask_blocks_; }

  private:
    explicit SparseTree(gpu::Context& ctx) : ctx_(ctx) {}
    Status allocate_pools(std::uint32_t node_blocks, std::uint32_t mask_blocks);
    /// Calls `visit(view, child)` for every node, level by level (see nodes()), `child` its child block.
    template <class Visit> Status walk(std::span<const glm::uvec2> nodes, Visit&& visit) const;
    /// Stats from the tree's counters after the update that stamped `frame`.
    TreeStats stats_of(const shaderio::TreeState& state, std::uint32_t frame) const;
    Status ensure_scratch(std::uint64_t fragments);
    void write_bindings(VkCommandBuffer cmd, const gpu::Buffer& bindings, const FragmentSource& source);
    /// Records an insertion of the fragments `bindings` names; `sized` when tree_begin sized its dispatches
    /// and visited its root (TreePush::size_fragments), else tree_fragments and the root's visit come first.
    /// No barrier follows its last (leaf) pass.
    void record_insert(VkCommandBuffer cmd, const gpu::Buffer& bindings, bool pinned, bool sized);
    Status prepare(const FragmentSource* rebuild_static, const FragmentSource* dynamic);
    void record_passes(VkCommandBuffer cmd, const FragmentSource* rebuild_static,
                       const FragmentSource* dynamic);

    gpu::Context& ctx_;
    std::uint32_t log2_b_ = 2;
    std::uint32_t levels_ = 1;
    std::uint32_t hysteresis_ = 8;
    std::uint32_t fragment_shift_ = 0;
    std::uint32_t node_blocks_ = 0;
    std::uint32_t mask_blocks_ = 0;
    std::uint32_t frame_ = 0;
    bool rebuild_pending_ = false;
    std::uint64_t scratch_capacity_ = 0;
    gpu::Pipeline begin_, fragments_, clear_, visit_, leaf_, coarsen_;
    gpu::Buffer state_, nodes_, masks_, node_free_, mask_free_;
    gpu::Buffer frag_node_, records_[2], leaves_[2];
    gpu::Buffer static_bindings_, dynamic_bindings_;
    gpu::Profiler profiler_;
};

} // namespace gust
