// One frame of docs/design.md's steps 3 and 4: voxelize what changed and keep the sparse tree current.
#pragma once

#include <cstdint>
#include <gust/voxelizer/sparse_tree.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace gust {

/// The grid, the tree's shape and how to voxelize.
struct WorldDesc {
    GridDesc grid; ///< grid.res must be a power of tree.branching
    /// tree.res is taken from grid.res. With tree.node_blocks and tree.mask_blocks both 0 the world sizes
    /// the pools from its meshes before each frame (VoxelWorld::step, ::record), so that a frame rarely
    /// runs out; given, the pools start at those sizes and grow only when they run out.
    TreeDesc tree;
    VoxelizeMethod method = VoxelizeMethod::Auto;
};

/// What one step did.
struct WorldFrame {
    /// `memory` holds the lists.
    explicit WorldFrame(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
        : static_voxelize(memory), dynamic_voxelize(memory), tree(memory), ms(memory) {}
    std::uint64_t frame = 0; ///< 0 for the first step
    /// The tree was rebuilt from the static set: it changed (and was voxelized again), or the pools grew.
    bool static_rebuilt = false;
    /// The static set was voxelized only in the slabs a scroll by whole voxels uncovered, the rest of its
    /// fragment list shifted into the moved grid (Voxelizer::voxelize_slabs); false when it was voxelized
    /// whole or not at all. The tree is rebuilt either way.
    bool static_slabs = false;
    VoxelizeStats static_voxelize;  ///< of the static set (the last rebuild's when not rebuilt now)
    VoxelizeStats dynamic_voxelize; ///< of this frame's dynamic instances
    TreeStats tree;                 ///< after the update
    /// Times the tree's pools were grown for this frame: before it (the meshes' estimate exceeded them),
    /// to redo it (step()), or after it ran out (collect(), for later frames).
    std::uint32_t pool_growths = 0;
    bool truncated = false; ///< recorded frame: a list or pool ran out, so its solids are partial
    gpu::Timings ms;        ///< milliseconds per pass (GPU where timed)
};

/// Static and dynamic voxelization feeding one tree. Thread-compatible; the Context must outlive it.
class VoxelWorld : public gpu::HostObject {
  public:
    static Result<std::unique_ptr<VoxelWorld>> create(gpu::Context& ctx, const WorldDesc& desc);

    /// Uploads a mesh (with a skin, see Voxelizer::upload) for use in instances of this world.
    Result<GpuMesh> upload(const MeshView& mesh, const SkinView* skin = nullptr) {
        return dynamic_->upload(mesh, skin);
    }
    /// Replaces a deforming mesh's positions for this frame (see Voxelizer::update_positions).
    Status update_positions(GpuMesh& mesh, std::span<const glm::vec3> positions) {
        return dynamic_->update_positions(mesh, positions);
    }
    /// The same from a device buffer (see Voxelizer::copy_positions).
    Status copy_positions(GpuMesh& mesh, VkBuffer source, VkDeviceSize offset) {
        return dynamic_->copy_positions(mesh, source, offset);
    }
    /// Poses a skinned mesh from a bone palette on the GPU (see Voxelizer::pose_from_bones).
    Status pose_from_bones(GpuMesh& mesh, std::span<const glm::mat4> palette) {
        return dynamic_->pose_from_bones(mesh, palette);
    }
    /// Frames in flight: records the skinning of the dynamic instances' meshes posed from bones, before
    /// record() voxelizes them (see Voxelizer::record_skinning). step() does it itself.
    void record_skinning(VkCommandBuffer cmd, std::span<const GpuInstance> dynamic) {
        dynamic_->record_skinning(cmd, dynamic);
    }

    /// Sets the static instances; the next step voxelizes them again only if they differ from the last
    /// set (meshes or matrices). Meshes must stay alive and unchanged while in the set.
    void set_static(std::span<const GpuInstance> instances);

    /// Moves the grid's min corner to `origin` (world, m, finite); the next step voxelizes the static set
    /// again and rebuilds the tree, whose voxels then index the moved grid. When the grid moved by whole
    /// voxels since the static set was last voxelized whole (within kWholeVoxelTolerance of a voxel on
    /// each axis) and the set is unchanged, only the slabs the move uncovered are voxelized
    /// (WorldFrame::static_slabs); the voxels are those of a whole voxelization at the new origin.
    Status move_grid(glm::vec3 origin);
    /// How far (in voxels) a move may be from whole voxels and still voxelize only the uncovered slabs.
    static constexpr double kWholeVoxelTolerance = 1e-3;

    /// Voxelizes the dynamic instances (with velocities over `dt` seconds, > 0) and updates the tree. Never
    /// returns a partial tree: when the pools ran out they grow and the tree is rebuilt from the kept
    /// fragment lists. Blocks until the GPU is done.
    Result<WorldFrame> step(std::span<const GpuInstance> dynamic, float dt);

    /// Frames in flight (gpu::Context::begin_frame): records step()'s work into `cmd` without waiting.
    /// Pools sized from the meshes' estimate are allocated before recording (never waiting); what runs
    /// out all the same is grown by collect() for later frames.
    Status record(VkCommandBuffer cmd, std::span<const GpuInstance> dynamic, float dt);
    /// Bytes record_readback() writes.
    static std::size_t readback_bytes();
    /// Records a copy of the recorded frame's counters into `dst` at `offset` (after record()).
    void record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const;
    /// What a recorded frame did, from its readback once the frame completed. When a list or pool ran out
    /// that frame's solids were cut short (`WorldFrame::truncated`); collect() grows it and has the next
    /// recorded frame voxelize the static set again and rebuild the tree, so later frames are whole.
    Result<WorldFrame> collect(const void* readback);

    const SparseTree& tree() const { return *tree_; }
    /// The dynamic fragment list and its velocities, for the solver.
    const Voxelizer& dynamic_voxelizer() const { return *dynamic_; }
    const Voxelizer& static_voxelizer() const { return *static_; }
    /// Counts the static set's voxelizations, run or recorded (a new set, a moved grid, a rebuild after the
    /// pools grew): while it stays the same, the static voxels in every cell do too, which lets the wind
    /// solver keep the cells that no moving surface reaches (SolidSource::static_generation).
    std::uint64_t static_generation() const { return static_generation_; }
    const GridDesc& grid() const { return desc_.grid; }

  private:
    VoxelWorld(gpu::Context& ctx, const WorldDesc& desc)
        : ctx_(&ctx), desc_(desc), static_set_(ctx.memory()), last_static_(ctx.memory()) {}

    /// The one growth policy of step(), record() and collect(): grows the pools to at least `wanted` (the
    /// meshes' estimate), doubled when `ran_out`, at most to the full tree; growing has the next update
    /// rebuild the tree. Returns whether the pools grew; fails when they ran out at the full tree's size.
    Result<bool> grow_pools(TreePools wanted, bool ran_out);
    /// grow_pools() with the estimate for the static set and `dynamic`, when the world sizes its pools.
    Result<bool> grow_for(std::span<const GpuInstance> dynamic);

    /// How the next update voxelizes the static set.
    struct StaticPlan {
        bool voxelize = false;
        bool slabs = false;  ///< only the slabs a scroll uncovered
        glm::ivec3 shift{0}; ///< slabs: the scroll, voxels
        glm::ivec3 at{0};    ///< slabs: voxels from static_anchor_ to the grid's origin
    };
    StaticPlan plan_static() const;
    /// Records that a step or frame that voxelized the static set as `plan` says (whole unless `slabs`)
    /// completed.
    void voxelized_static(const StaticPlan& plan, bool slabs);

    gpu::Context* ctx_ = nullptr;
    WorldDesc desc_;
    std::unique_ptr<Voxelizer> static_, dynamic_;
    std::unique_ptr<SparseTree> tree_;
    std::pmr::vector<GpuInstance> static_set_;
    bool static_dirty_ = true;      ///< the static set must be voxelized again (and the tree rebuilt)
    bool static_whole_ = true;      ///< ... and whole: it changed, or its list ran out (not only a scroll)
    glm::vec3 static_anchor_{0.0f}; ///< the grid's origin when the static set was last voxelized whole
    glm::ivec3 static_at_{0};       ///< voxels from static_anchor_ to the origin of its last voxelization
    bool rebuild_tree_ = false;     ///< the tree must be rebuilt from the kept static fragments (pools grew)
    bool estimate_pools_ = true;    ///< WorldDesc::tree gave no pool sizes
    std::uint64_t static_generation_ = 0;
    VoxelizeStats last_static_;
    std::uint64_t frame_ = 0;
    std::uint64_t recorded_frame_ = 0;   ///< record(): the frame recorded last
    bool recorded_voxelized_ = false;    ///< record(): whether it voxelized the static set
    bool recorded_slabs_ = false;        ///< record(): ... only in the slabs a scroll uncovered
    bool recorded_rebuild_ = false;      ///< record(): whether it rebuilt the tree
    std::uint32_t recorded_growths_ = 0; ///< record(): pool growths before it
    std::uint64_t pools_grown_for_ = 0; ///< collect(): frames from this one on were recorded with grown pools
};

} // namespace gust
