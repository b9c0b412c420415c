// WindSolver's creation (its pipelines, one per pass mode where a pass has several; its buffers and
// bindings) and its API around the step: fields, queries, texels, scrolling. The step is recorded in
// wind_solver_step.cpp.
#include "wind_solver_impl.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <optional>

namespace gust {

static_assert(kMaxCascades == shaderio::kMaxCascades);
static_assert(kCascadeBlendCells == shaderio::kCascadeBlendCells);
static_assert(kCascadeSolidShare == shaderio::kCascadeSolidShare);

namespace {
#include "gust_shaders/advect_comp.h"
#include "gust_shaders/cg_comp.h"
#include "gust_shaders/coarse_solve_comp.h"
#include "gust_shaders/coarse_weights_comp.h"
#include "gust_shaders/diffuse_comp.h"
#include "gust_shaders/fill_finish_comp.h"
#include "gust_shaders/fill_finish_small_comp.h"
#include "gust_shaders/fill_link_comp.h"
#include "gust_shaders/fill_link_small_comp.h"
#include "gust_shaders/finish_comp.h"
#include "gust_shaders/fluid_finish_comp.h"
#include "gust_shaders/jacobi_comp.h"
#include "gust_shaders/project_comp.h"
#include "gust_shaders/sample_comp.h"
#include "gust_shaders/scroll_comp.h"
#include "gust_shaders/smooth_coarse_comp.h"
#include "gust_shaders/smooth_comp.h"
#include "gust_shaders/solid_cells_comp.h"
#include "gust_shaders/solid_cells_small_comp.h"
#include "gust_shaders/solid_faces_comp.h"
#include "gust_shaders/solid_faces_small_comp.h"
#include "gust_shaders/solid_motion_comp.h"
#include "gust_shaders/start_comp.h"

using detail::groups_for;
using shaderio::GridLevel;
using shaderio::kDispatchSlots;
using shaderio::LevelDispatch;
using shaderio::SolverBindings;
using shaderio::SolverPush;
using shaderio::SolverState;

template <std::size_t N> std::span<const std::uint32_t> words(const std::uint32_t (&a)[N]) {
    return {a, N};
}

/// Workgroups of smooth.comp over a level: one per 8^3 tile.
LevelDispatch tiles_for(glm::ivec3 dims) {
    const auto side = int(shaderio::kTileSide);
    return {std::uint32_t((dims.x + side / 2 + side - 1) / side),
            std::uint32_t((dims.y + side / 2 + side - 1) / side),
            std::uint32_t((dims.z + side / 2 + side - 1) / side)};
}

std::uint64_t cells_of(glm::ivec3 dims) {
    return std::uint64_t(dims.x) * dims.y * dims.z;
}

/// A shader once per mode (SolverPush::mode) the solver uses, the mode its specialization constant 0 and
/// `constant1`, when given, its constant 1: a compiler then keeps only that mode's code, where a CPU device
/// would execute every mode's.
Status create_modes(gpu::Context& ctx, std::span<gpu::Pipeline> out, std::span<const std::uint32_t> code,
                    const char* name, std::span<const std::uint32_t> modes,
                    std::optional<std::uint32_t> constant1 = std::nullopt) {
    for (const std::uint32_t mode : modes) {
        const std::array<std::uint32_t, 2> constants{mode, constant1.value_or(0u)};
        auto pipeline = gpu::Pipeline::compute(ctx, name, code, sizeof(SolverPush),
                                               std::span(constants).first(constant1 ? 2 : 1));
        if (!pipeline) return pipeline.status();
        out[mode] = std::move(*pipeline);
    }
    return {};
}

/// advect.comp for the solver's advection, its constant 1 (kNested) saying whether it has a neighbouring
/// cascade: a grid alone then carries none of the cascades' reads, which cost it half again in the pass.
Status create_advect(gpu::Context& ctx, const SolverDesc& desc, bool nested,
                     std::array<gpu::Pipeline, shaderio::kAdvectModes>& out) {
    static constexpr std::uint32_t kMacCormackModes[] = {shaderio::kAdvectForward, shaderio::kAdvectCorrect},
                                   kMacCormackScaleModes[] = {shaderio::kAdvectForward,
                                                              shaderio::kAdvectCorrect,
                                                              shaderio::kAdvectCorrectScale},
                                   kSemiLagrangianMode[] = {shaderio::kAdvectSemiLagrangian},
                                   kForcesMode[] = {shaderio::kAdvectForces};
    const std::span<const std::uint32_t> modes =
        desc.advection == Advection::MacCormack
            ? (detail::scale_in_advection(desc) ? std::span<const std::uint32_t>(kMacCormackScaleModes)
                                                : std::span<const std::uint32_t>(kMacCormackModes))
        : desc.advection == Advection::SemiLagrangian ? std::span<const std::uint32_t>(kSemiLagrangianMode)
                                                      : std::span<const std::uint32_t>(kForcesMode);
    return create_modes(ctx, out, words(advect_comp), "gust advect", modes, nested ? 1u : 0u);
}

} // namespace

WindSolver::WindSolver(gpu::Context& ctx) : ctx_(ctx) {}
WindSolver::~WindSolver() = default;

std::size_t WindSolver::face_count() const {
    return std::size_t(shaderio::faces_total(glm::ivec3(desc_.cells)));
}
std::size_t WindSolver::cell_count() const {
    return std::size_t(desc_.cells.x) * desc_.cells.y * desc_.cells.z;
}

Result<std::unique_ptr<WindSolver>> WindSolver::create(gpu::Context& ctx, const SolverDesc& desc) {
    if (Status s = validate(desc); !s) return s;
    std::unique_ptr<WindSolver> solver(new (ctx.memory()) WindSolver(ctx));
    solver->desc_ = desc;
    if (desc.layout == PassLayout::Auto)
        solver->desc_.layout = ctx.info().type == "cpu" ? PassLayout::LessWork : PassLayout::FewerStages;
    solver->origin_ = desc.origin;
    solver->impl_.reset(new (ctx.memory()) Impl(ctx.memory()));
    Impl& m = *solver->impl_;
    m.levels = detail::build_levels(desc.cells, desc.cell_size, ctx.memory());
    solver->levels_ = std::uint32_t(m.levels.size());
    solver->cycles_to_record_ = desc.max_cycles;

    struct Stage {
        gpu::Pipeline* pipeline;
        std::span<const std::uint32_t> code;
        const char* name;
    };
    // The voxel-set passes' two-word build serves cells of up to 4^3 voxels (solver_io.h, kBitsWords).
    const bool small = detail::cell_words(desc.voxels_per_cell) <= 2;
    const Stage stages[] = {
        {&m.solid_cells, small ? words(solid_cells_small_comp) : words(solid_cells_comp), "gust solid_cells"},
        {&m.solid_motion, words(solid_motion_comp), "gust solid_motion"},
        {&m.fill_link, small ? words(fill_link_small_comp) : words(fill_link_comp), "gust fill_link"},
        {&m.fill_finish, small ? words(fill_finish_small_comp) : words(fill_finish_comp), "gust fill_finish"},
        {&m.solid_faces, small ? words(solid_faces_small_comp) : words(solid_faces_comp), "gust solid_faces"},
        {&m.fluid_finish, words(fluid_finish_comp), "gust fluid_finish"},
        {&m.coarse_weights, words(coarse_weights_comp), "gust coarse_weights"},
        {&m.diffuse, words(diffuse_comp), "gust diffuse"},
        {&m.start, words(start_comp), "gust start"},
        {&m.coarse_solve, words(coarse_solve_comp), "gust coarse_solve"},
        {&m.cg, words(cg_comp), "gust cg"},
        {&m.jacobi, words(jacobi_comp), "gust jacobi"},
        {&m.project, words(project_comp), "gust project"},
        {&m.finish, words(finish_comp), "gust finish"},
        {&m.scroll, words(scroll_comp), "gust scroll"},
        {&m.sample, words(sample_comp), "gust sample"}};
    // coarse_solve.comp runs in one workgroup as wide as the device allows (a power of two, up to 1024),
    // so that each thread relaxes few cells of the levels it holds. A CPU device runs a workgroup's
    // invocations one after another between barriers, so there width buys nothing and costs each barrier.
    const std::uint32_t widest = ctx.info().type == "cpu" ? shaderio::kSolverGroupSize : 1024u;
    const std::uint32_t wide_group = std::bit_floor(std::clamp(ctx.info().max_workgroup_size, 64u, widest));
    for (const Stage& stage : stages) {
        const std::uint32_t constants[] = {wide_group};
        auto pipeline = gpu::Pipeline::compute(
            ctx, stage.name, stage.code, sizeof(SolverPush),
            stage.pipeline == &m.coarse_solve ? std::span(constants) : std::span<const std::uint32_t>());
        if (!pipeline) return pipeline.status();
        *stage.pipeline = std::move(*pipeline);
    }
    static constexpr std::uint32_t kPcgModes[] = {shaderio::kSmoothStart, shaderio::kSmoothFirst,
                                                  shaderio::kSmoothDown, shaderio::kSmoothUp,
                                                  shaderio::kSmoothUpBeta},
                                   kMultigridModes[] = {shaderio::kSmoothStart, shaderio::kSmoothDown,
                                                        shaderio::kSmoothUp, shaderio::kSmoothFirstPlain};
    const std::span<const std::uint32_t> smooth_modes =
        desc.pressure == PressureSolver::MultigridPCG ? std::span<const std::uint32_t>(kPcgModes)
        : desc.pressure == PressureSolver::Multigrid  ? std::span<const std::uint32_t>(kMultigridModes)
                                                      : std::span<const std::uint32_t>();
    if (Status s = create_advect(ctx, solver->desc_, desc.nested, m.advect); !s) return s;
    m.advect_nested = desc.nested;
    if (Status s = create_modes(ctx, m.smooth, words(smooth_comp), "gust smooth", smooth_modes); !s) return s;
    m.coarse_level = solver->levels_ - 1;
    while (m.coarse_level > 0 && cells_of(m.levels[m.coarse_level - 1].dims) <= shaderio::kCoarseCells)
        --m.coarse_level;
    // PassLayout::FewerStages: the pass just above the coarse solve's levels runs it in its last workgroup:
    // level 0's first passes, or the downward smoothing of the level between. A CPU device pays for that
    // pass's size in every workgroup (docs/solver.md, "Stages on a GPU and on a CPU device").
    if (solver->desc_.layout == PassLayout::FewerStages && m.coarse_level > 0 &&
        desc.pressure != PressureSolver::Jacobi) {
        const std::uint32_t first_modes[] = {shaderio::kSmoothStart,
                                             desc.pressure == PressureSolver::MultigridPCG
                                                 ? shaderio::kSmoothFirst
                                                 : shaderio::kSmoothFirstPlain},
                            down_mode[] = {shaderio::kSmoothDown};
        if (Status s = create_modes(ctx, m.smooth_coarse, words(smooth_coarse_comp), "gust smooth_coarse",
                                    m.coarse_level == 1 ? std::span<const std::uint32_t>(first_modes)
                                                        : std::span<const std::uint32_t>(down_mode));
            !s)
            return s;
    }

    const GridLevel& last = m.levels.back();
    const std::uint64_t all_cells = last.cells + std::uint64_t(last.dims.x) * last.dims.y * last.dims.z;
    const std::uint64_t all_faces = last.faces + std::uint64_t(shaderio::faces_total(last.dims));
    const std::uint64_t faces = solver->face_count(), cells = solver->cell_count();
    const std::uint64_t words_per_cell = detail::cell_words(desc.voxels_per_cell);
    const std::uint64_t open_words = shaderio::open_count_words(std::uint32_t(faces));
    const std::uint64_t nodes = 1 + shaderio::kCellParts * cells; // the fill's; fluid_node() adds one a cell
    // Partial sums: one per workgroup of the widest reducing pass (level-0 faces: the advection's correction
    // with the warm start's b·q; level-0 cells; level-0 tiles).
    const LevelDispatch face_groups = groups_for(faces), level0_tiles = tiles_for(m.levels[0].dims);
    const std::uint64_t partials =
        std::max<std::uint64_t>(std::uint64_t(face_groups.x) * face_groups.y,
                                std::uint64_t(level0_tiles.x) * level0_tiles.y * level0_tiles.z);
    struct Want {
        gpu::Buffer* buffer;
        std::uint64_t bytes;
        VkBufferUsageFlags usage;
        const char* name;
    };
    // Everything lives in device-local memory, the state and the indirect arguments too: the host reads
    // the state through record_readback()'s copy.
    constexpr VkBufferUsageFlags kIndirect = VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT;
    const Want wants[] = {
        {&m.velocity, faces * 4, 0, "gust velocity A"},
        {&m.velocity_tmp, faces * 4, 0, "gust velocity B"},
        {&m.velocity_back, faces * 4 * (desc.advection == Advection::MacCormack ? 3 : 1), 0,
         "gust velocity back"},
        {&m.open_counts, open_words * 4, 0, "gust open counts"},
        {&m.weights, std::max<std::uint64_t>(all_faces - faces, 1) * 4, 0, "gust coarse weights"},
        {&m.solid_velocity, faces * 4, 0, "gust solid velocity"},
        {&m.pressure, all_cells * 4, 0, "gust v-cycle down"},
        {&m.pressure_up, all_cells * 4, 0, "gust v-cycle up"},
        {&m.rhs, all_cells * 4, 0, "gust v-cycle rhs"},
        {&m.scratch, cells * 4, 0, "gust scratch"},
        {&m.cg_cells, 7 * cells * 4, 0, "gust solve"},
        {&m.partials, partials * 8, 0, "gust partial sums"},
        {&m.cell_solid, cells * 4, 0, "gust solid fraction"},
        {&m.cell_parts, cells * shaderio::kCellParts * words_per_cell * 4, 0, "gust cell parts"},
        {&m.cell_static, cells * words_per_cell * 4, 0, "gust cell static voxels"},
        {&m.cell_flags, cells * 4, 0, "gust cell flags"},
        {&m.cell_motion, cells * 16, 0, "gust cell motion"},
        {&m.labels, (nodes + cells) * 4, 0, "gust fill labels"},
        {&m.region_motion, nodes * 32, 0, "gust region motion"},
        {&m.vorticity_buf, cells * 16, 0, "gust vorticity"},
        {&m.confinement, cells * 16, 0, "gust confinement"},
        {&m.emitters, shaderio::kMaxEmitters * sizeof(shaderio::GpuEmitter), 0, "gust emitters"},
        {&m.state, sizeof(SolverState), kIndirect, "gust solver state"},
        {&m.dispatch, 2 * kDispatchSlots * sizeof(LevelDispatch), kIndirect, "gust solver dispatch"},
        {&m.bindings, sizeof(SolverBindings), 0, "gust solver bindings"}};
    for (const Want& want : wants) {
        auto buffer = gpu::Buffer::create(ctx, want.bytes, gpu::MemoryUse::Device, want.usage, want.name);
        if (!buffer) return buffer.status();
        *want.buffer = std::move(*buffer);
    }
    auto readback =
        gpu::Buffer::create(ctx, sizeof(SolverState), gpu::MemoryUse::Readback, 0, "gust solver stats");
    if (!readback) return readback.status();
    m.state_readback = std::move(*readback);
    auto profiler = gpu::Profiler::create(ctx, 16);
    if (!profiler) return profiler.status();
    m.profiler = std::move(*profiler);

    std::pmr::vector<LevelDispatch> dispatch(2 * kDispatchSlots, LevelDispatch{0, 0, 0}, ctx.memory());
    for (std::size_t l = 0; l < m.levels.size(); ++l) {
        const glm::ivec3 d = m.levels[l].dims;
        dispatch[kDispatchSlots + l] = groups_for(cells_of(d));
        dispatch[kDispatchSlots + shaderio::kTileSlot + l] = tiles_for(d);
    }
    dispatch[kDispatchSlots + shaderio::kCoarseSlot] = {1, 1, 1};

    SolverBindings& b = m.b;
    b.velocity = m.velocity.address();
    b.velocity_tmp = m.velocity_tmp.address();
    b.velocity_back = m.velocity_back.address();
    b.weights = m.weights.address();
    b.open_counts = m.open_counts.address();
    b.level0_faces = std::uint32_t(faces);
    b.pair_share = shaderio::pair_share(desc.voxels_per_cell);
    b.voxel_share = shaderio::voxel_share(desc.voxels_per_cell);
    b.solid_velocity = m.solid_velocity.address();
    b.pressure = m.pressure.address();
    b.pressure_up = m.pressure_up.address();
    b.rhs = m.rhs.address();
    b.scratch = m.scratch.address();
    b.cg_cells = m.cg_cells.address();
    b.partials = m.partials.address();
    b.partial_count = std::uint32_t(partials);
    b.cell_solid = m.cell_solid.address();
    b.cell_parts = m.cell_parts.address();
    b.cell_static = m.cell_static.address();
    b.cell_flags = m.cell_flags.address();
    b.cell_motion = m.cell_motion.address();
    b.labels = m.labels.address();
    b.region_motion = m.region_motion.address();
    b.max_solid_speed = desc.max_solid_speed;
    b.vorticity = m.vorticity_buf.address();
    b.confinement = m.confinement.address();
    b.emitters = m.emitters.address();
    b.state = m.state.address();
    b.dispatch = m.dispatch.address();
    b.dims = glm::ivec3(desc.cells);
    b.h = desc.cell_size;
    b.voxels_per_cell = desc.voxels_per_cell;
    b.cell_words = std::uint32_t(words_per_cell);
    b.levels = solver->levels_;
    b.coarse_level = m.coarse_level;
    b.tolerance = desc.tolerance;
    b.vorticity_strength = desc.vorticity;
    b.smoothing = desc.smoothing;
    b.current = m.velocity.address();
    std::copy(m.levels.begin(), m.levels.end(), b.level);
    detail::face_masks(desc.voxels_per_cell, b.face_mask);

    Status cleared = ctx.submit_and_wait([&](VkCommandBuffer cmd) {
        ctx.vk().vkCmdUpdateBuffer(cmd, m.dispatch.handle(), 0, dispatch.size() * sizeof(LevelDispatch),
                                   dispatch.data());
        // cell_flags, cell_motion and region_motion start clear: each step's solid_cells clears only what
        // the last step marked. The solve's buffers start at zero so that a term multiplied by zero (a
        // direction times β = 0) never meets an uninitialised NaN.
        for (gpu::Buffer* buffer :
             {&m.velocity, &m.velocity_tmp, &m.solid_velocity, &m.pressure, &m.pressure_up, &m.cg_cells,
              &m.cell_solid, &m.cell_flags, &m.cell_motion, &m.region_motion, &m.vorticity_buf})
            ctx.vk().vkCmdFillBuffer(cmd, buffer->handle(), 0, VK_WHOLE_SIZE, 0);
        ctx.vk().vkCmdFillBuffer(cmd, m.weights.handle(), 0, VK_WHOLE_SIZE,
                                 std::bit_cast<std::uint32_t>(1.0f));
        const std::uint32_t all_open = desc.voxels_per_cell * desc.voxels_per_cell;
        ctx.vk().vkCmdFillBuffer(cmd, m.open_counts.handle(), 0, VK_WHOLE_SIZE, all_open * 0x01010101u);
        // A nested cascade may read these bindings before this solver's first step (couple).
        gpu::update(ctx, cmd, m.bindings, &b, sizeof(b));
    });
    if (!cleared) return cleared;
    return solver;
}

Status WindSolver::set_ambient(glm::vec3 velocity) {
    if (Status s = detail::validate_ambient(velocity); !s) return s;
    if (last_dt_ > 0.0f) {
        // A change of the far-field wind reaches the whole field at once (docs/solver.md, "Ambient wind").
        ambient_change_ += velocity - ambient_;
        ambient_ = velocity;
        return Status{};
    }
    ambient_ = velocity;
    const std::pmr::vector<float> faces =
        detail::uniform_faces(glm::ivec3(desc_.cells), velocity, ctx_.memory());
    Impl& m = *impl_;
    return upload(ctx_, const_cast<gpu::Buffer&>(m.current_velocity()), faces.data(),
                  faces.size() * sizeof(float));
}

Status WindSolver::couple(const WindSolver* outer, const WindSolver* inner) {
    Impl& m = *impl_;
    if (inner && !m.previous) {
        auto previous = gpu::Buffer::create(ctx_, face_count() * 4, gpu::MemoryUse::Device, 0,
                                            "gust velocity before the last step");
        if (!previous) return previous.status();
        m.previous = std::move(*previous);
    }
    if (const bool nested = outer || inner; nested != m.advect_nested) {
        if (Status s = create_advect(ctx_, desc_, nested, m.advect); !s) return s;
        m.advect_nested = nested;
    }
    m.b.outer = outer ? outer->impl_->bindings.address() : 0;
    m.b.inner = inner ? inner->impl_->bindings.address() : 0;
    // Until the first keep, the finer cascade reads the current field alone.
    m.b.previous = inner ? m.previous.address() : 0;
    m.b.previous_origin = origin_;
    m.b.time_blend = 1.0f;
    return Status{};
}

void WindSolver::record_keep_previous(VkCommandBuffer cmd) {
    Impl& m = *impl_;
    if (!m.previous) return;
    gpu::barrier(ctx_, cmd);
    const VkBufferCopy region{0, 0, face_count() * 4};
    ctx_.vk().vkCmdCopyBuffer(cmd, m.current_velocity().handle(), m.previous.handle(), 1, &region);
    m.b.previous_origin = origin_;
    gpu::barrier(ctx_, cmd);
}

void WindSolver::record_ambient_change(VkCommandBuffer cmd) {
    if (ambient_change_ == glm::vec3(0.0f)) return;
    // Added to the air everywhere at once: a uniform field is divergence-free, so this is the response of
    // incompressible air to a new far field, and the next projection fits it to the solids (docs/solver.md,
    // "Ambient wind"). The field kept for the finer cascades too, so their blend in time sees it whole.
    Impl& m = *impl_;
    m.b.ambient_change = ambient_change_;
    m.record_single_pass(ctx_, cmd, m.scroll, shaderio::kScrollAmbientChange, glm::ivec3(0), face_count());
    ambient_change_ = glm::vec3(0.0f);
}

void WindSolver::record_time_blend(VkCommandBuffer cmd, float blend) {
    Impl& m = *impl_;
    if (!m.previous) return;
    m.b.time_blend = std::clamp(blend, 0.0f, 1.0f);
    // The whole bindings: previous_origin changed with the keep too.
    m.put_bindings(ctx_, cmd);
}

Status WindSolver::shift_origin(glm::vec3 offset) {
    const glm::vec3 moved = origin_ + offset;
    if (!std::isfinite(moved.x) || !std::isfinite(moved.y) || !std::isfinite(moved.z))
        return Status::failure("the shifted origin must be finite");
    origin_ = moved;
    impl_->b.previous_origin += offset;
    for (std::uint32_t e = 0; e < impl_->emitter_count; ++e)
        impl_->emitter_data[e].position += offset;
    impl_->solids_stale = true;
    return Status{};
}

void WindSolver::record_bindings(VkCommandBuffer cmd) {
    impl_->b.origin = origin_;
    impl_->put_current(ctx_, cmd);
}

Status WindSolver::set_emitters(std::span<const Emitter> emitters) {
    if (Status s = validate(emitters); !s) return s;
    impl_->omni_count = detail::omni_first(emitters, impl_->emitter_data);
    impl_->emitter_count = std::uint32_t(emitters.size());
    return Status{};
}

Status WindSolver::set_velocity(std::span<const float> faces) {
    if (faces.size() != face_count())
        return Status::failure("expected " + std::to_string(face_count()) + " face velocities, got " +
                               std::to_string(faces.size()));
    for (float v : faces)
        if (!std::isfinite(v)) return Status::failure("face velocities must be finite");
    Impl& m = *impl_;
    if (Status s =
            upload(ctx_, const_cast<gpu::Buffer&>(m.current_velocity()), faces.data(), faces.size_bytes());
        !s)
        return s;
    m.has_guess = false;
    return Status{};
}

void WindSolver::bind_texels(const gpu::Buffer& texels) {
    impl_->bound_texels = impl_->b.texels = texels.address();
}

namespace {
Result<std::vector<float>> read_floats(gpu::Context& ctx, const gpu::Buffer& buffer, std::size_t count,
                                       std::size_t offset = 0) {
    std::vector<float> out(count);
    if (Status s = download(ctx, buffer, out.data(), count * sizeof(float), offset); !s) return s;
    return out;
}
} // namespace

Result<std::vector<float>> WindSolver::read_velocity() const {
    return read_floats(ctx_, impl_->current_velocity(), face_count());
}
Result<std::vector<float>> WindSolver::read_open_fraction() const {
    std::vector<std::uint32_t> words(shaderio::open_count_words(std::uint32_t(face_count())));
    if (Status s = download(ctx_, impl_->open_counts, words.data(), words.size() * 4); !s) return s;
    const float share = shaderio::pair_share(desc_.voxels_per_cell);
    std::vector<float> out(face_count());
    for (std::uint32_t i = 0; i < out.size(); ++i)
        out[i] = shaderio::open_fraction_of(shaderio::open_count_in(words[i / 4], i), share);
    return out;
}
Result<std::vector<float>> WindSolver::read_solid_velocity() const {
    return read_floats(ctx_, impl_->solid_velocity, face_count());
}
Result<std::vector<float>> WindSolver::read_solid_fraction() const {
    return read_floats(ctx_, impl_->cell_solid, cell_count());
}
Result<std::vector<float>> WindSolver::read_pressure() const {
    // φ is the last of the solve's level-0 arrays (kCellPhi, cg_cells' seventh).
    auto phi = read_floats(ctx_, impl_->cg_cells, cell_count(), 6 * cell_count() * sizeof(float));
    if (!phi) return phi;
    const float scale = last_dt_ > 0.0f ? detail::kAirDensity / last_dt_ : 0.0f;
    for (float& p : *phi)
        p *= scale;
    return phi;
}

Result<std::vector<glm::vec3>> WindSolver::read_cell_velocity() {
    Impl& m = *impl_;
    const std::size_t bytes = cell_count() * sizeof(glm::vec3);
    auto out_buffer = gpu::Buffer::create(ctx_, bytes, gpu::MemoryUse::Readback, 0, "gust cell velocity");
    if (!out_buffer) return out_buffer.status();
    Status s = ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
        m.b.origin = origin_;
        m.b.samples = out_buffer->address();
        m.record_single_pass(ctx_, cmd, m.sample, shaderio::kSampleCells, glm::ivec3(0), cell_count());
    });
    if (!s) return s;
    std::vector<glm::vec3> out(cell_count());
    std::memcpy(out.data(), out_buffer->mapped(), bytes);
    return out;
}

Result<std::pmr::vector<glm::vec3>> WindSolver::sample(std::span<const glm::vec3> points, PointSample what) {
    std::pmr::vector<glm::vec3> out(points.size(), ctx_.memory());
    if (points.empty()) return out;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y) || !std::isfinite(points[i].z))
            return Status::failure("point " + std::to_string(i) + " is not finite");
    if (points.size() > 0xffffffffu / sizeof(glm::vec3))
        return Status::failure("too many points in one call");
    Impl& m = *impl_;
    const std::size_t bytes = points.size() * sizeof(glm::vec3);
    if (m.points.size() < bytes) {
        for (auto [buffer, use] : {std::pair(&m.points, gpu::MemoryUse::Upload),
                                   std::pair(&m.samples, gpu::MemoryUse::Readback)}) {
            auto grown =
                gpu::Buffer::create(ctx_, std::max<std::size_t>(bytes, 4096), use, 0, "gust query points");
            if (!grown) return grown.status();
            *buffer = std::move(*grown);
        }
    }
    std::memcpy(m.points.mapped(), points.data(), bytes);
    Status s = ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
        record_sample(cmd, m.points.address(), m.samples.address(), std::uint32_t(points.size()), what);
    });
    if (!s) return s;
    std::memcpy(out.data(), m.samples.mapped(), bytes);
    return out;
}

void WindSolver::record_sample(VkCommandBuffer cmd, VkDeviceAddress points, VkDeviceAddress samples,
                               std::uint32_t count, PointSample what) {
    Impl& m = *impl_;
    m.b.origin = origin_;
    m.b.ambient = ambient_;
    m.b.points = points;
    m.b.samples = samples;
    m.b.point_count = count;
    m.record_single_pass(ctx_, cmd, m.sample,
                         what == PointSample::Wind ? shaderio::kSampleWind : shaderio::kSamplePoints,
                         glm::ivec3(0), count);
}

Status WindSolver::check_texels(const gpu::Buffer& texels) const {
    if (texels.size() < cell_count() * 8)
        return Status::failure("texel buffer holds " + std::to_string(texels.size()) + " bytes, needs " +
                               std::to_string(cell_count() * 8));
    return Status{};
}

void WindSolver::record_texels(VkCommandBuffer cmd, const gpu::Buffer& texels) {
    Impl& m = *impl_;
    m.b.origin = origin_;
    m.b.texels = texels.address();
    m.record_single_pass(ctx_, cmd, m.sample, shaderio::kSampleTexels, glm::ivec3(0), cell_count());
    // The steps write the bound texels alone; the next pass's bindings carry them again.
    m.b.texels = m.bound_texels;
}

Status WindSolver::scroll(glm::ivec3 cells) {
    if (cells == glm::ivec3(0)) return Status{};
    return ctx_.submit_and_wait([&](VkCommandBuffer cmd) { record_scroll(cmd, cells); });
}

void WindSolver::record_scroll(VkCommandBuffer cmd, glm::ivec3 cells) {
    if (cells == glm::ivec3(0)) return;
    Impl& m = *impl_;
    m.b.ambient = ambient_;
    m.record_single_pass(ctx_, cmd, m.scroll, shaderio::kScrollMove, cells,
                         std::max(face_count(), cell_count()));
    m.swap ^= 1u;
    // φ was moved into the scratch array; the last step's vorticity would no longer line up, so the next
    // step's confinement starts from none.
    const VkBufferCopy phi{0, 6 * cell_count() * sizeof(float), cell_count() * sizeof(float)};
    ctx_.vk().vkCmdCopyBuffer(cmd, m.scratch.handle(), m.cg_cells.handle(), 1, &phi);
    ctx_.vk().vkCmdFillBuffer(cmd, m.vorticity_buf.handle(), 0, VK_WHOLE_SIZE, 0);
    gpu::barrier(ctx_, cmd);
    m.solids_stale = true;
    origin_ += glm::vec3(cells) * desc_.cell_size;
    m.b.origin = origin_;
    m.put_current(ctx_, cmd);
}

} // namespace gust
