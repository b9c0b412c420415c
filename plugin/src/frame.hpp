// One frame of docs/design.md ("One frame"): what a step records into a command buffer, in order, and what
// it brings back once the GPU has run it. System (system.cpp) is the API shell around it.
#pragma once

#include "snapshot.hpp"

#include <array>
#include <cstdint>
#include <gust/gpu/context.hpp>
#include <gust/gpu/image.hpp>
#include <gust/gpu/profiler.hpp>
#include <gust/gust.hpp>
#include <gust/solver/wind_solver.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <memory_resource>
#include <optional>
#include <span>
#include <vector>

namespace gust::detail {

/// Where a frame's results lie in its readback buffer: the voxel world's counters, the solver's, then one
/// vec3 answer per async query point. The one place this layout is put together.
struct ReadbackLayout {
    static constexpr std::size_t world = 0;
    static std::size_t wind() { return world + VoxelWorld::readback_bytes(); }
    /// The counters of the coarser cascade the frame stepped, if any (FrameSlot::cascade).
    static std::size_t cascade_world() { return wind() + WindSolver::readback_bytes(); }
    static std::size_t cascade_wind() { return cascade_world() + VoxelWorld::readback_bytes(); }
    static std::size_t answers() { return (cascade_wind() + WindSolver::readback_bytes() + 15) / 16 * 16; }
    /// Bytes for a frame asking `points` points (at least one, so the buffer always exists).
    static std::size_t bytes(std::size_t points) {
        return answers() + (points > 0 ? points : 1) * 3 * sizeof(float);
    }
};

/// What the engine set for the frame, gathered by System without changing its own state.
struct FrameInputs {
    float dt = 0.0f;                      ///< seconds, checked by System
    glm::vec3 focus{0.0f};                ///< where the cascades centre (the coarser ones scroll to it)
    glm::ivec3 shift{0};                  ///< whole cells the domain moves (Frame::scroll_for)
    std::span<const GpuInstance> dynamic; ///< moving and deforming instances, with their last transforms
    const std::pmr::vector<GpuInstance>* fixed = nullptr; ///< the static set when it changed, else null
    std::span<const glm::vec3> points; ///< async query points asked since the last frame, in order
};

/// Per-frame storage a recorded frame's results come back through (HostCommands: one per frame in flight,
/// used again once that frame has completed).
struct FrameSlot {
    explicit FrameSlot(std::pmr::memory_resource* memory) : asked(memory) {}
    gpu::Buffer readback;            ///< ReadbackLayout
    gpu::Buffer points;              ///< the async query points the frame samples
    std::pmr::vector<QueryId> asked; ///< the queries whose points the frame samples, in order
    bool used = false;               ///< a recorded frame's results wait here
    std::uint64_t frame = 0;         ///< the frame they belong to (gpu::Context::begin_frame)
    std::uint64_t dispatches = 0;    ///< dispatches and draws the frame recorded
    std::uint64_t stages = 0;        ///< its dependent stages (gpu::WorkCounts::stages)
    /// The coarser cascade (index into Frame's, from 0 for cascade 1) the frame also stepped; -1: none.
    int cascade = -1;
    /// SystemDesc::snapshot: every cascade's wind texels (8 bytes a cell, finest first), and where each
    /// cascade stood.
    gpu::Buffer snapshot;
    bool snapshot_recorded = false;
    std::array<glm::vec3, kMaxCascades> snapshot_origins{};
    glm::vec3 snapshot_ambient{0.0f};
    std::uint64_t snapshot_frame = 0;
};

/// A coarser cascade of the nest (docs/solver.md "Cascades"): its voxel world and solver (owned by System),
/// and when it steps: every `period` frames, ahead of the finest cascade by up to a period, so that the finer
/// cascades read its wind between its last two steps.
struct Cascade {
    VoxelWorld* world = nullptr;
    WindSolver* solver = nullptr;
    std::uint32_t period = 1; ///< frames between its steps: ratio^k for cascade k
    std::uint32_t waited =
        0;               ///< frames since its last step (period − 1 at first: it steps in the first frame)
    double before = 0.0; ///< s: the time its field stood at before its last step (the kept field)
    double ahead = 0.0;  ///< s: the time its last step reached
    bool static_stale = true; ///< the static set changed since it last took it
    float voxel_size = 0.0f;  ///< m: a moving instance smaller than this is not voxelized into it
};

/// One cascade's wind texture: its solver's last pass writes the texels, a copy puts them into the image.
struct CascadeTexture {
    gpu::Buffer texels;
    gpu::Image image;
};

/// Records frames and collects them. Owns a wind texture per cascade (the texels are written by each
/// step's last pass) and the frame counter; the domain's position is the solver's, which the frame
/// scrolls and the voxel grid follows.
class Frame {
  public:
    /// `hooks` (for the log) and the modules outlive the Frame.
    /// `coarser`: the cascades beyond the finest (`world`, `solver`), next coarser first; the Frame steps at
    /// most one of them a frame, the most overdue, before the finest.
    Frame(gpu::Context& ctx, VoxelWorld& world, WindSolver& solver, std::pmr::vector<Cascade> coarser,
          const Hooks& hooks)
        : ctx_(&ctx), world_(&world), solver_(&solver), coarser_(std::move(coarser)), hooks_(&hooks),
          static_set_(coarser_.get_allocator()), moving_(coarser_.get_allocator()),
          textures_(coarser_.get_allocator()), published_(coarser_.get_allocator()) {}
    ~Frame();
    Frame(const Frame&) = delete;
    Frame& operator=(const Frame&) = delete;

    /// Creates every cascade's wind texture, fills it from its solver's field and binds its texels to every
    /// step of that solver.
    Outcome create_textures();

    /// The world's origin moved (System::shift_origin): the next frame first records every cascade's
    /// bindings, so that none reads a neighbour's old origin.
    void origin_shifted() { rebind_ = true; }

    /// SystemDesc::snapshot: from now on every frame copies every cascade's texels into its slot, and
    /// collect publishes them into `ring` (which outlives the Frame).
    void enable_snapshot(SnapshotRing& ring) { snapshot_ = &ring; }
    /// Cells of every cascade together: what a snapshot holds.
    std::size_t snapshot_cells() const;

    /// Whole cells the finest cascade must move to centre on `focus`; fails when that is too far for one
    /// step.
    Outcome scroll_for(glm::vec3 focus, glm::ivec3& cells) const {
        return scroll_for(*solver_, focus, cells);
    }

    /// Records a whole frame into `cmd`: inputs, scroll, voxelize, tree, solid, wind (its last pass writes
    /// the texels), outputs (texture copy, async queries), the counters' readback into `slot`. Nothing on
    /// the host advances unless it returns success.
    Outcome record(VkCommandBuffer cmd, const FrameInputs& in, FrameSlot& slot);

    /// Reads a completed frame's slot into `stats` (with `work`, the frame's GPU work counts) and points
    /// `answers` at its async answers, in the order of `slot.asked` (valid until the slot is used again).
    /// The world grows what ran out for the frames recorded later.
    Outcome collect(const FrameSlot& slot, const gpu::WorkCounts& work, FrameStats& stats,
                    const glm::vec3*& answers);

    /// SystemDesc::snapshot: publishes a completed frame's texels (after collect) for System::sample.
    void publish_snapshot(const FrameSlot& slot);

    /// System::set_dispatch_timing: from the next frame recorded, every dispatch and draw is timed apart and
    /// collect puts those times into FrameStats::ms in place of the passes'.
    Outcome time_dispatches(bool on);
    /// Every cascade's wind texture, finest first.
    std::span<const WindTexture> textures() const { return published_; }
    /// Cascade k's texels as its last step wrote them (the contents of its texture once a frame completed).
    const gpu::Buffer& texels(std::size_t k) const { return textures_[k].texels; }
    /// Frames recorded so far.
    std::uint64_t recorded() const { return recorded_; }

  private:
    static Outcome scroll_for(const WindSolver& solver, glm::vec3 focus, glm::ivec3& cells);
    /// The coarser cascade whose turn it is this frame (null: none), every cascade's count advanced.
    Cascade* next_cascade();
    /// Records the coarser cascade `c`'s scroll, voxels and step into `cmd`, its counters into `slot`.
    Outcome record_cascade(VkCommandBuffer cmd, const FrameInputs& in, Cascade& c, FrameSlot& slot);
    /// Cascade k's solver (0: the finest).
    WindSolver& solver(std::size_t k) const { return k == 0 ? *solver_ : *coarser_[k - 1].solver; }
    void record_texture_copy(VkCommandBuffer cmd, std::size_t k);
    /// Cascade k's texture as its grid stands now; `stepped`: its texels were written by this frame.
    void publish_texture(std::size_t k, bool stepped);
    void stats_from(const WorldFrame& world, const WindStats& wind, const gpu::WorkCounts& work,
                    FrameStats& stats) const;
    void log(LogLevel level, const std::string& message) const;

    gpu::Context* ctx_;
    VoxelWorld* world_;
    WindSolver* solver_;
    std::pmr::vector<Cascade> coarser_;
    const Hooks* hooks_;
    /// The static set as last handed over, for the coarser cascades that take it at their next step, and
    /// the moving instances large enough for the cascade a frame steps.
    std::pmr::vector<GpuInstance> static_set_, moving_;
    bool rebind_ = false;
    std::pmr::vector<CascadeTexture> textures_; ///< finest first
    std::pmr::vector<WindTexture> published_;   ///< what the host reads, finest first
    VkSampler sampler_ = VK_NULL_HANDLE;
    std::uint64_t recorded_ = 0;
    double time_ = 0.0; ///< s: the finest cascade's time, the sum of the frames' dt
    SnapshotRing* snapshot_ = nullptr;
    /// Dispatches and draws timed a frame at most: more than the largest frame records (about 200, the
    /// first frame of 4 cascades); the rest go untimed.
    static constexpr std::uint32_t kTimedDispatches = 512;
    std::optional<gpu::Profiler> dispatch_profiler_; ///< time_dispatches(true)
};

} // namespace gust::detail
