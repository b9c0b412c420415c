// GPU conservative surface voxelization of triangle meshes into a fragment list (docs/design.md "Voxelizer").
#pragma once

#include <cstdint>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/host_memory.hpp>
#include <gust/gpu/pipeline.hpp>
#include <gust/gpu/profiler.hpp>
#include <gust/voxelizer/grid.hpp>
#include <gust/voxelizer/voxelize_cost.hpp>
#include <memory>
#include <memory_resource>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace gust {

namespace shaderio {
struct VoxelizeCounters;
}

/// Which path turns triangles into voxels.
enum class VoxelizeMethod {
    Raster,  ///< hardware rasterizer: dominant-axis projection, dilation, exact per-voxel test
    Compute, ///< a thread per triangle (a workgroup per large triangle), exact per-voxel test
    Auto     ///< per instance, the path the cost model predicts faster on this device and queue
             ///< (voxelize_cost.hpp)
};

/// "raster", "compute" or "auto".
const char* to_string(VoxelizeMethod method);
/// Parses "raster", "compute" or "auto"; false for anything else.
bool parse_method(const std::string& text, VoxelizeMethod& out);
/// Whether `method` can run on the queue `device` describes: Raster needs a queue with graphics, and on
/// an async compute queue (DeviceInfo::graphics_queue false) it fails naming the queue and the paths
/// that run there; Auto then picks Compute for every instance.
Status check_method(VoxelizeMethod method, const gpu::DeviceInfo& device);

/// Joints and weights of a skinned mesh, four influences a vertex as glTF's JOINTS_0 and WEIGHTS_0, for
/// Voxelizer::upload. The mesh's positions are its bind pose, which the palette's matrices move.
struct SkinView {
    const std::uint16_t* joints = nullptr; ///< 4 per vertex, each < joint_count
    const float* weights = nullptr;        ///< 4 per vertex, finite, >= 0, not all 0; used as given
    std::uint32_t joint_count = 0;         ///< palette size, 1..kMaxSkinJoints
};
/// The most joints a skin has (uint16 joint indices).
inline constexpr std::uint32_t kMaxSkinJoints = 65536;

/// A mesh uploaded to the device, validated once. Owned by the caller; outlives its use in calls.
class GpuMesh {
  public:
    GpuMesh() = default;
    std::uint32_t triangle_count() const { return triangles_; }
    std::uint32_t vertex_count() const { return vertices_; }
    /// Joints of its skin (Voxelizer::upload with a SkinView); 0 without one.
    std::uint32_t joint_count() const { return joints_; }
    /// Triangle sizes measured at upload (the positions given then), for the cost model and list sizing.
    const MeshSizes& sizes() const { return sizes_; }

  private:
    friend class Voxelizer;
    explicit GpuMesh(std::pmr::memory_resource* memory) : staged_(memory), staged_palette_(memory) {}
    gpu::Buffer positions_;      ///< float[3 * vertices], this frame
    gpu::Buffer prev_positions_; ///< float[3 * vertices], last frame (only once positions were updated)
    gpu::Buffer indices_;        ///< uint[3 * triangles]
    std::uint32_t triangles_ = 0;
    std::uint32_t vertices_ = 0;
    MeshSizes sizes_;
    // A skin: the bind pose, joints (uvec2 of four uint16) and weights (vec4) per vertex, and the palette
    // the skinning pass reads (mat4 per joint, written by the frame that poses the mesh).
    gpu::Buffer bind_, joint_indices_, weights_, palette_;
    std::uint32_t joints_ = 0;
    // Frames in flight: positions set since the last recorded frame, written into positions_ by the next
    // frame's commands (a write now could race the frames still running). Mutable: the positions are
    // already set; the staging only says when they reach the GPU.
    mutable std::pmr::vector<glm::vec3> staged_;
    mutable VkBuffer staged_source_ = VK_NULL_HANDLE; ///< or copied from this buffer at staged_offset_
    mutable VkDeviceSize staged_offset_ = 0;
    /// Or posed from this palette by the next recorded skinning pass (Voxelizer::pose_from_bones).
    mutable std::pmr::vector<glm::mat4> staged_palette_;
    bool staged() const {
        return !staged_.empty() || staged_source_ != VK_NULL_HANDLE || !staged_palette_.empty();
    }
};

/// One placement of an uploaded mesh.
struct GpuInstance {
    const GpuMesh* mesh = nullptr;
    glm::mat4 model{1.0f};               ///< mesh space -> world space, this frame
    std::optional<glm::mat4> prev_model; ///< last frame's; none means it did not move
    /// The change since last frame (transform or positions) is a jump, not motion: no surface velocity.
    bool teleport = false;
};

/// Options for a Voxelizer.
struct VoxelizerDesc {
    /// Fragment slots allocated up front; the list grows (and the pass is redone) when a call needs more.
    std::uint32_t initial_capacity = 1u << 20;
};

/// What one voxelize() call did.
struct VoxelizeStats {
    /// `memory` holds the pass timings.
    explicit VoxelizeStats(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
        : ms(memory) {}
    std::uint64_t triangles = 0; ///< triangles submitted
    std::uint64_t rejected = 0;  ///< triangles with a non-finite vertex after the model transform
    std::uint64_t fragments =
        0; ///< entries in the fragment list (a voxel appears once per triangle touching it)
    std::uint32_t retries = 0;                      ///< passes redone because the fragment list was too small
    std::uint64_t capacity = 0;                     ///< fragment slots after the call
    VoxelizeMethod method = VoxelizeMethod::Raster; ///< path used (Auto reports the last mesh's choice)
    gpu::Timings ms;                                ///< GPU milliseconds per pass (empty without timestamps)
    bool truncated = false; ///< recorded pass (frames in flight) overflowed: fragments were cut, list grown
};

/// Owns the pipelines and the fragment list. One call at a time (thread-compatible).
class Voxelizer : public gpu::HostObject {
  public:
    /// Builds the pipelines on `ctx` (which must outlive the Voxelizer).
    static Result<std::unique_ptr<Voxelizer>> create(gpu::Context& ctx, const VoxelizerDesc& desc = {});

    /// Validates `mesh` (index count a multiple of 3, every index < vertex_count, stride >= 12) and
    /// copies it to the device. Non-finite positions are accepted: those triangles are counted as rejected.
    /// With `skin` (joint indices in range, weights finite, non-negative and not all 0 a vertex) the mesh's
    /// poses may come from bone palettes (pose_from_bones); its positions are the bind pose.
    Result<GpuMesh> upload(const MeshView& mesh, const SkinView* skin = nullptr);

    /// Voxelizes every instance into the fragment list, blocking until done. The list holds each
    /// voxel once per triangle that touches it; it is never truncated: when it overflows it is grown
    /// and the pass redone (counted in `retries`). With `dt` > 0 (seconds since last frame) each
    /// fragment also gets the surface velocity there (velocity_buffer()).
    Result<VoxelizeStats> voxelize(std::span<const GpuInstance> instances, const GridDesc& grid,
                                   VoxelizeMethod method, float dt = 0.0f);

    /// A scroll's pass, instead of voxelize() when only the grid's origin moved by `shift` whole voxels (the
    /// old grid's voxel v + shift is `grid`'s v) since the last call, which was made with the same res,
    /// voxel size and keep and without a frame time. Moves the last call's fragment list into `grid` (keys
    /// minus `shift`, those outside the kept extent dropped), then appends only the fragments of voxels
    /// the old grid did not keep (v + shift outside [0, keep) on some axis): the same voxels as
    /// voxelize() at `grid`, in another order and with the same duplicates. Both paths support it. One
    /// pass, never redone: when the list overflowed, the stats say `truncated`, the list was grown and
    /// holds a partial set, and the caller voxelizes again with voxelize().
    Result<VoxelizeStats> voxelize_slabs(std::span<const GpuInstance> instances, const GridDesc& grid,
                                         VoxelizeMethod method, glm::ivec3 shift);
    /// Frames in flight: records voxelize_slabs()'s pass, as record() records voxelize()'s (collect()
    /// reports an overflow, then the list is partial and the caller records voxelize()'s pass again). A
    /// last recorded pass that overflowed makes this one count as overflowed too.
    Status record_slabs(VkCommandBuffer cmd, std::span<const GpuInstance> instances, const GridDesc& grid,
                        VoxelizeMethod method, glm::ivec3 shift);

    /// Replaces a mesh's vertex positions (a skinned pose) with `positions` (mesh space, one per vertex);
    /// the previous ones are kept for velocities. Blocks until uploaded; with frames in flight
    /// (gpu::Context::deferred) the positions are kept and written by the next recorded pass instead.
    Status update_positions(GpuMesh& mesh, std::span<const glm::vec3> positions);
    /// The same from a device buffer of the same Context's device holding vertex_count() float3 at
    /// `offset` (the caller checked its size). Blocks until copied; with frames in flight the copy is
    /// recorded by the next pass, and the buffer must hold the positions when that pass runs.
    Status copy_positions(GpuMesh& mesh, VkBuffer source, VkDeviceSize offset);
    /// Poses a skinned mesh from `palette` (joint_count() matrices, bind-pose mesh space -> posed mesh space)
    /// on the GPU, as update_positions would with the positions a CPU skinned from it: the previous pose is
    /// kept for velocities, and the next record_skinning() writes this one (copied now). The last of these
    /// three calls before that pass sets the pose.
    Status pose_from_bones(GpuMesh& mesh, std::span<const glm::mat4> palette);
    /// Records the skinning pass of every instance's mesh posed from bones since the last one (palettes,
    /// then one dispatch a mesh) into `cmd`, before the voxelize pass that reads them; voxelize() records it
    /// itself. Records nothing when no mesh waits.
    void record_skinning(VkCommandBuffer cmd, std::span<const GpuInstance> instances);

    /// Frames in flight: records one pass of voxelize() into `cmd` without waiting or growing the list
    /// within the frame. record_readback() copies the pass's counters out; collect() reads them once the
    /// frame completed and grows the list for later frames if this one overflowed (`truncated`).
    Status record(VkCommandBuffer cmd, std::span<const GpuInstance> instances, const GridDesc& grid,
                  VoxelizeMethod method, float dt);
    /// Bytes record_readback() writes.
    static std::size_t readback_bytes();
    /// Records a copy of the last recorded pass's counters and capacities into `dst` at `offset`.
    void record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const;
    /// The stats of a recorded pass from its readback; grows the lists it overflowed.
    Result<VoxelizeStats> collect(const void* readback);
    /// GPU milliseconds per pass of the pass recorded while gpu::Context::begin_frame(`frame`) was
    /// current, once that frame completed; empty if none was recorded then.
    gpu::Timings timings(std::uint64_t frame) const;

    /// Copies the fragment list of the last call to the host (packed keys, unsorted, duplicates kept).
    Result<std::vector<std::uint32_t>> read_fragments() const;

    /// The device fragment list of the last call and its length, for passes that consume it on the GPU.
    const gpu::Buffer& fragment_buffer() const { return fragments_; }
    std::uint64_t fragment_count() const { return fragment_count_; }
    /// Device address of the uint counting the last call's fragments (may exceed the capacity only
    /// inside a call that then redoes its pass).
    VkDeviceAddress fragment_count_address() const { return counters_.address(); }
    /// Fragment slots of the current list.
    std::uint64_t fragment_capacity() const { return capacity_; }
    /// Surface velocity per fragment of the last call made with dt > 0: uvec2 per fragment holding
    /// half-float x, y (first word) and z (second word), m/s in world space.
    const gpu::Buffer& velocity_buffer() const { return velocities_; }
    /// Copies the velocities of the last call to the host (same order as read_fragments()).
    Result<std::vector<glm::vec3>> read_velocities() const;

  private:
    explicit Voxelizer(gpu::Context& ctx) : ctx_(ctx) {}
    /// The most fragments one device allocation holds, the moving meshes' velocity list included.
    std::uint64_t fragment_limit() const;
    Status ensure_capacity(std::uint64_t fragments);
    Status rotate_positions(GpuMesh& mesh);
    /// Uploads a checked skin's bind pose (the mesh's positions), joints and weights, and makes its palette.
    Status upload_skin(GpuMesh& mesh, const MeshView& view, const SkinView& skin);
    Status ensure_large_list(std::uint64_t items);
    Status ensure_velocity_capacity();
    Status ensure_instances(std::size_t count);
    Result<VoxelizeStats> run(std::span<const GpuInstance> instances, std::span<const VoxelizeMethod> methods,
                              const GridDesc& grid);
    /// Validates a call and picks each instance's path.
    Result<std::pmr::vector<VoxelizeMethod>> prepare(std::span<const GpuInstance> instances,
                                                     const GridDesc& grid, VoxelizeMethod method, float dt);
    /// Sizes the fragment list (first guess: the expected fragments of voxelize_work), the instance and
    /// the velocity buffers for a pass.
    Status ensure_pass(std::span<const GpuInstance> instances, const GridDesc& grid);
    /// A slab pass's buffers: the last list becomes the shift's source, the spare one the new list.
    Status ensure_slab_pass(std::span<const GpuInstance> instances, const GridDesc& grid);
    /// Records one pass (instance records, staged positions, the passes) into `cmd`; with `slabs` (the
    /// scroll in voxels) a slab pass, which first shifts the spare list into the new one.
    void record_pass(VkCommandBuffer cmd, std::span<const GpuInstance> instances,
                     std::span<const VoxelizeMethod> methods, const GridDesc& grid,
                     const glm::ivec3* slabs = nullptr);
    /// Records one pass (record_pass) with the skinning before it, submits it and waits, then its timings
    /// and counters into `stats` (take_counters).
    Status submit_pass(std::span<const GpuInstance> instances, std::span<const VoxelizeMethod> methods,
                       const GridDesc& grid, const glm::ivec3* slabs, VoxelizeStats& stats);
    /// Counters into `stats`; grows what overflowed. `capacity` and `large_capacity` are the pass's.
    Status take_counters(const shaderio::VoxelizeCounters& counters, std::uint64_t capacity,
                         std::uint64_t large_capacity, VoxelizeStats& stats);

    gpu::Context& ctx_;
    gpu::Pipeline raster_[2]; ///< [0]: without velocities, [1]: with
    gpu::Pipeline compute_small_[2];
    gpu::Pipeline compute_large_[2];
    gpu::Pipeline shift_;         ///< voxelize_shift.comp
    gpu::Pipeline skin_;          ///< skin.comp
    gpu::Profiler skin_profiler_; ///< the skinning pass ("skin"), recorded before the voxelize passes
    gpu::Profiler profiler_;
    gpu::Buffer fragments_;
    /// The list before the last slab pass (its source), reused as the next one's new list.
    gpu::Buffer spare_;
    gpu::Buffer source_count_; ///< uint: the fragments a slab pass's source holds, copied on the GPU
    gpu::Buffer counters_;
    gpu::Buffer large_list_;
    gpu::Buffer velocities_;
    gpu::Buffer instances_;
    float inv_dt_ = 0.0f;
    VoxelizeMethod method_ = VoxelizeMethod::Raster; ///< the last recorded pass's (record())
    std::uint64_t large_capacity_ = 0;
    std::uint64_t capacity_ = 0;
    std::uint64_t spare_capacity_ = 0;
    std::uint64_t fragment_count_ = 0;
};

/// Checks a grid: res in [kMinRes, kMaxRes], finite origin, finite voxel size > 0, and voxels no finer than
/// 2^-40 of the grid's largest coordinate (what OpenVDB's double transforms place).
Status validate_grid(const GridDesc& grid);

/// The grid docs/design.md uses when none is given: the box [lo, hi] made cubic about its centre and padded
/// by one voxel on every side (an empty or flat box gets a 1-unit edge).
GridDesc grid_around(glm::vec3 lo, glm::vec3 hi, std::uint32_t res);

/// Bounding box of the finite vertices that triangles of `mesh` reference; lo > hi when there are none.
std::pair<glm::vec3, glm::vec3> mesh_bounds(const MeshView& mesh);

} // namespace gust
