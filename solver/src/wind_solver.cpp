#include "solver_setup.hpp"
#include "tree/tree_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <gust/solver/wind_solver.hpp>

namespace gust {

namespace {
#include "gust_shaders/advect_comp.h"
#include "gust_shaders/cg_comp.h"
#include "gust_shaders/coarse_solve_comp.h"
#include "gust_shaders/coarse_weights_comp.h"
#include "gust_shaders/diffuse_comp.h"
#include "gust_shaders/extend_comp.h"
#include "gust_shaders/fill_finish_comp.h"
#include "gust_shaders/fill_finish_small_comp.h"
#include "gust_shaders/fill_link_comp.h"
#include "gust_shaders/fill_link_small_comp.h"
#include "gust_shaders/finish_comp.h"
#include "gust_shaders/fluid_finish_comp.h"
#include "gust_shaders/fluid_link_comp.h"
#include "gust_shaders/jacobi_comp.h"
#include "gust_shaders/project_comp.h"
#include "gust_shaders/restrict_comp.h"
#include "gust_shaders/sample_comp.h"
#include "gust_shaders/scroll_comp.h"
#include "gust_shaders/smooth_comp.h"
#include "gust_shaders/solid_cells_comp.h"
#include "gust_shaders/solid_cells_small_comp.h"
#include "gust_shaders/solid_faces_comp.h"
#include "gust_shaders/solid_faces_small_comp.h"
#include "gust_shaders/solid_motion_comp.h"
#include "gust_shaders/start_comp.h"

using shaderio::GridLevel;
using shaderio::kCellWords;
using shaderio::kDispatchSlots;
using shaderio::LevelDispatch;
using shaderio::SolverBindings;
using shaderio::SolverPush;
using shaderio::SolverState;

template <std::size_t N> std::span<const std::uint32_t> words(const std::uint32_t (&a)[N]) {
    return {a, N};
}

LevelDispatch groups_for(std::uint64_t items) {
    const std::uint64_t groups = (items + shaderio::kSolverGroupSize - 1) / shaderio::kSolverGroupSize;
    return {std::uint32_t(std::min<std::uint64_t>(groups, 65535)), std::uint32_t((groups + 65534) / 65535),
            1};
}

float from_bits(std::uint32_t bits) {
    return std::bit_cast<float>(bits);
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

} // namespace

struct WindSolver::Impl : gpu::HostObject {
    explicit Impl(std::pmr::memory_resource* memory) : levels(memory) {}
    /// advect.comp and smooth.comp specialized to each mode (SolverPush::mode) the solver uses.
    std::array<gpu::Pipeline, shaderio::kAdvectModes> advect;
    std::array<gpu::Pipeline, shaderio::kSmoothModes> smooth;
    gpu::Pipeline solid_cells, solid_motion, fill_link, fill_finish, solid_faces, fluid_link, fluid_finish,
        coarse_weights, diffuse, start, restrict_, coarse_solve, cg, jacobi, project, extend, finish, scroll,
        sample;
    gpu::Buffer velocity, velocity_tmp, velocity_back, open_counts, weights, solid_velocity, pressure,
        pressure_up, rhs, scratch, cg_cells, partials, cell_solid, cell_parts, cell_static, cell_flags,
        cell_motion, labels, region_motion, vorticity_buf, confinement, emitters, state, dispatch, bindings,
        points, samples, state_readback;
    gpu::Profiler profiler;
    std::pmr::vector<GridLevel> levels;
    /// The first level the coarse solve takes (coarse_solve.comp): at most kCoarseCells cells.
    std::uint32_t coarse_level = 0;
    std::uint32_t emitter_count = 0;
    std::uint32_t omni_count = 0; ///< the first emitter_data are omni (omni_first)
    std::array<shaderio::GpuEmitter, shaderio::kMaxEmitters> emitter_data{}; ///< written by each step
    /// Which of the two velocity buffers holds the velocity (SolverPush::swap bit 0): a pass writes the
    /// next field into the other, and they trade places instead of being copied.
    std::uint32_t swap = 0;
    const gpu::Buffer& current_velocity() const { return swap ? velocity_tmp : velocity; }
    const gpu::Buffer& other_velocity() const { return swap ? velocity : velocity_tmp; }
    /// Records the bindings `b` into their buffer, between barriers (passes earlier in the command buffer
    /// may still read the old ones).
    void put_bindings(const gpu::Context& ctx, VkCommandBuffer cmd) const {
        gpu::barrier(ctx, cmd);
        gpu::update(ctx, cmd, bindings, &b, sizeof(b));
        gpu::barrier(ctx, cmd);
    }
    /// Records sample.comp in `mode` (shaderio::kSample*) over `count` threads, after the bindings `b` the
    /// caller set.
    void record_sample_pass(const gpu::Context& ctx, VkCommandBuffer cmd, std::uint32_t mode,
                            std::uint64_t count) {
        put_bindings(ctx, cmd);
        SolverPush push{};
        push.bindings = bindings.address();
        push.mode = mode;
        push.swap = swap;
        const LevelDispatch g = groups_for(count);
        sample.bind(cmd, &push, sizeof(push));
        sample.dispatch(cmd, g.x, g.y, g.z);
        gpu::barrier(ctx, cmd);
    }
    /// φ holds the last solve of this field's history, so the next solve may start from it (the warm
    /// start); false before the first step and after set_velocity replaced the field.
    bool has_guess = false;
    /// What the last step's solid_cells saw: a step whose solids differ in any of these (or the first, or
    /// one after a scroll) redoes every cell's voxels; otherwise only the cells a moving surface reaches.
    bool solids_stale = true;
    const SparseTree* last_tree = nullptr;
    std::uint64_t last_static_generation = 0;
    glm::ivec3 last_voxel_offset{0};
    SolverBindings b{};
};

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
        {&m.fluid_link, words(fluid_link_comp), "gust fluid_link"},
        {&m.fluid_finish, words(fluid_finish_comp), "gust fluid_finish"},
        {&m.coarse_weights, words(coarse_weights_comp), "gust coarse_weights"},
        {&m.diffuse, words(diffuse_comp), "gust diffuse"},
        {&m.start, words(start_comp), "gust start"},
        {&m.restrict_, words(restrict_comp), "gust restrict"},
        {&m.coarse_solve, words(coarse_solve_comp), "gust coarse_solve"},
        {&m.cg, words(cg_comp), "gust cg"},
        {&m.jacobi, words(jacobi_comp), "gust jacobi"},
        {&m.project, words(project_comp), "gust project"},
        {&m.extend, words(extend_comp), "gust extend"},
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
    // advect.comp and smooth.comp once per mode (SolverPush::mode) the solver uses, the mode a
    // specialization constant: a compiler then keeps only that mode's code, where a CPU device would
    // execute every mode's.
    auto create_modes = [&](std::span<gpu::Pipeline> out, std::span<const std::uint32_t> code,
                            const char* name, std::span<const std::uint32_t> modes) -> Status {
        for (const std::uint32_t mode : modes) {
            const std::uint32_t constants[] = {mode};
            auto pipeline = gpu::Pipeline::compute(ctx, name, code, sizeof(SolverPush), constants);
            if (!pipeline) return pipeline.status();
            out[mode] = std::move(*pipeline);
        }
        return {};
    };
    static constexpr std::uint32_t kMacCormackModes[] = {shaderio::kAdvectForward, shaderio::kAdvectBackward,
                                                         shaderio::kAdvectCorrect},
                                   kSemiLagrangianMode[] = {shaderio::kAdvectSemiLagrangian},
                                   kForcesMode[] = {shaderio::kAdvectForces};
    static constexpr std::uint32_t kPcgModes[] = {shaderio::kSmoothFirst, shaderio::kSmoothDown,
                                                  shaderio::kSmoothUp, shaderio::kSmoothUpBeta},
                                   kMultigridModes[] = {shaderio::kSmoothDown, shaderio::kSmoothUp,
                                                        shaderio::kSmoothFirstPlain};
    const std::span<const std::uint32_t> advect_modes =
        desc.advection == Advection::MacCormack       ? std::span<const std::uint32_t>(kMacCormackModes)
        : desc.advection == Advection::SemiLagrangian ? std::span<const std::uint32_t>(kSemiLagrangianMode)
                                                      : std::span<const std::uint32_t>(kForcesMode);
    const std::span<const std::uint32_t> smooth_modes =
        desc.pressure == PressureSolver::MultigridPCG ? std::span<const std::uint32_t>(kPcgModes)
        : desc.pressure == PressureSolver::Multigrid  ? std::span<const std::uint32_t>(kMultigridModes)
                                                      : std::span<const std::uint32_t>();
    if (Status s = create_modes(m.advect, words(advect_comp), "gust advect", advect_modes); !s) return s;
    if (Status s = create_modes(m.smooth, words(smooth_comp), "gust smooth", smooth_modes); !s) return s;
    m.coarse_level = solver->levels_ - 1;
    while (m.coarse_level > 0 && cells_of(m.levels[m.coarse_level - 1].dims) <= shaderio::kCoarseCells)
        --m.coarse_level;

    const GridLevel& last = m.levels.back();
    const std::uint64_t all_cells = last.cells + std::uint64_t(last.dims.x) * last.dims.y * last.dims.z;
    const std::uint64_t all_faces = last.faces + std::uint64_t(shaderio::faces_total(last.dims));
    const std::uint64_t faces = solver->face_count(), cells = solver->cell_count();
    const std::uint64_t words_per_cell = detail::cell_words(desc.voxels_per_cell);
    const std::uint64_t open_words = shaderio::open_count_words(std::uint32_t(faces));
    const std::uint64_t nodes = 1 + shaderio::kCellParts * cells; // the fill's; fluid_node() adds one a cell
    // Partial sums: one per workgroup of the widest reducing pass (level-0 cells or level-0 tiles).
    const LevelDispatch level0_groups = groups_for(cells), level0_tiles = tiles_for(m.levels[0].dims);
    const std::uint64_t partials =
        std::max<std::uint64_t>(std::uint64_t(level0_groups.x) * level0_groups.y,
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
    b.tolerance = desc.tolerance;
    b.vorticity_strength = desc.vorticity;
    b.smoothing = desc.smoothing;
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
    });
    if (!cleared) return cleared;
    return solver;
}

Status WindSolver::set_ambient(glm::vec3 velocity) {
    if (Status s = detail::validate_ambient(velocity); !s) return s;
    ambient_ = velocity;
    if (last_dt_ > 0.0f) return Status{};
    const std::pmr::vector<float> faces =
        detail::uniform_faces(glm::ivec3(desc_.cells), velocity, ctx_.memory());
    Impl& m = *impl_;
    return upload(ctx_, const_cast<gpu::Buffer&>(m.current_velocity()), faces.data(),
                  faces.size() * sizeof(float));
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
    impl_->b.texels = texels.address();
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
        m.record_sample_pass(ctx_, cmd, shaderio::kSampleCells, cell_count());
    });
    if (!s) return s;
    std::vector<glm::vec3> out(cell_count());
    std::memcpy(out.data(), out_buffer->mapped(), bytes);
    return out;
}

Result<std::pmr::vector<glm::vec3>> WindSolver::sample(std::span<const glm::vec3> points) {
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
        record_sample(cmd, m.points.address(), m.samples.address(), std::uint32_t(points.size()));
    });
    if (!s) return s;
    std::memcpy(out.data(), m.samples.mapped(), bytes);
    return out;
}

void WindSolver::record_sample(VkCommandBuffer cmd, VkDeviceAddress points, VkDeviceAddress samples,
                               std::uint32_t count) {
    Impl& m = *impl_;
    m.b.origin = origin_;
    m.b.ambient = ambient_;
    m.b.points = points;
    m.b.samples = samples;
    m.b.point_count = count;
    m.record_sample_pass(ctx_, cmd, shaderio::kSamplePoints, count);
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
    m.record_sample_pass(ctx_, cmd, shaderio::kSampleTexels, cell_count());
}

Status WindSolver::scroll(glm::ivec3 cells) {
    if (cells == glm::ivec3(0)) return Status{};
    return ctx_.submit_and_wait([&](VkCommandBuffer cmd) { record_scroll(cmd, cells); });
}

void WindSolver::record_scroll(VkCommandBuffer cmd, glm::ivec3 cells) {
    if (cells == glm::ivec3(0)) return;
    Impl& m = *impl_;
    m.b.ambient = ambient_;
    m.put_bindings(ctx_, cmd);
    SolverPush push{};
    push.bindings = m.bindings.address();
    push.shift = cells;
    push.swap = m.swap;
    const LevelDispatch g = groups_for(std::max(face_count(), cell_count()));
    m.scroll.bind(cmd, &push, sizeof(push));
    m.scroll.dispatch(cmd, g.x, g.y, g.z);
    gpu::barrier(ctx_, cmd);
    m.swap ^= 1u;
    // φ was moved into the scratch array; the last step's vorticity would no longer line up, so the next
    // step's confinement starts from none.
    const VkBufferCopy phi{0, 6 * cell_count() * sizeof(float), cell_count() * sizeof(float)};
    ctx_.vk().vkCmdCopyBuffer(cmd, m.scratch.handle(), m.cg_cells.handle(), 1, &phi);
    ctx_.vk().vkCmdFillBuffer(cmd, m.vorticity_buf.handle(), 0, VK_WHOLE_SIZE, 0);
    gpu::barrier(ctx_, cmd);
    m.solids_stale = true;
    origin_ += glm::vec3(cells) * desc_.cell_size;
}

Result<WindStats> WindSolver::step(float dt, const SolidSource* solid) {
    if (Status s = detail::validate_dt(dt); !s) return s;
    Status recorded = ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
        record_passes(cmd, dt, solid);
        record_readback(cmd, impl_->state_readback.handle(), 0);
    });
    if (!recorded) return recorded;
    WindStats stats = stats_from(impl_->state_readback.mapped());
    stats.ms = impl_->profiler.read();
    return stats;
}

Status WindSolver::record_step(VkCommandBuffer cmd, float dt, const SolidSource* solid) {
    if (Status s = detail::validate_dt(dt); !s) return s;
    record_passes(cmd, dt, solid);
    return Status{};
}

std::size_t WindSolver::readback_bytes() {
    return sizeof(SolverState);
}

void WindSolver::record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const {
    gpu::record_readback(ctx_, cmd, impl_->state, sizeof(SolverState), dst, offset);
}

std::uint32_t WindSolver::cycles_per_step() const {
    if (desc_.pressure == PressureSolver::Jacobi)
        return (desc_.max_iterations + detail::kJacobiBlock - 1) / detail::kJacobiBlock;
    return desc_.cycles_per_step > 0 ? std::min(desc_.cycles_per_step, desc_.max_cycles) : cycles_to_record_;
}

void WindSolver::record_passes(VkCommandBuffer cmd, float dt, const SolidSource* solid) {
    Impl& m = *impl_;
    const gpu::Dispatch& vk = ctx_.vk();
    SolverBindings& b = m.b;
    b.origin = origin_;
    b.ambient = ambient_;
    b.open_sides = shaderio::open_sides_for(ambient_);
    b.emitter_count = m.emitter_count;
    b.omni_count = m.omni_count;
    b.tree_nodes = b.tree_masks = b.fragments = b.fragment_count = b.fragment_motion = 0;
    b.tree_levels = 0;
    b.fragment_capacity = 0;
    if (solid && solid->tree) {
        const SparseTree& tree = *solid->tree;
        b.tree_nodes = tree.node_address();
        b.tree_masks = tree.mask_address();
        b.tree_levels = tree.depth();
        b.tree_log2_branching = std::uint32_t(std::countr_zero(tree.branching()));
        b.mask_words = shaderio::mask_words(b.tree_log2_branching);
        b.mask_stride = shaderio::mask_stride(b.tree_log2_branching);
        b.voxel_offset = solid->voxel_offset;
    }
    const SparseTree* tree = solid ? solid->tree : nullptr;
    const std::uint64_t generation = solid ? solid->static_generation : 0;
    const bool all_cells = m.solids_stale || tree != m.last_tree || generation != m.last_static_generation ||
                           b.voxel_offset != m.last_voxel_offset;
    m.solids_stale = false;
    m.last_tree = tree;
    m.last_static_generation = generation;
    m.last_voxel_offset = b.voxel_offset;
    if (solid && solid->fragments && solid->fragment_velocities) {
        b.fragments = solid->fragments;
        b.fragment_count = solid->fragment_count;
        b.fragment_motion = solid->fragment_velocities;
        b.fragment_capacity = std::uint32_t(std::min<std::uint64_t>(solid->fragment_capacity, 0xffffffffu));
    }
    const std::uint32_t levels = levels_;
    const bool warm = desc_.warm_start && m.has_guess;
    const std::uint32_t recorded = cycles_per_step();
    b.cycles_recorded = recorded;
    const LevelDispatch face_groups = groups_for(face_count());
    const LevelDispatch cell_groups = groups_for(cell_count());
    SolverPush push{};
    push.bindings = m.bindings.address();
    push.dt = dt;
    auto run = [&](const gpu::Pipeline& p, LevelDispatch g) {
        push.swap = (push.swap & ~1u) | m.swap;
        p.bind(cmd, &push, sizeof(push));
        p.dispatch(cmd, g.x, g.y, g.z);
        gpu::barrier(ctx_, cmd);
    };
    // Indirect dispatches are the pressure solve's passes, each followed by another dispatch (or one whose
    // run() ends in a full barrier), so a compute barrier suffices.
    auto run_slot = [&](const gpu::Pipeline& p, std::uint32_t slot) {
        push.swap = (push.swap & ~1u) | m.swap;
        p.bind(cmd, &push, sizeof(push));
        p.dispatch_indirect(cmd, m.dispatch.handle(), slot * sizeof(LevelDispatch));
        gpu::compute_barrier(ctx_, cmd);
    };

    m.profiler.reset(cmd);
    m.put_bindings(ctx_, cmd);
    if (m.emitter_count > 0)
        gpu::update(ctx_, cmd, m.emitters, m.emitter_data.data(),
                    m.emitter_count * sizeof(shaderio::GpuEmitter));
    vk.vkCmdFillBuffer(cmd, m.state.handle(), 0, VK_WHOLE_SIZE, 0);
    const VkBufferCopy reset{kDispatchSlots * sizeof(LevelDispatch), 0,
                             kDispatchSlots * sizeof(LevelDispatch)};
    vk.vkCmdCopyBuffer(cmd, m.dispatch.handle(), m.dispatch.handle(), 1, &reset);
    gpu::barrier(ctx_, cmd);

    // The solid boundary in three timed parts: the cells' voxels and the moving fragments (solid), the
    // outside-air fill (fill), the faces' open fractions and solid velocities (faces).
    m.profiler.begin(cmd, "solid");
    push.mode = all_cells ? shaderio::kSolidAll : shaderio::kSolidChanged;
    run(m.solid_cells, cell_groups);
    m.solid_motion.bind(cmd, &push, sizeof(push));
    m.solid_motion.dispatch_indirect(cmd, m.state.handle(), offsetof(SolverState, fragments_dispatch));
    gpu::barrier(ctx_, cmd);
    m.profiler.end(cmd);
    m.profiler.begin(cmd, "fill");
    run(m.fill_link, cell_groups);
    run(m.fill_finish, cell_groups);
    m.profiler.end(cmd);
    m.profiler.begin(cmd, "faces");
    run(m.solid_faces, groups_for(shaderio::open_count_words(std::uint32_t(face_count()))));
    for (const gpu::Pipeline* p : {&m.fluid_link, &m.fluid_finish}) {
        p->bind(cmd, &push, sizeof(push));
        p->dispatch_indirect(cmd, m.state.handle(), offsetof(SolverState, fluid_dispatch));
        gpu::barrier(ctx_, cmd);
    }
    if (levels > 1) {
        const GridLevel& last = m.levels.back();
        run(m.coarse_weights,
            groups_for(last.faces - m.levels[1].faces + std::uint64_t(shaderio::faces_total(last.dims))));
    }
    m.profiler.end(cmd);

    // Advection, the emitters, the ambient wind and vorticity confinement into the other buffer, which
    // then holds the velocity.
    m.profiler.begin(cmd, "advect");
    push.param = detail::emitter_rate(dt, desc_.emitter_response);
    if (desc_.advection == Advection::MacCormack) {
        for (std::uint32_t mode :
             {shaderio::kAdvectForward, shaderio::kAdvectBackward, shaderio::kAdvectCorrect}) {
            push.mode = mode;
            run(m.advect[mode], face_groups);
        }
    } else {
        push.mode = desc_.advection == Advection::SemiLagrangian ? shaderio::kAdvectSemiLagrangian
                                                                 : shaderio::kAdvectForces;
        run(m.advect[push.mode], face_groups);
    }
    m.swap ^= 1u;
    m.profiler.end(cmd);

    if (desc_.viscosity > 0.0f) {
        m.profiler.begin(cmd, "viscosity");
        push.param = desc_.viscosity * dt / (desc_.cell_size * desc_.cell_size);
        std::uint32_t from = shaderio::kFieldVelocity;
        for (std::uint32_t i = 0; i < detail::kViscosityIterations; ++i) {
            push.mode = from;
            run(m.diffuse, face_groups);
            from = shaderio::diffuse_target(from);
        }
        if (from == shaderio::kFieldBack) {
            const VkBufferCopy region{0, 0, face_count() * sizeof(float)};
            vk.vkCmdCopyBuffer(cmd, m.velocity_back.handle(), m.other_velocity().handle(), 1, &region);
            gpu::barrier(ctx_, cmd);
        }
        m.swap ^= 1u;
        m.profiler.end(cmd);
    }

    m.profiler.begin(cmd, "pressure");
    push.mode = warm ? shaderio::kStartWarm : shaderio::kStartCold;
    push.level = 0;
    run(m.start, cell_groups);
    const bool cg = desc_.pressure == PressureSolver::MultigridPCG;
    if (desc_.pressure == PressureSolver::Jacobi) {
        // The baseline starts from zero (no warm start) and relaxes in blocks, each followed by a check.
        vk.vkCmdFillBuffer(cmd, m.cg_cells.handle(), 0, 2 * cell_count() * sizeof(float), 0);
        gpu::barrier(ctx_, cmd);
        for (std::uint32_t block = 0; block < recorded; ++block) {
            for (std::uint32_t i = 0; i < detail::kJacobiBlock; ++i) {
                push.mode = shaderio::kJacobiSweep;
                push.swap = (i & 1u) << 1;
                run_slot(m.jacobi, 0);
            }
            push.mode = shaderio::kJacobiCheck;
            push.swap = 0;
            run_slot(m.jacobi, 0);
        }
    } else {
        const std::uint32_t coarse = m.coarse_level;
        for (std::uint32_t k = 0; k < recorded; ++k) {
            push.swap = (k & 1u) << 1;
            push.iterations = k;
            push.level = 0;
            push.mode = cg ? shaderio::kSmoothFirst : shaderio::kSmoothFirstPlain;
            run_slot(m.smooth[push.mode], shaderio::kTileSlot);
            for (std::uint32_t l = 0; l < coarse; ++l) {
                push.level = l + 1;
                run_slot(m.restrict_, l + 1);
                if (l + 1 == coarse) break;
                push.mode = shaderio::kSmoothDown;
                run_slot(m.smooth[push.mode], shaderio::kTileSlot + l + 1);
            }
            push.level = coarse;
            push.mode = coarse == 0 && cg ? shaderio::kCoarseBeta : shaderio::kCoarseCorrection;
            push.iterations = detail::kCoarseSweeps;
            run_slot(m.coarse_solve, shaderio::kCoarseSlot);
            for (std::uint32_t l = coarse; l-- > 0;) {
                push.level = l;
                push.mode = l == 0 && cg ? shaderio::kSmoothUpBeta : shaderio::kSmoothUp;
                run_slot(m.smooth[push.mode], shaderio::kTileSlot + l);
            }
            if (cg) {
                push.level = 0;
                run_slot(m.cg, 0);
            }
        }
    }
    m.profiler.end(cmd);

    // The gradient and the first pass of the extension, the second, then the cells' end of the step.
    m.profiler.begin(cmd, "project");
    push.swap = 0;
    push.level = 0;
    run(m.project, face_groups);
    m.swap ^= 1u;
    run(m.extend, face_groups);
    m.swap ^= 1u;
    run(m.finish, cell_groups);
    m.profiler.end(cmd);
    last_dt_ = dt;
    m.has_guess = true;
}

gpu::Timings WindSolver::timings(std::uint64_t frame) const {
    return impl_->profiler.read_frame(frame);
}

WindStats WindSolver::stats_from(const void* readback) {
    SolverState st;
    std::memcpy(&st, readback, sizeof(st));
    WindStats stats(ctx_.memory());
    stats.divergence_before = from_bits(st.divergence_before);
    stats.divergence_after = from_bits(st.divergence_after);
    stats.residual = from_bits(st.residual);
    stats.diverged = st.diverged != 0;
    stats.converged = !stats.diverged && stats.residual <= double(desc_.tolerance) * stats.divergence_before;
    const bool jacobi = desc_.pressure == PressureSolver::Jacobi;
    const std::uint32_t per_check = jacobi ? detail::kJacobiBlock : 1;
    stats.cycles = std::min(st.checks, st.recorded) * per_check;
    stats.cycles_recorded = st.recorded * per_check;
    if (!jacobi && desc_.cycles_per_step == 0)
        cycles_to_record_ = detail::cycles_to_record(stats, desc_.max_cycles);
    stats.cut_cells = st.cut_cells;
    stats.fluid_cells = st.fluid_cells;
    stats.sealed_cells = st.sealed_cells;
    stats.moving_fragments = st.fragments;
    return stats;
}

} // namespace gust
