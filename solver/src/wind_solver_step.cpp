// The recording of a step: its passes in order (docs/solver.md), and its stats.
#include "tree/tree_io.h"
#include "wind_solver_impl.hpp"

#include <bit>
#include <cstring>

namespace gust {

namespace {
using detail::groups_for;
using shaderio::GridLevel;
using shaderio::kDispatchSlots;
using shaderio::LevelDispatch;
using shaderio::SolverBindings;
using shaderio::SolverPush;
using shaderio::SolverState;

float from_bits(std::uint32_t bits) {
    return std::bit_cast<float>(bits);
}

} // namespace

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
    b.open_sides = b.outer != 0 ? shaderio::nested_open_sides(ambient_) : shaderio::open_sides_for(ambient_);
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
    push.nest = m.nest();
    push.bindings = m.bindings.address();
    push.dt = dt;
    auto run = [&](const gpu::Pipeline& p, LevelDispatch g) {
        push.swap = (push.swap & ~1u) | m.swap;
        p.bind(cmd, &push, sizeof(push));
        p.dispatch(cmd, g.x, g.y, g.z);
        gpu::barrier(ctx_, cmd);
    };
    // A dispatch that the next one need not wait for: no barrier, so the two run as one stage; the barrier
    // after the next one orders both before what follows.
    auto run_beside = [&](const gpu::Pipeline& p, LevelDispatch g) {
        push.swap = (push.swap & ~1u) | m.swap;
        p.bind(cmd, &push, sizeof(push));
        p.dispatch(cmd, g.x, g.y, g.z);
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
    // The moving fragments' sums run beside the fill's links, which read no motion and only the bits of the
    // cells' flags that solid_cells set (solid_motion adds kCellMoving with an atomic); fill_finish reads
    // both.
    m.solid_motion.bind(cmd, &push, sizeof(push));
    m.solid_motion.dispatch_indirect(cmd, m.state.handle(), offsetof(SolverState, fragments_dispatch));
    m.profiler.end(cmd);
    m.profiler.begin(cmd, "fill");
    run(m.fill_link, cell_groups);
    run(m.fill_finish, cell_groups);
    m.profiler.end(cmd);
    m.profiler.begin(cmd, "faces");
    run(m.solid_faces, groups_for(shaderio::open_count_words(std::uint32_t(face_count()))));
    m.fluid_finish.bind(cmd, &push, sizeof(push));
    m.fluid_finish.dispatch_indirect(cmd, m.state.handle(), offsetof(SolverState, fluid_dispatch));
    gpu::barrier(ctx_, cmd);
    // The coarse levels' weights run beside the advection: only the pressure solve's coarse levels read
    // them, and they read no velocity.
    if (levels > 1) {
        const GridLevel& last = m.levels.back();
        run_beside(m.coarse_weights, groups_for(last.faces - m.levels[1].faces +
                                                std::uint64_t(shaderio::faces_total(last.dims))));
    }
    m.profiler.end(cmd);

    // A change of the ambient wind since the last step (unless record_ambient_change took it already).
    record_ambient_change(cmd);

    // The solve's start (docs/solver.md, "The solve's start"): its first pass makes b. The warm start's scale
    // needs b·q, which MacCormack's correction sums over the faces it writes (q made beside its forward pass)
    // where detail::scale_in_advection holds, else a start pass.
    const bool jacobi = desc_.pressure == PressureSolver::Jacobi;
    const bool scale_in_advection = warm && detail::scale_in_advection(desc_);

    // Advection, the emitters, the ambient wind and vorticity confinement into the other buffer, which
    // then holds the velocity.
    m.profiler.begin(cmd, "advect");
    push.param = detail::emitter_rate(dt, desc_.emitter_response);
    if (desc_.advection == Advection::MacCormack) {
        if (scale_in_advection) {
            push.mode = shaderio::kStartQ;
            run_beside(m.start, cell_groups);
        }
        push.mode = shaderio::kAdvectForward;
        run(m.advect[push.mode], face_groups);
        push.mode = scale_in_advection ? shaderio::kAdvectCorrectScale : shaderio::kAdvectCorrect;
        run(m.advect[push.mode], face_groups);
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
        if (from == shaderio::kFieldScratch) {
            const VkBufferCopy region{0, 0, face_count() * sizeof(float)};
            vk.vkCmdCopyBuffer(cmd, m.velocity_back.handle(), m.other_velocity().handle(), 1, &region);
            gpu::barrier(ctx_, cmd);
        }
        m.swap ^= 1u;
        m.profiler.end(cmd);
    }

    m.profiler.begin(cmd, "pressure");
    push.level = 0;
    const bool cg = desc_.pressure == PressureSolver::MultigridPCG;
    if (warm && !jacobi && !scale_in_advection) {
        push.mode = shaderio::kStartScale;
        run(m.start, cell_groups);
    }
    if (jacobi) {
        // The baseline starts from zero (no warm start) and relaxes in blocks, each followed by a check.
        push.mode = shaderio::kStartRhs;
        run(m.start, cell_groups);
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
        // PassLayout::FewerStages: the smoothing just above the coarse solve's levels runs the coarse solve
        // in its last workgroup.
        const bool coarse_fused = desc_.layout == PassLayout::FewerStages && coarse > 0;
        auto smoothing = [&](std::uint32_t level, std::uint32_t mode) -> const gpu::Pipeline& {
            return coarse_fused && level + 1 == coarse ? m.smooth_coarse[mode] : m.smooth[mode];
        };
        for (std::uint32_t k = 0; k < recorded; ++k) {
            push.swap = (k & 1u) << 1;
            push.iterations = k;
            push.level = 0;
            push.mode = k == 0 ? shaderio::kSmoothStart
                        : cg   ? shaderio::kSmoothFirst
                               : shaderio::kSmoothFirstPlain;
            run_slot(smoothing(0, push.mode), shaderio::kTileSlot);
            // Each level below restricts its right-hand side from the finer level's residual in its own
            // smoothing (or in the coarse solve), so going down costs one dispatch a level.
            for (std::uint32_t l = 1; l < coarse; ++l) {
                push.level = l;
                push.mode = shaderio::kSmoothDown;
                run_slot(smoothing(l, push.mode), shaderio::kTileSlot + l);
            }
            if (!coarse_fused) {
                push.level = coarse;
                push.mode = coarse == 0 && cg ? shaderio::kCoarseBeta : shaderio::kCoarseCorrection;
                push.iterations = detail::kCoarseSweeps;
                run_slot(m.coarse_solve, shaderio::kCoarseSlot);
            }
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

    // The gradient with both passes of the extension, then the cells' end of the step.
    m.profiler.begin(cmd, "project");
    push.swap = 0;
    push.level = 0;
    run(m.project, face_groups);
    m.swap ^= 1u;
    run(m.finish, cell_groups);
    m.profiler.end(cmd);
    m.put_current(ctx_, cmd);
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
