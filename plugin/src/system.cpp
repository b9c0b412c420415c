// gust::System: one frame of docs/design.md ("One frame") over the voxel world and the wind solver, behind
// the engine-facing API of include/gust/gust.hpp.
#include "tree/tree_io.h"
#if GUST_WITH_OPENVDB
#include "vdb_writer.hpp"
#endif

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <exception>
#include <glm/gtc/type_ptr.hpp>
#include <gust/gpu/context.hpp>
#include <gust/gpu/image.hpp>
#include <gust/gust.hpp>
#include <gust/solver/wind_solver.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <map>
#include <memory_resource>
#include <new>
#include <optional>

namespace gust {

static_assert(kVersionMajor == GUST_PACKAGE_VERSION_MAJOR && kVersionMinor == GUST_PACKAGE_VERSION_MINOR,
              "gust.hpp's version and project(gust VERSION ...) differ");

std::uint32_t library_version() {
    return kHeaderVersion;
}

namespace {

Outcome invalid(std::string message) {
    return Outcome(ErrorCode::InvalidArgument, std::move(message));
}
/// Frames an answer of query_async waits to be fetched before it is dropped.
constexpr std::uint64_t kKeepAnswers = 64;

/// The most cells set_focus moves the focus at once.
constexpr float kMaxFocusMoveCells = 1e6f;
/// Whether `focus` lies too far from the world's origin for cells of `h` m (kMaxFocusCells).
bool too_far_out(const glm::vec3& focus, float h) {
    return glm::any(glm::greaterThan(glm::abs(focus) / h, glm::vec3(kMaxFocusCells)));
}

const char* const kTooFarOut = "is more than 2^19 cells from the world's origin, where floats cannot place "
                               "voxels; move the world's origin nearer (origin rebasing)";

Outcome device_failure(const Status& s) {
    return Outcome(ErrorCode::DeviceFailure, s.message());
}

bool finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const Mat4& m) {
    for (float f : m.m)
        if (!std::isfinite(f)) return false;
    return true;
}
/// Finite and affine: the last row is (0, 0, 0, 1). A projective matrix would voxelize a distorted mesh.
Outcome check_transform(const Mat4& m, const char* name) {
    if (!finite(m)) return invalid(std::string(name) + " must be finite");
    if (m.m[3] != 0.0f || m.m[7] != 0.0f || m.m[11] != 0.0f || m.m[15] != 1.0f)
        return invalid(std::string(name) +
                       " must be affine: its last row (m[3], m[7], m[11], m[15]) must be 0, "
                       "0, 0, 1");
    return {};
}
glm::vec3 to_glm(const Vec3& v) {
    return {v.x, v.y, v.z};
}
Vec3 to_vec3(const glm::vec3& v) {
    return {v.x, v.y, v.z};
}
glm::mat4 to_glm(const Mat4& m) {
    return glm::make_mat4(m.m);
}

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

} // namespace

struct System::Impl {
    explicit Impl(const Hooks& h)
        : hooks(h), memory(h), meshes(&memory), instances(&memory),
          queries(&memory), stats{.nodes_per_level = FrameStats::Counts(&memory),
                                  .ms = FrameStats::Timings(&memory)},
          slots(&memory), blocking(&memory) {}

    Hooks hooks;
    HookResource memory;
    std::unique_ptr<gpu::Context> ctx;
    SolverDesc solver_desc;
    std::uint32_t branching = 4;
    Submission submission = Submission::OwnQueue;
    std::unique_ptr<VoxelWorld> world;
    std::unique_ptr<WindSolver> solver;

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
        bool asked = false;         ///< HostCommands: recorded into a frame, answered when it completes
        std::uint64_t answered = 0; ///< the frame whose stats brought the answer
    };
    std::pmr::map<MeshId, Mesh> meshes;
    std::pmr::map<InstanceId, Instance> instances;
    std::pmr::map<QueryId, Pending> queries;
    std::uint64_t next_id = 1;
    glm::vec3 focus{0.0f};
    /// The static instances changed since step() last handed them to the world; an unchanged static set
    /// then costs no list and no comparison per frame.
    bool static_dirty = true;

    gpu::Buffer texels;
    gpu::Image image;
    VkSampler sampler = VK_NULL_HANDLE;
    WindTexture texture;
    FrameStats stats;
    std::uint64_t frame = 0;
    /// Whether a step failed on the device or the host's memory part-way through, and why (cut to fit): the
    /// System's state is not known after that, so later steps refuse to run (never a frame of wrong wind).
    /// Kept without allocating, since memory may be what ran out.
    bool failed = false;
    std::array<char, 256> failure{};

    ~Impl() {
        if (!ctx) return;
        // Frames recorded into the host's command buffers may still run on what is destroyed below.
        ctx->wait_idle();
        if (sampler) ctx->vk().vkDestroySampler(ctx->device(), sampler, ctx->allocator());
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

    glm::mat4 world_to_texture() const {
        const glm::vec3 size = glm::vec3(solver_desc.cells) * solver_desc.cell_size;
        const glm::vec3 origin = solver->origin();
        glm::mat4 m(1.0f);
        for (int a = 0; a < 3; ++a) {
            m[a][a] = 1.0f / size[a];
            m[3][a] = -origin[a] / size[a];
        }
        return m;
    }
    /// Writes the wind texture from the field (blocking) and publishes its transform.
    Outcome refresh_texture();
    /// Records the copy of the texels into the texture, leaving it readable by shaders.
    void record_texture_copy(VkCommandBuffer cmd);
    /// The texture's transform and frame as of the last step.
    void publish_texture();

    /// Whole cells the domain moves this step to follow the focus into `cells`; fails when the focus
    /// moved too far in one step to follow.
    Outcome scroll_cells(glm::ivec3& cells) const;
    /// This step's dynamic instances (their last transforms become the previous ones); hands a changed
    /// static set to the world.
    std::pmr::vector<GpuInstance> frame_instances();
    /// Stats from a finished frame.
    void take_stats(const WorldFrame& frame, const WindStats& wind, const gpu::WorkCounts& work);

    /// A recorded frame's counters and async answers come back here (HostCommands: one per frame in flight).
    struct Slot {
        explicit Slot(std::pmr::memory_resource* memory) : asked(memory) {}
        gpu::Buffer readback; ///< world counters, solver counters, then answers at answers_offset()
        gpu::Buffer points;   ///< async query points asked in the frame
        std::pmr::vector<QueryId> asked;
        bool used = false;            ///< a recorded frame's results wait here
        std::uint64_t frame = 0;      ///< the frame they belong to (gpu::Context::begin_frame)
        std::uint64_t dispatches = 0; ///< dispatches and draws the frame recorded
    };
    std::pmr::vector<Slot> slots;
    Slot blocking; ///< OwnQueue: the frame step(dt) records, submits and waits for
    static std::size_t answers_offset();
    /// Records a whole frame into `commands` (scroll by `shift`, uploads, voxelize, tree, solid, wind,
    /// texture, async queries, the counters' readback into `slot`): the one path both kinds of step take.
    Outcome record_frame(VkCommandBuffer commands, float dt, glm::ivec3 shift, Slot& slot);
    /// Reads a completed frame's slot: stats (with `work`, the frame's GPU work), async answers, growth
    /// for later frames.
    Outcome collect(Slot& slot, const gpu::WorkCounts& work);
    /// Keeps a step's DeviceFailure in `failure`; returns the step's outcome.
    Outcome remember(Outcome stepped);
    /// DeviceFailure once a step has failed part-way (`failure`), else success.
    Outcome refuse_after_failure() const;

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
            error = invalid("mesh " + std::to_string(id) + " was not created as deforming");
        else if (vertex_count != m->gpu.vertex_count())
            error = invalid("got " + std::to_string(vertex_count) + " vertices for a mesh of " +
                            std::to_string(m->gpu.vertex_count()));
        return error ? m : nullptr;
    }
};

namespace {

// `hooks` and `memory` belong to the System and outlive the Context.
Outcome create_context(const SystemDesc& desc, const Hooks& hooks, std::pmr::memory_resource* memory,
                       std::unique_ptr<gpu::Context>& out) {
    gpu::MessageCallback on_message;
    if (hooks.log)
        on_message = [&hooks](gpu::Severity severity, const std::string& message) {
            const LogLevel level = severity == gpu::Severity::Error     ? LogLevel::Error
                                   : severity == gpu::Severity::Warning ? LogLevel::Warning
                                                                        : LogLevel::Info;
            hooks.log(hooks.user, level, message.c_str());
        };
    if (desc.host) {
        const HostDevice& h = *desc.host;
        if (!h.instance || !h.physical_device || !h.device || !h.get_instance_proc_addr)
            return invalid(
                "host: instance, physical_device, device and get_instance_proc_addr must not be null");
        gpu::HostDevice host;
        host.instance = h.instance;
        host.physical_device = h.physical_device;
        host.device = h.device;
        host.queue_family = h.queue_family;
        host.queue_index = h.queue_index;
        host.get_instance_proc_addr = h.get_instance_proc_addr;
        host.get_device_proc_addr = h.get_device_proc_addr;
        host.enabled_extensions = h.enabled_extensions;
        host.debug_utils = h.debug_utils;
        host.memory = memory;
        auto ctx = gpu::Context::adopt(host);
        if (!ctx) return Outcome(ErrorCode::DeviceUnsupported, ctx.message());
        out = std::move(*ctx);
        return {};
    }
    gpu::ContextDesc own;
    own.validation = desc.validation;
    own.device = desc.device ? desc.device : "";
    own.on_message = on_message;
    own.memory = memory;
    if (desc.pipeline_cache) own.pipeline_cache = desc.pipeline_cache;
    auto ctx = gpu::Context::create(own);
    if (!ctx) return Outcome(ErrorCode::DeviceUnsupported, ctx.message());
    out = std::move(*ctx);
    return {};
}

Outcome solver_desc_from(const SystemDesc& desc, SolverDesc& out) {
    const WindDomain& d = desc.domain;
    out.cells = {d.cells[0], d.cells[1], d.cells[2]};
    out.cell_size = d.cell_size;
    out.voxels_per_cell = d.voxels_per_cell;
    out.tolerance = desc.wind.tolerance;
    out.max_cycles = desc.wind.max_cycles;
    out.cycles_per_step = desc.wind.cycles_per_step;
    out.vorticity = desc.wind.vorticity;
    out.viscosity = desc.wind.viscosity;
    out.max_solid_speed = desc.wind.max_solid_speed;
    out.max_iterations = desc.wind.max_iterations;
    switch (desc.wind.advection) {
    case WindAdvection::MacCormack:
        out.advection = Advection::MacCormack;
        break;
    case WindAdvection::SemiLagrangian:
        out.advection = Advection::SemiLagrangian;
        break;
    case WindAdvection::None:
        out.advection = Advection::None;
        break;
    default:
        return invalid("wind.advection must be MacCormack, SemiLagrangian or None");
    }
    switch (desc.wind.pressure) {
    case WindPressure::MultigridPCG:
        out.pressure = PressureSolver::MultigridPCG;
        break;
    case WindPressure::Multigrid:
        out.pressure = PressureSolver::Multigrid;
        break;
    case WindPressure::Jacobi:
        out.pressure = PressureSolver::Jacobi;
        break;
    default:
        return invalid("wind.pressure must be MultigridPCG, Multigrid or Jacobi");
    }
    if (!finite(d.focus)) return invalid("domain.focus must be finite");
    if (!std::isfinite(d.cell_size) || !(d.cell_size >= kMinVoxelSize * float(d.voxels_per_cell)) ||
        d.cell_size > kMaxCellSize)
        return invalid("domain.cell_size must be from 1e-4 m x voxels_per_cell to 1000 m, got " +
                       std::to_string(d.cell_size));
    if (too_far_out(to_glm(d.focus), d.cell_size)) return invalid(std::string("domain.focus ") + kTooFarOut);
    out.origin = to_glm(d.focus) - 0.5f * glm::vec3(out.cells) * d.cell_size;
    if (Status s = validate(out); !s) return invalid(s.message());
    return {};
}

} // namespace

DeviceRequirements device_requirements() {
    const gpu::DeviceRequirements r = gpu::device_requirements();
    DeviceRequirements out;
    out.api_version = r.api_version;
    out.extensions = r.extensions;
    out.optional_extensions = r.optional_extensions;
    out.features = r.features;
    return out;
}

Outcome add_required_features(VkPhysicalDeviceFeatures2& features) {
    if (Status s = gpu::add_required_features(features); !s) return invalid(s.message());
    return {};
}

Outcome System::create(const SystemDesc& desc, std::unique_ptr<System>& out) {
    out.reset();
    const auto major_minor = [](std::uint32_t v) { return v >> 12; };
    if (major_minor(desc.header_version) != major_minor(kHeaderVersion))
        return Outcome(ErrorCode::VersionMismatch,
                       "the header is version " + std::to_string(desc.header_version >> 22) + "." +
                           std::to_string((desc.header_version >> 12) & 0x3ff) + ", the library " +
                           std::to_string(kVersionMajor) + "." + std::to_string(kVersionMinor));
    if ((desc.hooks.allocate == nullptr) != (desc.hooks.free == nullptr))
        return invalid("hooks.allocate and hooks.free must be given together");
    if (desc.submission != Submission::OwnQueue && desc.submission != Submission::HostCommands)
        return invalid("submission must be OwnQueue or HostCommands");
    if (int(desc.voxelize) < 0 || int(desc.voxelize) > int(VoxelizePath::Compute))
        return invalid("voxelize must be Auto, Raster or Compute");
    if (desc.submission == Submission::HostCommands && !desc.host)
        return invalid("submission HostCommands needs a host device");
    if (desc.submission == Submission::HostCommands &&
        (desc.frames_in_flight < 1 || desc.frames_in_flight > 8))
        return invalid("frames_in_flight must be 1..8, got " + std::to_string(desc.frames_in_flight));
    SolverDesc solver_desc;
    if (Outcome o = solver_desc_from(desc, solver_desc); !o) return o;
    const std::uint32_t b = desc.domain.branching;
    if (b != 2 && b != 4 && b != 8) return invalid("domain.branching must be 2, 4 or 8");

    return guarded([&]() -> Outcome {
        // The System first, so that a failed allocation of either frees what came before.
        std::unique_ptr<System> system(new (desc.hooks) System());
        HookResource memory(desc.hooks);
        void* place = memory.allocate(sizeof(Impl), alignof(Impl));
        try {
            system->impl_ = new (place) Impl(desc.hooks);
        } catch (...) {
            memory.deallocate(place, sizeof(Impl), alignof(Impl));
            throw;
        }
        Impl& m = *system->impl_;
        m.solver_desc = solver_desc;
        m.branching = b;
        m.submission = desc.submission;
        m.focus = to_glm(desc.domain.focus);
        // Without an allocate hook Vulkan keeps the driver's own allocator.
        std::pmr::memory_resource* hooked = desc.hooks.allocate ? &m.memory : nullptr;
        if (Outcome o = create_context(desc, m.hooks, hooked, m.ctx); !o)
            return m.memory.ran_out()
                       ? Outcome(ErrorCode::DeviceFailure, "out of host memory: " + o.message())
                       : o;

        auto grid = voxel_grid(solver_desc, b);
        if (!grid) return invalid(grid.message());
        WorldDesc world_desc;
        world_desc.grid = *grid;
        world_desc.tree.branching = b;
        world_desc.tree.hysteresis = desc.domain.hysteresis;
        world_desc.method = desc.voxelize == VoxelizePath::Raster    ? VoxelizeMethod::Raster
                            : desc.voxelize == VoxelizePath::Compute ? VoxelizeMethod::Compute
                                                                     : VoxelizeMethod::Auto;
        auto world = VoxelWorld::create(*m.ctx, world_desc);
        if (!world) return device_failure(world.status());
        m.world = std::move(*world);
        auto solver = WindSolver::create(*m.ctx, solver_desc);
        if (!solver) return device_failure(solver.status());
        m.solver = std::move(*solver);

        const std::size_t cells = m.solver->cell_count();
        auto texels = gpu::Buffer::create(*m.ctx, cells * 8, gpu::MemoryUse::Device);
        if (!texels) return device_failure(texels.status());
        m.texels = std::move(*texels);
        gpu::ImageDesc image;
        image.extent = {solver_desc.cells.x, solver_desc.cells.y, solver_desc.cells.z};
        image.format = VK_FORMAT_R16G16B16A16_SFLOAT;
        // Sampled by the engine, written by gust's copy, and copied out by an engine that exports or
        // captures it.
        image.usage =
            VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
        image.volume = true;
        auto created = gpu::Image::create(*m.ctx, image);
        if (!created) return device_failure(created.status());
        m.image = std::move(*created);
        VkSamplerCreateInfo sampler{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
        sampler.magFilter = sampler.minFilter = VK_FILTER_LINEAR;
        sampler.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
        sampler.addressModeU = sampler.addressModeV = sampler.addressModeW =
            VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        if (m.ctx->vk().vkCreateSampler(m.ctx->device(), &sampler, m.ctx->allocator(), &m.sampler) !=
            VK_SUCCESS)
            return Outcome(ErrorCode::DeviceFailure, "vkCreateSampler failed");
        m.texture.image = m.image.handle();
        m.texture.view = m.image.view();
        m.texture.sampler = m.sampler;
        m.texture.format = m.image.format();
        for (int a = 0; a < 3; ++a)
            m.texture.extent[a] = solver_desc.cells[a];
        if (Outcome o = m.refresh_texture(); !o) return o;
        if (desc.submission == Submission::HostCommands)
            for (std::uint32_t i = 0; i < desc.frames_in_flight; ++i)
                m.slots.emplace_back(&m.memory);
        out = std::move(system);
        return {};
    });
}

namespace {
/// What precedes a System in its block: the hooks that allocated it, for operator delete.
struct alignas(std::max_align_t) SystemHeader {
    Hooks hooks;
};
} // namespace

void* System::operator new(std::size_t bytes, const Hooks& hooks) {
    HookResource memory(hooks);
    auto* block =
        static_cast<std::byte*>(memory.allocate(sizeof(SystemHeader) + bytes, alignof(SystemHeader)));
    new (block) SystemHeader{hooks};
    return block + sizeof(SystemHeader);
}

// Not inlined: GCC would otherwise pair System::operator new with the ::operator delete it forwards to
// and warn of a mismatch.
[[gnu::noinline]] void System::operator delete(void* system) noexcept {
    if (!system) return;
    auto* block = static_cast<std::byte*>(system) - sizeof(SystemHeader);
    HookResource memory(std::launder(reinterpret_cast<SystemHeader*>(block))->hooks);
    memory.deallocate(block, sizeof(SystemHeader) + sizeof(System), alignof(SystemHeader));
}

void System::operator delete(void* system, const Hooks&) noexcept {
    operator delete(system);
}

System::~System() {
    if (!impl_) return;
    const Hooks hooks = impl_->hooks;
    impl_->~Impl();
    HookResource memory(hooks);
    memory.deallocate(impl_, sizeof(Impl), alignof(Impl));
}

Outcome System::Impl::refresh_texture() {
    Status s = solver->write_texels(texels, [&](VkCommandBuffer cmd) { record_texture_copy(cmd); });
    if (!s) return device_failure(s);
    publish_texture();
    return {};
}

void System::Impl::record_texture_copy(VkCommandBuffer cmd) {
    image.transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    image.copy_from(cmd, texels);
    image.transition(cmd, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
}

void System::Impl::publish_texture() {
    const glm::mat4 w = world_to_texture();
    std::memcpy(texture.world_to_texture.m, glm::value_ptr(w), sizeof(texture.world_to_texture.m));
    texture.frame = frame;
}

Outcome System::create_mesh(const MeshDesc& desc, MeshId& id) {
    id = 0;
    if (desc.vertex_count > 0 && !desc.positions) return invalid("positions is null");
    if (desc.index_count > 0 && !desc.indices) return invalid("indices is null");
    if (desc.stride < 12)
        return invalid("stride must be at least 12 bytes, got " + std::to_string(desc.stride));
    const MeshView view{desc.positions, desc.vertex_count, desc.stride, desc.indices, desc.index_count};
    for (std::uint32_t v = 0; v < desc.vertex_count; ++v) {
        const glm::vec3 p = view.position(v);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return invalid("vertex " + std::to_string(v) + " is not finite");
    }
    return guarded([&]() -> Outcome {
        auto mesh = impl_->world->upload(view);
        if (!mesh) return invalid(mesh.message());
        const MeshId next = impl_->next_id++;
        impl_->meshes.emplace(next, Impl::Mesh{std::move(*mesh), desc.deforming, 0});
        id = next;
        return {};
    });
}

Outcome System::destroy_mesh(MeshId mesh) {
    Outcome error;
    const Impl::Mesh* m = impl_->find_mesh(mesh, error);
    if (!m) return error;
    if (m->instances > 0)
        return Outcome(ErrorCode::InvalidHandle, "mesh " + std::to_string(mesh) + " is still used by " +
                                                     std::to_string(m->instances) + " instances");
    impl_->meshes.erase(mesh);
    return {};
}

Outcome System::set_vertices(MeshId mesh, const float* positions, std::uint32_t vertex_count,
                             std::uint32_t stride, bool teleport) {
    Outcome error;
    Impl::Mesh* m = impl_->find_deforming(mesh, vertex_count, error);
    if (!m) return error;
    if (vertex_count > 0 && !positions) return invalid("positions is null");
    if (stride < 12) return invalid("stride must be at least 12 bytes, got " + std::to_string(stride));
    return guarded([&]() -> Outcome {
        std::pmr::vector<glm::vec3> packed(vertex_count, &impl_->memory);
        for (std::uint32_t v = 0; v < vertex_count; ++v) {
            const auto* p = reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(positions) +
                                                           std::size_t(v) * stride);
            packed[v] = {p[0], p[1], p[2]};
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
                return invalid("vertex " + std::to_string(v) + " is not finite");
        }
        if (Status s = impl_->world->update_positions(m->gpu, packed); !s) return device_failure(s);
        m->teleport = m->teleport || teleport;
        return {};
    });
}

Outcome System::set_vertices(MeshId mesh, VkBuffer buffer, VkDeviceSize offset, std::uint32_t vertex_count,
                             bool teleport) {
    Outcome error;
    Impl::Mesh* m = impl_->find_deforming(mesh, vertex_count, error);
    if (!m) return error;
    if (impl_->ctx->owns_device()) return invalid("vertex buffers need a host device (SystemDesc::host)");
    if (buffer == VK_NULL_HANDLE) return invalid("buffer is null");
    if (offset % 4 != 0) return invalid("offset must be a multiple of 4");
    return guarded([&]() -> Outcome {
        if (Status s = impl_->world->copy_positions(m->gpu, buffer, offset); !s) return device_failure(s);
        m->teleport = m->teleport || teleport;
        return {};
    });
}

Outcome System::Impl::add_instance(MeshId mesh, const Mat4& transform, const Mat4* previous, bool moving,
                                   InstanceId& id) {
    id = 0;
    Outcome error;
    Mesh* m = find_mesh(mesh, error);
    if (!m) return error;
    if (Outcome o = check_transform(transform, "transform"); !o) return o;
    if (previous)
        if (Outcome o = check_transform(*previous, "previous"); !o) return o;
    return guarded([&]() -> Outcome {
        const InstanceId next = next_id++;
        const bool dynamic = moving || m->deforming;
        std::optional<glm::mat4> prev;
        if (previous) prev = to_glm(*previous);
        instances.emplace(next, Instance{mesh, to_glm(transform), prev, dynamic});
        ++m->instances;
        if (!dynamic) static_dirty = true;
        id = next;
        return {};
    });
}

Outcome System::create_instance(MeshId mesh, const Mat4& transform, bool moving, InstanceId& id) {
    return impl_->add_instance(mesh, transform, nullptr, moving, id);
}

Outcome System::create_moving_instance(MeshId mesh, const Mat4& transform, const Mat4& previous,
                                       InstanceId& id) {
    return impl_->add_instance(mesh, transform, &previous, true, id);
}

Outcome System::set_transform(InstanceId instance, const Mat4& transform, bool teleport) {
    auto it = impl_->instances.find(instance);
    if (it == impl_->instances.end())
        return Outcome(ErrorCode::InvalidHandle, "no instance " + std::to_string(instance));
    if (Outcome o = check_transform(transform, "transform"); !o) return o;
    it->second.model = to_glm(transform);
    it->second.teleport = it->second.teleport || teleport;
    if (!it->second.dynamic) impl_->static_dirty = true;
    return {};
}

Outcome System::destroy_instance(InstanceId instance) {
    auto it = impl_->instances.find(instance);
    if (it == impl_->instances.end())
        return Outcome(ErrorCode::InvalidHandle, "no instance " + std::to_string(instance));
    --impl_->meshes.at(it->second.mesh).instances;
    if (!it->second.dynamic) impl_->static_dirty = true;
    impl_->instances.erase(it);
    return {};
}

Outcome System::set_emitters(std::span<const WindEmitter> emitters) {
    return guarded([&]() -> Outcome {
        std::pmr::vector<Emitter> out(&impl_->memory);
        for (const WindEmitter& e : emitters) {
            const int type = int(e.type);
            if (type < 0 || type > int(WindEmitterType::ConeMotor))
                return invalid("emitter " + std::to_string(out.size()) + ": unknown type " +
                               std::to_string(type));
            out.push_back(Emitter{EmitterType(type), to_glm(e.position), to_glm(e.direction), e.radius,
                                  e.strength, e.falloff, e.length});
        }
        if (Status s = impl_->solver->set_emitters(out); !s) return invalid(s.message());
        return {};
    });
}

Outcome System::set_ambient(const Vec3& velocity) {
    if (Status s = impl_->solver->set_ambient(to_glm(velocity)); !s) return invalid(s.message());
    return {};
}

Outcome System::set_focus(const Vec3& position) {
    if (!finite(position)) return invalid("focus must be finite");
    // The next step scrolls by whole cells, counted in 32-bit integers: a move it could not make is
    // refused here, keeping the old focus, rather than failing every step after.
    const float h = impl_->solver_desc.cell_size;
    if (too_far_out(to_glm(position), h)) return invalid(std::string("focus ") + kTooFarOut);
    const glm::vec3 centre = impl_->solver->origin() + 0.5f * glm::vec3(impl_->solver_desc.cells) * h;
    if (glm::any(glm::greaterThan(glm::abs(to_glm(position) - centre) / h, glm::vec3(kMaxFocusMoveCells))))
        return invalid("focus is more than a million cells from the domain's centre; move it in smaller "
                       "steps or create the System at the new place");
    impl_->focus = to_glm(position);
    return {};
}

namespace {
Outcome check_dt(float dt) {
    if (!std::isfinite(dt) || !(dt > 0.0f) || dt > 10.0f)
        return invalid("dt must be a finite number of seconds in (0, 10], got " + std::to_string(dt));
    return {};
}
} // namespace

Outcome System::Impl::scroll_cells(glm::ivec3& cells) const {
    // Follow the focus in whole cells: the wind scrolls, the voxel grid moves with it.
    const float h = solver_desc.cell_size;
    const glm::vec3 wanted = focus - 0.5f * glm::vec3(solver_desc.cells) * h;
    const glm::vec3 shift = glm::round((wanted - solver->origin()) / h);
    if (glm::any(glm::greaterThan(glm::abs(shift), glm::vec3(kMaxFocusMoveCells + 1.0f))))
        return invalid("the focus moved more than a million cells in one step");
    cells = glm::ivec3(shift);
    return {};
}

std::pmr::vector<GpuInstance> System::Impl::frame_instances() {
    // Meshes in use cannot be destroyed, so the static set only changes through the instance calls that
    // set static_dirty; VoxelWorld::set_static still compares, so a transform set to its old value
    // voxelizes nothing.
    if (static_dirty) {
        std::pmr::vector<GpuInstance> fixed(&memory);
        for (const auto& [id, instance] : instances)
            if (!instance.dynamic)
                fixed.push_back({&meshes.at(instance.mesh).gpu, instance.model, std::nullopt});
        world->set_static(fixed);
        static_dirty = false;
    }
    std::pmr::vector<GpuInstance> dynamic(&memory);
    for (auto& [id, instance] : instances)
        if (instance.dynamic) {
            const Mesh& mesh = meshes.at(instance.mesh);
            dynamic.push_back({&mesh.gpu, instance.model, instance.prev, instance.teleport || mesh.teleport});
            instance.prev = instance.model;
            instance.teleport = false;
        }
    for (auto& [id, mesh] : meshes)
        mesh.teleport = false;
    return dynamic;
}

void System::Impl::take_stats(const WorldFrame& world_frame, const WindStats& wind,
                              const gpu::WorkCounts& work) {
    FrameStats& st = stats;
    st.dispatches = work.dispatches;
    st.submissions = std::uint32_t(work.submissions);
    st.waits = std::uint32_t(work.waits);
    const TreeStats& tree = world_frame.tree;
    st.frame = world_frame.frame;
    st.fragments = world_frame.static_voxelize.fragments + world_frame.dynamic_voxelize.fragments;
    st.voxels = tree.voxels;
    st.nodes = tree.nodes;
    st.refined = tree.refined;
    st.coarsened = tree.coarsened;
    st.pool_bytes = tree.pool_bytes;
    st.fragment_bytes = st.fragments * 4 + world_frame.dynamic_voxelize.fragments * 8;
    const std::uint64_t res = world->grid().res;
    st.dense_bytes = res * res * res * 4;
    st.divergence_before = float(wind.divergence_before);
    st.divergence_after = float(wind.divergence_after);
    st.residual = float(wind.residual);
    st.cycles = wind.cycles;
    st.converged = wind.converged;
    st.diverged = wind.diverged;
    st.sealed_cells = wind.sealed_cells;
    st.rejected_triangles =
        std::uint32_t(world_frame.dynamic_voxelize.rejected +
                      (world_frame.static_rebuilt ? world_frame.static_voxelize.rejected : 0));
    st.cut_cells = wind.cut_cells;
    st.fluid_cells = wind.fluid_cells;
    st.free_node_blocks = tree.free_node_blocks;
    st.free_mask_blocks = tree.free_mask_blocks;
    st.exhausted = tree.exhausted;
    st.pool_growths = world_frame.pool_growths;
    st.static_rebuilt = world_frame.static_rebuilt;
    st.nodes_per_level.assign(tree.nodes_per_level.begin(), tree.nodes_per_level.end());
    st.ms.assign(world_frame.ms.begin(), world_frame.ms.end());
    for (const auto& [pass, ms] : wind.ms)
        st.ms.emplace_back("wind_", ms).first.append(pass);
    if (world_frame.pool_growths > 0)
        log(LogLevel::Info,
            "the voxel tree's pools grew " + std::to_string(world_frame.pool_growths) + " times");
    if (world_frame.truncated)
        log(LogLevel::Warning,
            "frame " + std::to_string(world_frame.frame) +
                ": a fragment list or tree pool ran out, so its solids were partial; grown "
                "for the frames recorded from now on");
    if (wind.diverged)
        log(LogLevel::Warning,
            "frame " + std::to_string(world_frame.frame) +
                ": the pressure solve diverged and was stopped, so the frame's wind was not "
                "projected (docs/solver.md, \"Stability\")");
}

Outcome System::Impl::remember(Outcome stepped) {
    if (stepped.code() == ErrorCode::DeviceFailure && !failed) {
        const std::string_view why = stepped.message();
        const std::size_t n = std::min(why.size(), failure.size() - 1);
        std::copy_n(why.data(), n, failure.data());
        failure[n] = '\0';
        failed = true;
    }
    return stepped;
}

Outcome System::Impl::refuse_after_failure() const {
    if (!failed) return {};
    return Outcome(ErrorCode::DeviceFailure, "an earlier step failed (" + std::string(failure.data()) +
                                                 "), so the System's state is unknown: destroy it and create "
                                                 "another");
}

Outcome System::step(float dt) {
    if (impl_->submission == Submission::HostCommands)
        return invalid("with Submission::HostCommands, call step(dt, commands)");
    if (Outcome o = check_dt(dt); !o) return o;
    if (Outcome o = impl_->refuse_after_failure(); !o) return o;
    return impl_->remember(guarded([&]() -> Outcome {
        Impl& m = *impl_;
        const gpu::WorkCounts before = m.ctx->work();
        glm::ivec3 shift;
        if (Outcome o = m.scroll_cells(shift); !o) return o;
        // The frame as a host's command buffer would hold it: recorded, one submission, one wait. Buffers
        // replaced while recording are released once it completes (Context::retire).
        const std::uint64_t n = m.frame;
        m.ctx->begin_frame(n);
        Outcome recorded;
        const Status ran = m.ctx->submit_and_wait(
            [&](VkCommandBuffer cmd) { recorded = m.record_frame(cmd, dt, shift, m.blocking); });
        if (!recorded) return recorded;
        if (!ran) return device_failure(ran);
        m.ctx->retire(n);
        const gpu::WorkCounts& after = m.ctx->work();
        return m.collect(m.blocking, {after.dispatches - before.dispatches,
                                      after.submissions - before.submissions, after.waits - before.waits});
    }));
}

std::size_t System::Impl::answers_offset() {
    const std::size_t counters = VoxelWorld::readback_bytes() + WindSolver::readback_bytes();
    return (counters + 15) / 16 * 16;
}

Outcome System::Impl::collect(Slot& slot, const gpu::WorkCounts& work) {
    const auto* bytes = static_cast<const unsigned char*>(slot.readback.mapped());
    auto done = world->collect(bytes);
    if (!done) return device_failure(done.status());
    WindStats wind = solver->stats_from(bytes + VoxelWorld::readback_bytes());
    wind.ms = solver->timings(slot.frame);
    const auto* answers = reinterpret_cast<const glm::vec3*>(bytes + answers_offset());
    std::size_t at = 0;
    for (QueryId id : slot.asked) {
        Pending& pending = queries.at(id);
        pending.answer.assign(answers + at, answers + at + pending.points.size());
        pending.ready = true;
        pending.answered = slot.frame;
        at += pending.points.size();
    }
    // An answer left unfetched for kKeepAnswers frames is dropped, so an engine that abandons its tickets
    // does not hold their memory for the rest of the session.
    for (auto it = queries.begin(); it != queries.end();) {
        if (it->second.ready && slot.frame >= it->second.answered + kKeepAnswers) {
            log(LogLevel::Warning, "query " + std::to_string(it->first) + " was answered " +
                                       std::to_string(kKeepAnswers) +
                                       " frames ago and never fetched; dropped");
            it = queries.erase(it);
        } else {
            ++it;
        }
    }
    slot.asked.clear();
    slot.used = false;
    take_stats(*done, wind, work);
    return {};
}

Outcome System::step(float dt, VkCommandBuffer commands) {
    if (impl_->submission != Submission::HostCommands)
        return invalid("step(dt, commands) needs Submission::HostCommands");
    if (commands == VK_NULL_HANDLE) return invalid("commands is null");
    if (Outcome o = check_dt(dt); !o) return o;
    if (Outcome o = impl_->refuse_after_failure(); !o) return o;
    return impl_->remember(guarded([&]() -> Outcome {
        Impl& m = *impl_;
        glm::ivec3 shift;
        if (Outcome o = m.scroll_cells(shift); !o) return o;
        // The frame contract: the frame that last used this slot has completed, and so have those before.
        const std::uint64_t n = m.frame;
        Impl::Slot& slot = m.slots[n % m.slots.size()];
        if (slot.used)
            if (Outcome o = m.collect(slot, {slot.dispatches, 0, 0}); !o) return o;
        if (n >= m.slots.size()) m.ctx->retire(n - m.slots.size());
        m.ctx->begin_frame(n);

        return m.record_frame(commands, dt, shift, slot);
    }));
}

Outcome System::Impl::record_frame(VkCommandBuffer commands, float dt, glm::ivec3 shift, Slot& slot) {
    std::pmr::vector<glm::vec3> points(&memory);
    std::pmr::vector<QueryId> asked(&memory);
    for (const auto& [id, pending] : queries)
        if (!pending.asked) {
            points.insert(points.end(), pending.points.begin(), pending.points.end());
            asked.push_back(id);
        }
    const std::size_t readback =
        Impl::answers_offset() + std::max<std::size_t>(points.size(), 1) * sizeof(glm::vec3);
    if (!slot.readback || slot.readback.size() < readback) {
        auto grown = gpu::Buffer::create(*ctx, readback, gpu::MemoryUse::Readback);
        if (!grown) return device_failure(grown.status());
        slot.readback = std::move(*grown);
    }
    if (!points.empty() && slot.points.size() < points.size() * sizeof(glm::vec3)) {
        auto grown = gpu::Buffer::create(*ctx, points.size() * sizeof(glm::vec3), gpu::MemoryUse::Upload);
        if (!grown) return device_failure(grown.status());
        slot.points = std::move(*grown);
    }

    // Whatever the host submitted before (its draws sampling the wind texture, gust's last frame)
    // comes before this frame's work.
    const std::uint64_t dispatched = ctx->work().dispatches;
    gpu::barrier(*ctx, commands);
    if (shift != glm::ivec3(0)) {
        solver->record_scroll(commands, shift);
        if (Status s = world->move_grid(solver->origin()); !s) return device_failure(s);
    }
    const std::pmr::vector<GpuInstance> dynamic = frame_instances();
    if (Status s = world->record(commands, dynamic, dt); !s) return device_failure(s);
    const SolidSource solid = solid_source(*world);
    if (Status s = solver->record_step(commands, dt, &solid); !s) return device_failure(s);
    solver->record_texels(commands, texels);
    record_texture_copy(commands);
    if (!points.empty()) {
        std::memcpy(slot.points.mapped(), points.data(), points.size() * sizeof(glm::vec3));
        solver->record_sample(commands, slot.points.address(),
                              slot.readback.address() + Impl::answers_offset(), std::uint32_t(points.size()));
    }
    world->record_readback(commands, slot.readback.handle(), 0);
    solver->record_readback(commands, slot.readback.handle(), VoxelWorld::readback_bytes());
    // The readback copies reach the host once the frame completes; the host's later commands (its
    // shaders sampling the wind texture) see every write of this frame.
    VkMemoryBarrier2 barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
    barrier.srcStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
    barrier.srcAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT;
    barrier.dstStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT | VK_PIPELINE_STAGE_2_HOST_BIT;
    barrier.dstAccessMask = VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_HOST_READ_BIT;
    VkDependencyInfo dependency{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dependency.memoryBarrierCount = 1;
    dependency.pMemoryBarriers = &barrier;
    ctx->vk().vkCmdPipelineBarrier2(commands, &dependency);
    // Only a frame recorded whole answers its queries; after an error they wait for the next one.
    for (QueryId id : asked)
        queries.at(id).asked = true;
    slot.asked = std::move(asked);
    slot.used = true;
    slot.frame = ctx->recording_frame();
    slot.dispatches = ctx->work().dispatches - dispatched;
    ++frame;
    publish_texture();
    return {};
}

namespace {
Outcome check_points(std::span<const Vec3> points) {
    if (points.size() > kMaxQueryPoints)
        return invalid(std::to_string(points.size()) + " points, more than the " +
                       std::to_string(kMaxQueryPoints) + " a query takes");
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!finite(points[i])) return invalid("point " + std::to_string(i) + " is not finite");
    return {};
}
} // namespace

Outcome System::query(std::span<const Vec3> points, std::span<Vec3> velocities) {
    if (velocities.size() != points.size())
        return invalid("velocities holds " + std::to_string(velocities.size()) + " entries for " +
                       std::to_string(points.size()) + " points");
    if (Outcome o = check_points(points); !o) return o;
    return guarded([&]() -> Outcome {
        std::pmr::vector<glm::vec3> at(points.size(), &impl_->memory);
        for (std::size_t i = 0; i < points.size(); ++i)
            at[i] = to_glm(points[i]);
        auto answers = impl_->solver->sample(at);
        if (!answers) return device_failure(answers.status());
        for (std::size_t i = 0; i < points.size(); ++i)
            velocities[i] = to_vec3((*answers)[i]);
        return {};
    });
}

Outcome System::query_async(std::span<const Vec3> points, QueryId& id) {
    id = 0;
    if (Outcome o = check_points(points); !o) return o;
    return guarded([&]() -> Outcome {
        Impl::Pending pending(&impl_->memory);
        pending.points.reserve(points.size());
        for (const Vec3& p : points)
            pending.points.push_back(to_glm(p));
        const QueryId next = impl_->next_id++;
        impl_->queries.emplace(next, std::move(pending));
        id = next;
        return {};
    });
}

Outcome System::fetch(QueryId id, std::span<Vec3> velocities) {
    auto it = impl_->queries.find(id);
    if (it == impl_->queries.end())
        return Outcome(ErrorCode::InvalidHandle, "no query " + std::to_string(id));
    if (!it->second.ready)
        return Outcome(ErrorCode::NotReady, "query " + std::to_string(id) + " is answered by the next step");
    if (velocities.size() != it->second.answer.size())
        return invalid("velocities holds " + std::to_string(velocities.size()) + " entries for " +
                       std::to_string(it->second.answer.size()) + " points");
    for (std::size_t i = 0; i < velocities.size(); ++i)
        velocities[i] = to_vec3(it->second.answer[i]);
    impl_->queries.erase(it);
    return {};
}

Outcome System::wind_at(const Vec3& point, WindSample& sample) {
    sample = {};
    if (!finite(point)) return invalid("point is not finite");
    const float h = impl_->solver_desc.cell_size;
    const Vec3 points[7] = {point,
                            {point.x - h, point.y, point.z},
                            {point.x + h, point.y, point.z},
                            {point.x, point.y - h, point.z},
                            {point.x, point.y + h, point.z},
                            {point.x, point.y, point.z - h},
                            {point.x, point.y, point.z + h}};
    Vec3 v[7];
    if (Outcome o = query(points, v); !o) return o;
    glm::vec3 mean(0.0f);
    for (int i = 1; i < 7; ++i)
        mean += to_glm(v[i]) / 6.0f;
    const glm::vec3 here = to_glm(v[0]);
    sample.speed = glm::length(here);
    sample.direction = sample.speed > 0.0f ? to_vec3(here / sample.speed) : Vec3{};
    sample.gust = glm::length(here - mean);
    return {};
}

const WindTexture& System::wind_texture() const {
    return impl_->texture;
}
const FrameStats& System::stats() const {
    return impl_->stats;
}
Vec3 System::domain_origin() const {
    return to_vec3(impl_->solver->origin());
}
const char* System::device_name() const {
    return impl_->ctx->info().name.c_str();
}

Outcome System::export_vdb(const char* path) {
    if (!path || !*path) return invalid("path is empty");
#if GUST_WITH_OPENVDB
    return guarded([&]() -> Outcome {
        Impl& m = *impl_;
        auto voxels = m.world->tree().leaf_voxels();
        auto velocity = m.solver->read_cell_velocity();
        auto solid = m.solver->read_solid_fraction();
        auto pressure = m.solver->read_pressure();
        for (const Status* s : {&voxels.status(), &velocity.status(), &solid.status(), &pressure.status()})
            if (!*s) return device_failure(*s);
        const vdb::WindGrids grids{
            m.solver_desc.cells, m.solver_desc.cell_size, m.solver->origin(), *solid, *velocity, *pressure};
        if (Status s = vdb::write_frame_vdb(path, *voxels, m.world->grid(), grids); !s)
            return Outcome(ErrorCode::IoError, s.message());
        return {};
    });
#else
    return Outcome(ErrorCode::Unsupported, std::string("cannot write ") + path +
                                               ": gust was built without OpenVDB (GUST_WITH_OPENVDB=OFF)");
#endif
}

Outcome System::debug_voxel_grid(VoxelGridInfo& info) const {
    const GridDesc& grid = impl_->world->grid();
    const SparseTree& tree = impl_->world->tree();
    info = {};
    info.origin = to_vec3(grid.origin);
    info.voxel_size = grid.voxel_size;
    std::fill(std::begin(info.resolution), std::end(info.resolution), grid.res);
    info.depth = tree.depth();
    info.branching = tree.branching();
    return {};
}

Outcome System::debug_voxels(std::span<VoxelCoord> out, std::size_t& count) {
    count = 0;
    return guarded([&]() -> Outcome {
        auto keys = impl_->world->tree().leaf_voxels();
        if (!keys) return device_failure(keys.status());
        const std::size_t written = std::min(out.size(), keys->size());
        for (std::size_t v = 0; v < written; ++v) {
            const glm::uvec3 c = unpack_voxel((*keys)[v]);
            out[v] = {c.x, c.y, c.z};
        }
        count = keys->size();
        return {};
    });
}

Outcome System::debug_tree_nodes(std::span<TreeNode> out, std::size_t& count) {
    count = 0;
    return guarded([&]() -> Outcome {
        Impl& m = *impl_;
        const SparseTree& tree = m.world->tree();
        auto pool = tree.node_pool();
        if (!pool) return device_failure(pool.status());
        const std::pmr::vector<glm::uvec2>& nodes = *pool;
        const GridDesc& grid = m.world->grid();
        const std::uint32_t log2_b = std::uint32_t(std::countr_zero(tree.branching()));
        const std::uint32_t children = 1u << (3 * log2_b), depth = tree.depth();
        const std::size_t blocks = nodes.size() / children;
        if (Outcome o = m.check(blocks > 0, "the node pool holds the root's block", __LINE__); !o) return o;

        // Level by level, so a short `out` still holds the coarse levels whole. A block reached twice (or
        // the root's block reached as a child) would mean a corrupt pool; refusing it bounds the walk.
        struct Visit {
            std::uint32_t node;
            glm::uvec3 corner; ///< in voxels
        };
        std::pmr::vector<Visit> level_nodes({{0, glm::uvec3(0)}}, &m.memory), next(&m.memory);
        std::pmr::vector<bool> reached(blocks, false, &m.memory);
        reached[0] = true;
        std::size_t total = 0;
        std::uint32_t extent = grid.res; // voxels across a node of this level
        for (std::uint32_t level = 0; !level_nodes.empty(); ++level, extent >>= log2_b) {
            const bool bricks = level + 1 == depth;
            next.clear();
            for (const Visit& v : level_nodes) {
                const glm::uvec2 node = nodes[v.node];
                if (total < out.size()) {
                    TreeNode& n = out[total];
                    n.min = to_vec3(grid.origin + glm::vec3(v.corner) * grid.voxel_size);
                    n.size = float(extent) * grid.voxel_size;
                    n.level = level;
                    n.state = node.y == shaderio::kPinned                   ? TreeNodeState::Static
                              : tree.frame() != 0 && node.y == tree.frame() ? TreeNodeState::Reached
                                                                            : TreeNodeState::Stale;
                    n.refined = node.x != 0;
                }
                ++total;
                if (bricks || node.x == 0) continue;
                const bool fresh = node.x < blocks && !reached[node.x];
                if (Outcome o = m.check(fresh, "every child block is in the pool, once", __LINE__); !o)
                    return o;
                reached[node.x] = true;
                const std::uint32_t child_extent = extent >> log2_b, mask = (1u << log2_b) - 1;
                for (std::uint32_t c = 0; c < children; ++c) {
                    const glm::uvec3 slot(c & mask, (c >> log2_b) & mask, c >> (2 * log2_b));
                    next.push_back({node.x * children + c, v.corner + slot * child_extent});
                }
            }
            level_nodes.swap(next);
        }
        count = total;
        return {};
    });
}

} // namespace gust
