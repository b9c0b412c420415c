// System's state behind include/gust/gust.hpp: the scene the engine sets (meshes, instances, queries), the
// modules, and the Frame that records a step (frame.hpp). Shared by system.cpp and system_answers.cpp.
#pragma once

#include "frame.hpp"

#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <glm/gtc/type_ptr.hpp>
#include <map>
#include <memory>
#include <memory_resource>
#include <mutex>
#include <new>
#include <optional>
#include <string>

namespace gust::detail {

inline Outcome invalid(std::string message) {
    return Outcome(ErrorCode::InvalidArgument, std::move(message));
}
inline Outcome device_failure(const Status& s) {
    return Outcome(ErrorCode::DeviceFailure, s.message());
}
inline bool finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline glm::vec3 to_glm(const Vec3& v) {
    return {v.x, v.y, v.z};
}
inline Vec3 to_vec3(const glm::vec3& v) {
    return {v.x, v.y, v.z};
}
inline glm::mat4 to_glm(const Mat4& m) {
    return glm::make_mat4(m.m);
}

/// The most cells set_focus moves the focus at once (Frame::scroll_for refuses more in one step).
inline constexpr float kMaxFocusMoveCells = 1e6f;
/// Whether `focus` lies too far from the world's origin for cells of `h` m (kMaxFocusCells).
inline bool too_far_out(const glm::vec3& focus, float h) {
    return glm::any(glm::greaterThan(glm::abs(focus) / h, glm::vec3(kMaxFocusCells)));
}
inline constexpr const char* kTooFarOut =
    "is more than 2^19 cells from the world's origin, where floats "
    "cannot place voxels; move the world's origin nearer (origin rebasing)";

/// Host memory through Hooks::allocate/free (operator new without them).
class HookResource final : public std::pmr::memory_resource {
  public:
    explicit HookResource(const Hooks& hooks) : hooks_(hooks) {}

    /// Whether the hook has refused an allocation: Vulkan then fails with its own error (a failed
    /// vkCreateInstance read as an unsupported device), which this tells apart.
    bool ran_out() const { return ran_out_; }

  private:
    void* do_allocate(std::size_t bytes, std::size_t alignment) override {
        if (!hooks_.allocate) return ::operator new(bytes, std::align_val_t(alignment));
        void* memory = hooks_.allocate(hooks_.user, bytes, alignment);
        if (!memory) {
            ran_out_ = true;
            throw std::bad_alloc();
        }
        return memory;
    }
    void do_deallocate(void* memory, std::size_t bytes, std::size_t alignment) override {
        if (!hooks_.allocate) return ::operator delete(memory, bytes, std::align_val_t(alignment));
        hooks_.free(hooks_.user, memory);
    }
    bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
        return this == &other;
    }

    Hooks hooks_;
    bool ran_out_ = false;
};

/// Runs `body`, turning an exception from below (allocation) into an error: none crosses the API.
template <class F> Outcome guarded(F&& body) {
    try {
        return body();
    } catch (const std::bad_alloc&) {
        return Outcome(ErrorCode::DeviceFailure, "out of host memory");
    } catch (const std::exception& e) {
        return Outcome(ErrorCode::DeviceFailure, e.what());
    }
}

} // namespace gust::detail

namespace gust {

struct System::Impl {
    explicit Impl(const Hooks& h)
        : hooks(h), memory(h), coarse_worlds(&memory), coarse_solvers(&memory), exported(&memory),
          meshes(&memory), instances(&memory),
          queries(&memory), stats{.nodes_per_level = FrameStats::Counts(&memory),
                                  .ms = FrameStats::Timings(&memory)},
          slots(&memory), blocking(&memory) {}

    Hooks hooks;
    detail::HookResource memory;
    std::unique_ptr<gpu::Context> ctx;
    SolverDesc solver_desc;
    Submission submission = Submission::OwnQueue;
    std::unique_ptr<VoxelWorld> world;
    std::unique_ptr<WindSolver> solver;
    /// WindDomain::cascades: the cascades beyond the finest (`world`, `solver`), next coarser first.
    std::pmr::vector<std::unique_ptr<VoxelWorld>> coarse_worlds;
    std::pmr::vector<std::unique_ptr<WindSolver>> coarse_solvers;
    std::optional<detail::Frame> frame; ///< in the System's own block: no allocation of its own
    /// SystemDesc::exported_copies: copy s of cascade k at [k * copies + s], in exportable memory.
    std::pmr::vector<gpu::Image> exported;
    std::uint32_t exported_copies = 0;

    struct Mesh {
        GpuMesh gpu;
        bool deforming = false;
        std::uint32_t instances = 0;
        bool teleport = false; ///< the vertices set since the last step jumped (set_vertices)
    };
    struct Instance {
        MeshId mesh = 0;
        glm::mat4 model{1.0f};
        std::optional<glm::mat4> prev;
        bool dynamic = false;  ///< moving, or of a deforming mesh: voxelized every frame
        bool teleport = false; ///< the transform set since the last step jumped (set_transform)
    };
    struct Pending {
        explicit Pending(std::pmr::memory_resource* memory) : points(memory), answer(memory) {}
        std::pmr::vector<glm::vec3> points;
        std::pmr::vector<glm::vec3> answer;
        bool ready = false;
        bool asked = false;         ///< recorded into a frame, answered when it completes
        std::uint64_t answered = 0; ///< the frame whose stats brought the answer
    };
    std::pmr::map<MeshId, Mesh> meshes;
    std::pmr::map<InstanceId, Instance> instances;
    std::pmr::map<QueryId, Pending> queries;
    std::uint64_t next_id = 1;
    glm::vec3 focus{0.0f};
    /// The static instances changed since a step last handed them to the world; an unchanged static set
    /// then costs no list and no comparison per frame.
    bool static_dirty = true;

    FrameStats stats;
    mutable std::mutex stats_mutex; ///< held while a frame's stats are stored, and by read_stats
    std::optional<detail::SnapshotRing> snapshot; ///< SystemDesc::snapshot
    std::atomic<bool> writing{false};             ///< a thread is inside a writer call
    std::pmr::vector<detail::FrameSlot> slots;    ///< HostCommands: one per frame in flight
    detail::FrameSlot blocking; ///< OwnQueue: the frame step(dt) records, submits and waits for
    /// Whether a step failed on the device or the host's memory part-way through, and why (cut to fit): the
    /// System's state is not known after that, so later steps refuse to run (never a frame of wrong wind).
    /// Kept without allocating, since memory may be what ran out.
    bool failed = false;
    std::array<char, 256> failure{};

    ~Impl() {
        if (!ctx) return;
        // Frames recorded into the host's command buffers may still run on what is destroyed below.
        ctx->wait_idle();
        frame.reset();
        // SystemDesc::pipeline_cache: the cache only saves time, so failing to write it fails nothing.
        static_cast<void>(ctx->save_pipeline_cache());
    }

    void log(LogLevel level, const std::string& message) const {
        if (hooks.log) hooks.log(hooks.user, level, message.c_str());
    }
    Outcome check(bool condition, const char* expression, int line) const {
        if (condition) return {};
        if (hooks.assert_failed) hooks.assert_failed(hooks.user, expression, __FILE__, line);
        return Outcome(ErrorCode::DeviceFailure, std::string("internal check failed: ") + expression);
    }

    /// Records one frame into `commands` through `slot` from the scene as set; advances the scene's
    /// per-step state (previous transforms, teleports, asked queries) only once the frame is recorded.
    Outcome record(VkCommandBuffer commands, float dt, detail::FrameSlot& slot);
    /// Reads a completed frame's slot: stats (with `work`, the frame's GPU work) and async answers.
    Outcome collect(detail::FrameSlot& slot, const gpu::WorkCounts& work);
    /// Keeps a step's DeviceFailure in `failure`; returns the step's outcome.
    Outcome remember(Outcome stepped);
    /// DeviceFailure once a step has failed part-way (`failure`), else success.
    Outcome refuse_after_failure() const;

    /// query() without the writer flag (wind_at's points).
    Outcome query(std::span<const Vec3> points, std::span<Vec3> velocities, WindReading reading);

    /// create_instance() and create_moving_instance(): `previous` (or null) is the transform one step before.
    Outcome add_instance(MeshId mesh, const Mat4& transform, const Mat4* previous, bool moving,
                         InstanceId& id);

    /// The mesh `id`, or null with `error` set.
    Mesh* find_mesh(MeshId id, Outcome& error) {
        auto it = meshes.find(id);
        if (it != meshes.end()) return &it->second;
        error = Outcome(ErrorCode::InvalidHandle, "no mesh " + std::to_string(id));
        return nullptr;
    }
    /// The deforming mesh `id` of `vertex_count` vertices, or null with `error` set.
    Mesh* find_deforming(MeshId id, std::uint32_t vertex_count, Outcome& error) {
        Mesh* m = find_mesh(id, error);
        if (!m) return nullptr;
        if (!m->deforming)
            error = detail::invalid("mesh " + std::to_string(id) + " was not created as deforming");
        else if (vertex_count != m->gpu.vertex_count())
            error = detail::invalid("got " + std::to_string(vertex_count) + " vertices for a mesh of " +
                                    std::to_string(m->gpu.vertex_count()));
        return error ? m : nullptr;
    }
};

/// SystemDesc::exported_copies: creates `copies` exportable images per cascade, the size and format of its
/// wind texture (system_share.cpp).
Outcome create_exported(System::Impl& m, std::uint32_t copies);

/// Marks a writer call for its duration; fails (ErrorCode::Busy) when another thread is inside one.
class WriterCall {
  public:
    explicit WriterCall(System::Impl& impl) : flag_(impl.writing), owned_(!flag_.exchange(true)) {}
    ~WriterCall() {
        if (owned_) flag_.store(false);
    }
    WriterCall(const WriterCall&) = delete;
    WriterCall& operator=(const WriterCall&) = delete;
    explicit operator bool() const { return owned_; }
    static Outcome busy(const char* call) {
        return Outcome(ErrorCode::Busy, std::string(call) +
                                            ": another thread is inside a writer call of this System "
                                            "(one writer at a time; gust.hpp, \"Threading\")");
    }

  private:
    std::atomic<bool>& flag_;
    bool owned_;
};

} // namespace gust
