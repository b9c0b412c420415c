// gust::System: the API shell of include/gust/gust.hpp around the Frame (frame.hpp), which records a step.
// Here: creation, the two steps, and collecting a finished frame's stats and async answers. The scene's
// calls are in system_scene.cpp, the answers in system_answers.cpp.
#include "system_impl.hpp"

#include <algorithm>
#include <cstring>
#include <string>

namespace gust {

using namespace detail;

static_assert(kVersionMajor == GUST_PACKAGE_VERSION_MAJOR && kVersionMinor == GUST_PACKAGE_VERSION_MINOR,
              "gust.hpp's version and project(gust VERSION ...) differ");

std::uint32_t library_version() {
    return kHeaderVersion;
}

namespace {
/// Frames an answer of query_async waits to be fetched before it is dropped.
constexpr std::uint64_t kKeepAnswers = 64;
} // namespace

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
    if (desc.device_uuid) {
        own.device_uuid.emplace();
        std::copy_n(desc.device_uuid, VK_UUID_SIZE, own.device_uuid->begin());
    }
    own.external_memory = desc.exported_copies > 0;
    // Only the raster voxelizer draws: without it gust takes an async compute queue where the device has
    // one, and its steps overlap the game's rendering (docs/api.md "Devices").
    own.needs_graphics = desc.voxelize == VoxelizePath::Raster;
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
    if (desc.exported_copies > 8)
        return invalid("exported_copies must be 0..8, got " + std::to_string(desc.exported_copies));
    if (desc.exported_copies > 0 && desc.host)
        return invalid("exported_copies needs gust's own device (host must be null): a host device shares "
                       "gust's images as they are");
    if (desc.submission == Submission::HostCommands &&
        (desc.frames_in_flight < 1 || desc.frames_in_flight > 8))
        return invalid("frames_in_flight must be 1..8, got " + std::to_string(desc.frames_in_flight));
    SolverDesc solver_desc;
    if (Outcome o = solver_desc_from(desc, solver_desc); !o) return o;
    const std::uint32_t b = desc.domain.branching;
    if (b != 2 && b != 4 && b != 8) return invalid("domain.branching must be 2, 4 or 8");
    const std::uint32_t cascades = desc.domain.cascades, ratio = desc.domain.ratio;
    if (cascades < 1 || cascades > kMaxCascades)
        return invalid("domain.cascades must be 1.." + std::to_string(kMaxCascades) + ", got " +
                       std::to_string(cascades));
    if (ratio != 2 && ratio != 4) return invalid("domain.ratio must be 2 or 4, got " + std::to_string(ratio));
    const float coarsest = solver_desc.cell_size * std::pow(float(ratio), float(cascades - 1));
    if (cascades > 1 && !(coarsest <= kMaxCellSize))
        return invalid("domain.cascades: the coarsest cascade's cells would be " + std::to_string(coarsest) +
                       " m, more than 1000 m");
    solver_desc.nested = cascades > 1;

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
        if (desc.voxelize == VoxelizePath::Raster)
            if (Status s = check_method(VoxelizeMethod::Raster, m.ctx->info()); !s)
                return invalid("voxelize Raster: " + s.message());
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

        // The coarser cascades: the same cells, ratio^k times larger, centred on the same focus, each solver
        // coupled with its neighbours (docs/solver.md, "Cascades").
        std::pmr::vector<Cascade> coarser(&m.memory);
        std::uint32_t period = 1;
        SolverDesc cascade_desc = solver_desc;
        for (std::uint32_t k = 1; k < cascades; ++k) {
            period *= ratio;
            cascade_desc.cell_size *= float(ratio);
            cascade_desc.origin = m.focus - 0.5f * glm::vec3(cascade_desc.cells) * cascade_desc.cell_size;
            auto cascade_grid = voxel_grid(cascade_desc, b);
            if (!cascade_grid) return invalid(cascade_grid.message());
            world_desc.grid = *cascade_grid;
            auto cascade_world = VoxelWorld::create(*m.ctx, world_desc);
            if (!cascade_world) return device_failure(cascade_world.status());
            auto cascade_solver = WindSolver::create(*m.ctx, cascade_desc);
            if (!cascade_solver) return device_failure(cascade_solver.status());
            m.coarse_worlds.push_back(std::move(*cascade_world));
            m.coarse_solvers.push_back(std::move(*cascade_solver));
            coarser.push_back({.world = m.coarse_worlds.back().get(),
                               .solver = m.coarse_solvers.back().get(),
                               .period = period,
                               .waited = period - 1,
                               .voxel_size = cascade_desc.cell_size / float(cascade_desc.voxels_per_cell)});
        }
        for (std::uint32_t k = 0; k < cascades; ++k) {
            WindSolver& s = k == 0 ? *m.solver : *m.coarse_solvers[k - 1];
            const WindSolver* outer = k + 1 < cascades ? m.coarse_solvers[k].get() : nullptr;
            const WindSolver* inner = k == 0   ? nullptr
                                      : k == 1 ? m.solver.get()
                                               : m.coarse_solvers[k - 2].get();
            if (Status coupled = s.couple(outer, inner); !coupled) return device_failure(coupled);
        }

        m.frame.emplace(*m.ctx, *m.world, *m.solver, std::move(coarser), m.hooks);
        if (Outcome o = m.frame->create_textures(); !o) return o;
        if (Outcome o = create_exported(m, desc.exported_copies); !o) return o;
        if (desc.snapshot) {
            m.snapshot.emplace(m.frame->snapshot_cells(), cascades, &m.memory);
            m.frame->enable_snapshot(*m.snapshot);
        }
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

namespace {
Outcome check_dt(float dt) {
    if (!std::isfinite(dt) || !(dt > 0.0f) || dt > 10.0f)
        return invalid("dt must be a finite number of seconds in (0, 10], got " + std::to_string(dt));
    return {};
}
} // namespace

Outcome System::Impl::record(VkCommandBuffer commands, float dt, FrameSlot& slot) {
    FrameInputs in;
    in.dt = dt;
    in.focus = focus;
    if (Outcome o = frame->scroll_for(focus, in.shift); !o) return o;
    // Meshes in use cannot be destroyed, so the static set only changes through the instance calls that
    // set static_dirty; VoxelWorld::set_static still compares, so a transform set to its old value
    // voxelizes nothing.
    std::pmr::vector<GpuInstance> fixed(&memory), dynamic(&memory);
    for (const auto& [id, instance] : instances) {
        const Mesh& mesh = meshes.at(instance.mesh);
        if (instance.dynamic)
            dynamic.push_back({&mesh.gpu, instance.model, instance.prev, instance.teleport || mesh.teleport});
        else if (static_dirty)
            fixed.push_back({&mesh.gpu, instance.model, std::nullopt});
    }
    if (static_dirty) in.fixed = &fixed;
    in.dynamic = dynamic;
    std::pmr::vector<glm::vec3> points(&memory);
    std::pmr::vector<QueryId> asked(&memory);
    for (const auto& [id, pending] : queries)
        if (!pending.asked) {
            points.insert(points.end(), pending.points.begin(), pending.points.end());
            asked.push_back(id);
        }
    in.points = points;

    if (Outcome o = frame->record(commands, in, slot); !o) return o;

    // The frame is recorded: the scene's per-step state advances. Only a frame recorded whole answers its
    // queries; after an error they wait for the next one.
    static_dirty = false;
    for (auto& [id, instance] : instances)
        if (instance.dynamic) {
            instance.prev = instance.model;
            instance.teleport = false;
        }
    for (auto& [id, mesh] : meshes)
        mesh.teleport = false;
    for (QueryId id : asked)
        queries.at(id).asked = true;
    slot.asked = std::move(asked);
    return {};
}

Outcome System::Impl::collect(FrameSlot& slot, const gpu::WorkCounts& work) {
    const glm::vec3* answers = nullptr;
    {
        // Readers copy the stats (read_stats) under the same lock.
        const std::lock_guard lock(stats_mutex);
        if (Outcome o = frame->collect(slot, work, stats, answers); !o) return o;
    }
    // Outside the lock: the conversion grows with the grid, and read_stats need not wait for it.
    frame->publish_snapshot(slot);
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
    return {};
}

Outcome System::step(float dt) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("step");
    if (impl_->submission == Submission::HostCommands)
        return invalid("with Submission::HostCommands, call step(dt, commands)");
    if (Outcome o = check_dt(dt); !o) return o;
    if (Outcome o = impl_->refuse_after_failure(); !o) return o;
    return impl_->remember(guarded([&]() -> Outcome {
        Impl& m = *impl_;
        const gpu::WorkCounts before = m.ctx->work();
        // The frame as a host's command buffer would hold it: recorded, one submission, one wait. Buffers
        // replaced while recording are released once it completes (Context::retire).
        const std::uint64_t n = m.frame->recorded();
        m.ctx->begin_frame(n);
        Outcome recorded;
        const Status ran =
            m.ctx->submit_and_wait([&](VkCommandBuffer cmd) { recorded = m.record(cmd, dt, m.blocking); });
        if (!recorded) return recorded;
        if (!ran) return device_failure(ran);
        m.ctx->retire(n);
        const gpu::WorkCounts& after = m.ctx->work();
        return m.collect(m.blocking, {.dispatches = after.dispatches - before.dispatches,
                                      .submissions = after.submissions - before.submissions,
                                      .waits = after.waits - before.waits,
                                      .stages = after.stages - before.stages});
    }));
}

Outcome System::step(float dt, VkCommandBuffer commands) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("step");
    if (impl_->submission != Submission::HostCommands)
        return invalid("step(dt, commands) needs Submission::HostCommands");
    if (commands == VK_NULL_HANDLE) return invalid("commands is null");
    if (Outcome o = check_dt(dt); !o) return o;
    if (Outcome o = impl_->refuse_after_failure(); !o) return o;
    return impl_->remember(guarded([&]() -> Outcome {
        Impl& m = *impl_;
        // The frame contract: the frame that last used this slot has completed, and so have those before.
        const std::uint64_t n = m.frame->recorded();
        FrameSlot& slot = m.slots[n % m.slots.size()];
        if (slot.used)
            if (Outcome o = m.collect(slot, {.dispatches = slot.dispatches, .stages = slot.stages}); !o)
                return o;
        if (n >= m.slots.size()) m.ctx->retire(n - m.slots.size());
        m.ctx->begin_frame(n);
        return m.record(commands, dt, slot);
    }));
}

} // namespace gust
