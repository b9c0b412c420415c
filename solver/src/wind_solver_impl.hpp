// The GPU solver's state, shared by its creation and API (wind_solver.cpp) and the recording of its step
// (wind_solver_step.cpp).
#pragma once

#include "solver_setup.hpp"

#include <algorithm>
#include <array>
#include <gust/solver/wind_solver.hpp>

namespace gust {

namespace detail {

/// Workgroups of kSolverGroupSize threads over `items`, in rows of at most 65,535.
inline shaderio::LevelDispatch groups_for(std::uint64_t items) {
    const std::uint64_t groups = (items + shaderio::kSolverGroupSize - 1) / shaderio::kSolverGroupSize;
    return {std::uint32_t(std::min<std::uint64_t>(groups, 65535)), std::uint32_t((groups + 65534) / 65535),
            1};
}

} // namespace detail

struct WindSolver::Impl : gpu::HostObject {
    explicit Impl(std::pmr::memory_resource* memory) : levels(memory) {}
    /// advect.comp and smooth.comp specialized to each mode (shaderio::SolverPush::mode) the solver uses.
    std::array<gpu::Pipeline, shaderio::kAdvectModes> advect;
    bool advect_nested = false; ///< advect is specialized for a nest (kNested)
    std::array<gpu::Pipeline, shaderio::kSmoothModes> smooth;
    /// smooth.comp built with GUST_THEN_COARSE, for the pass just above the coarse solve's levels (when it
    /// does not hold level 0), whose last workgroup runs the coarse solve.
    std::array<gpu::Pipeline, shaderio::kSmoothModes> smooth_coarse;
    gpu::Pipeline solid_cells, solid_motion, fill_link, fill_finish, solid_faces, fluid_finish,
        coarse_weights, diffuse, start, coarse_solve, cg, jacobi, project, finish, scroll, sample;
    gpu::Buffer velocity, velocity_tmp, velocity_back, open_counts, weights, solid_velocity, pressure,
        pressure_up, rhs, scratch, cg_cells, partials, cell_solid, cell_parts, cell_static, cell_flags,
        cell_motion, labels, region_motion, vorticity_buf, confinement, emitters, state, dispatch, bindings,
        points, samples, state_readback;
    /// The field before the last step, for the finer cascade's blend in time (WindSolver::couple with an
    /// inner; empty otherwise).
    gpu::Buffer previous;
    gpu::Profiler profiler;
    std::pmr::vector<shaderio::GridLevel> levels;
    /// The first level the coarse solve takes (coarse_levels.glsl): at most kCoarseCells cells.
    std::uint32_t coarse_level = 0;
    std::uint32_t emitter_count = 0;
    std::uint32_t omni_count = 0; ///< the first emitter_data are omni (omni_first)
    std::array<shaderio::GpuEmitter, shaderio::kMaxEmitters> emitter_data{}; ///< written by each step
    /// Which of the two velocity buffers holds the velocity (shaderio::SolverPush::swap bit 0): a pass writes
    /// the next field into the other, and they trade places instead of being copied.
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
    /// SolverPush::nest of this solver's passes.
    std::uint32_t nest() const {
        return (b.outer != 0 ? shaderio::kNestOuter : 0u) | (b.inner != 0 ? shaderio::kNestInner : 0u);
    }
    /// Records the bindings with `current` at the buffer that now holds the field, for the cascades nested
    /// with this one (WindSolver::couple), at the end of a step or scroll.
    void put_current(const gpu::Context& ctx, VkCommandBuffer cmd) {
        b.current = current_velocity().address();
        put_bindings(ctx, cmd);
    }
    /// Records `pass` (scroll.comp or sample.comp) in `mode` (shaderio::kScroll*, kSample*) over `count`
    /// threads, moving by `shift` cells (scroll.comp), after the bindings `b` the caller set, and a barrier.
    void record_single_pass(const gpu::Context& ctx, VkCommandBuffer cmd, const gpu::Pipeline& pass,
                            std::uint32_t mode, glm::ivec3 shift, std::uint64_t count) {
        put_bindings(ctx, cmd);
        shaderio::SolverPush push{};
        push.bindings = bindings.address();
        push.nest = nest();
        push.mode = mode;
        push.shift = shift;
        push.swap = swap;
        const shaderio::LevelDispatch g = detail::groups_for(count);
        pass.bind(cmd, &push, sizeof(push));
        pass.dispatch(cmd, g.x, g.y, g.z);
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
    shaderio::SolverBindings b{};
    /// The texels every step writes in its last pass (bind_texels; 0: none). b.texels holds them between
    /// passes: record_texels points it at its own buffer for one pass only.
    VkDeviceAddress bound_texels = 0;
};

} // namespace gust
