// CpuWind's set-up, its step in the GPU's order of passes and its pressure solve; the solid boundary is in
// cpu_wind_solid.cpp.
#include "cpu_wind_impl.hpp"

#include <algorithm>
#include <cmath>

namespace gust {

CpuWind::~CpuWind() = default;

Result<std::unique_ptr<CpuWind>> CpuWind::create(const SolverDesc& desc) {
    if (Status s = validate(desc); !s) return s;
    std::unique_ptr<CpuWind> wind(new CpuWind());
    wind->impl_ = std::make_unique<Impl>();
    Impl& m = *wind->impl_;
    m.desc = desc;
    m.k.dims = glm::ivec3(desc.cells);
    m.k.h = desc.cell_size;
    m.k.origin = desc.origin;
    const auto levels = detail::build_levels(desc.cells, desc.cell_size);
    m.k.levels.assign(levels.begin(), levels.end());
    const GridLevel& last = m.k.levels.back();
    const std::size_t all_cells = last.cells + std::size_t(last.dims.x) * last.dims.y * last.dims.z;
    const std::size_t all_faces = last.faces + std::size_t(shaderio::faces_total(last.dims));
    for (auto& f : m.k.face)
        f.assign(m.faces(), 0.0f);
    m.k.weights.assign(all_faces, 1.0f);
    for (auto& c : m.k.cell)
        c.assign(all_cells, 0.0f);
    m.k.vorticity.assign(m.cells(), glm::vec4(0.0f));
    m.k.confinement.assign(m.cells(), glm::vec4(0.0f));
    m.solid_fraction.assign(m.cells(), 0.0f);
    m.flags.assign(m.cells(), 0);
    m.parts.assign(m.cells() * shaderio::kCellParts, shaderio::bits_none());
    m.fixed.assign(m.cells(), shaderio::bits_none());
    m.motion.assign(m.cells(), glm::ivec4(0));
    m.roots.assign(1 + shaderio::kCellParts * m.cells(), 0);
    m.region_motion.assign(2 * m.roots.size(), glm::ivec4(0));
    detail::face_masks(desc.voxels_per_cell, m.face_mask);
    return wind;
}

Status CpuWind::set_ambient(glm::vec3 velocity) {
    if (Status s = detail::validate_ambient(velocity); !s) return s;
    if (impl_->last_dt > 0.0f) impl_->ambient_change += velocity - impl_->k.ambient;
    impl_->k.ambient = velocity;
    if (impl_->last_dt == 0.0f) {
        const auto faces = detail::uniform_faces(impl_->k.dims, velocity);
        impl_->k.face[shaderio::kFieldVelocity].assign(faces.begin(), faces.end());
    }
    return Status{};
}

Status CpuWind::set_emitters(std::span<const Emitter> emitters) {
    if (Status s = validate(emitters); !s) return s;
    impl_->k.emitters.resize(emitters.size());
    impl_->k.omni = detail::omni_first(emitters, impl_->k.emitters);
    return Status{};
}

Status CpuWind::set_velocity(std::span<const float> faces) {
    if (faces.size() != impl_->faces()) return Status::failure("wrong number of face velocities");
    impl_->k.face[shaderio::kFieldVelocity].assign(faces.begin(), faces.end());
    impl_->has_guess = false;
    return Status{};
}

Status CpuWind::scroll(glm::ivec3 cells) {
    Impl& m = *impl_;
    std::vector<float> moved(m.faces());
    m.each_face([&](int i, std::uint32_t axis, glm::ivec3 f) {
        const glm::ivec3 src = f + cells;
        const glm::ivec3 lattice = m.k.dims + shaderio::axis_unit(axis);
        const bool inside =
            glm::all(glm::greaterThanEqual(src, glm::ivec3(0))) && glm::all(glm::lessThan(src, lattice));
        moved[std::size_t(i)] =
            inside ? m.k.face[0][std::size_t(shaderio::face_index(m.k.dims, axis, src))] : m.k.ambient[axis];
    });
    m.k.face[0] = std::move(moved);
    std::vector<float>& phi = m.k.cell[shaderio::kCellPhi];
    std::vector<float> shifted(m.cells());
    m.each_cell(m.k.levels[0], [&](int i, glm::ivec3 c) {
        const glm::ivec3 src = c + cells;
        shifted[std::size_t(i)] = shaderio::inside_cells(m.k.dims, src)
                                      ? phi[std::size_t(shaderio::cell_index(m.k.dims, src))]
                                      : 0.0f;
    });
    std::copy(shifted.begin(), shifted.end(), phi.begin());
    m.k.origin += glm::vec3(cells) * m.desc.cell_size;
    return Status{};
}

const std::vector<float>& CpuWind::velocity() const {
    return impl_->k.face[shaderio::kFieldVelocity];
}
const std::vector<float>& CpuWind::solid_velocity() const {
    return impl_->k.face[shaderio::kFieldSolid];
}
const std::vector<float>& CpuWind::solid_fraction() const {
    return impl_->solid_fraction;
}
const std::vector<float>& CpuWind::open_fraction() const {
    return impl_->k.weights;
}
std::vector<float> CpuWind::pressure() const {
    const float scale = impl_->last_dt > 0.0f ? detail::kAirDensity / impl_->last_dt : 0.0f;
    std::vector<float> p(impl_->k.cell[shaderio::kCellPhi].begin(),
                         impl_->k.cell[shaderio::kCellPhi].begin() + std::ptrdiff_t(impl_->cells()));
    for (float& v : p)
        v *= scale;
    return p;
}

// extend.comp's two passes: velocity -> tmp (layer 1) -> velocity (layer 2).
void CpuWind::Impl::extend() {
    std::vector<float>& u = k.face[shaderio::kFieldVelocity];
    std::vector<float>& tmp = k.face[shaderio::kFieldTmp];
    each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        tmp[std::size_t(i)] = k.extend_face(shaderio::kFieldVelocity, a, f, 1);
    });
    each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        u[std::size_t(i)] = k.extend_face(shaderio::kFieldTmp, a, f, 2);
    });
}

void CpuWind::Impl::coarse_weights() {
    for (std::uint32_t l = 1; l < k.levels.size(); ++l) {
        const GridLevel& level = k.levels[l];
        for (int i = 0; i < shaderio::faces_total(level.dims); ++i) {
            std::uint32_t axis;
            const glm::ivec3 f = shaderio::face_from_index(level.dims, i, axis);
            k.weights[level.faces + std::size_t(i)] = k.coarse_weight(l, axis, f);
        }
    }
}

void CpuWind::Impl::smooth(std::uint32_t l) {
    const GridLevel& level = k.levels[l];
    for (std::uint32_t s = 0; s < desc.smoothing; ++s)
        for (std::uint32_t colour = 0; colour < 2; ++colour)
            each_cell(level, [&](int i, glm::ivec3 c) {
                if (std::uint32_t(c.x + c.y + c.z) % 2 != colour) return;
                k.cell[shaderio::kCellPressure][level.cells + std::size_t(i)] =
                    k.relax_cell(level, c, shaderio::kCellPressure);
            });
}

void CpuWind::Impl::v_cycle() {
    std::vector<float>& phi = k.cell[shaderio::kCellPressure];
    std::vector<float>& rhs = k.cell[shaderio::kCellRhs];
    const std::uint32_t levels = std::uint32_t(k.levels.size());
    for (std::uint32_t l = 0; l + 1 < levels; ++l) {
        smooth(l);
        const GridLevel& coarse = k.levels[l + 1];
        each_cell(coarse, [&](int i, glm::ivec3 c) {
            rhs[coarse.cells + std::size_t(i)] = k.restrict_cell(k.levels[l], c);
            phi[coarse.cells + std::size_t(i)] = 0.0f;
        });
    }
    const GridLevel& coarsest = k.levels[levels - 1];
    for (std::uint32_t sweep = 0; sweep < 2 * detail::kCoarseSweeps; ++sweep)
        each_cell(coarsest, [&](int i, glm::ivec3 c) {
            if (std::uint32_t(c.x + c.y + c.z) % 2 == sweep % 2)
                phi[coarsest.cells + std::size_t(i)] = k.relax_cell(coarsest, c, shaderio::kCellPressure);
        });
    for (std::uint32_t l = levels - 1; l-- > 0;) {
        const GridLevel& level = k.levels[l];
        std::vector<float> add(std::size_t(level.dims.x) * level.dims.y * level.dims.z);
        each_cell(level, [&](int i, glm::ivec3 c) {
            add[std::size_t(i)] = k.prolong_cell(level, k.levels[l + 1], c, shaderio::kCellPressure);
        });
        for (std::size_t i = 0; i < add.size(); ++i)
            phi[level.cells + i] += add[i];
        smooth(l);
    }
}

// start.comp's warm start over b in kCellTarget and the last step's φ (kCellPhi): x0 = s·φ (s fitted by
// warm_scale, 0 when not warm) and its residual r0 = b − s·Lφ, placed as the solver takes them (conjugate
// gradients: x0 in x, r0 in rhs, the V-cycle's φ = 0; otherwise x0 in the V-cycle's φ). Returns max |r0|.
float CpuWind::Impl::start_solve(bool warm) {
    using namespace shaderio;
    std::vector<float>& phi = k.cell[kCellPressure];
    const std::vector<float>& last = k.cell[kCellPhi];
    std::vector<float>& q = k.cell[kCellScratch];
    const std::vector<float>& b = k.cell[kCellTarget];
    float s = 0.0f;
    if (warm) {
        double bq = 0.0, qq = 0.0;
        each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            const float lap = k.laplacian_cell(k.levels[0], c, kCellPhi);
            q[std::size_t(i)] = lap;
            bq += double(b[std::size_t(i)]) * lap;
            qq += double(lap) * lap;
        });
        s = warm_scale(float(bq), float(qq));
    }
    const bool pcg = desc.pressure == PressureSolver::MultigridPCG;
    float worst = 0.0f;
    for (std::size_t i = 0; i < cells(); ++i) {
        const float x0 = s != 0.0f ? s * last[i] : 0.0f;
        const float r0 = s != 0.0f ? b[i] - s * q[i] : b[i];
        if (pcg) {
            k.cell[kCellSolution][i] = x0;
            k.cell[kCellRhs][i] = r0;
            phi[i] = 0.0f;
        } else {
            phi[i] = x0;
        }
        worst = std::max(worst, std::abs(r0));
    }
    return worst;
}

// The GPU's passes in the GPU's order (wind_solver.cpp), with the dot products summed in double, from
// x, r, b as start_solve left them. The residual is recomputed from x each iteration rather than updated:
// the update drifts from b − Lx in float by more than the tolerance.
float CpuWind::Impl::conjugate_gradients(Check& check, float residual, bool& done, std::uint32_t& checks) {
    using namespace shaderio;
    std::vector<float>& z = k.cell[kCellPressure];
    std::vector<float>& r = k.cell[kCellRhs];
    std::vector<float>& x = k.cell[kCellSolution];
    std::vector<float>& p = k.cell[kCellDirection];
    std::vector<float>& b = k.cell[kCellTarget];
    std::vector<float>& old_r = k.cell[kCellOldResidual];
    const std::size_t n = cells();
    std::fill_n(p.begin(), n, 0.0f);
    std::fill_n(old_r.begin(), n, 0.0f);
    float old_rz = 0.0f;
    for (std::uint32_t it = 0; it < desc.max_cycles && !done; ++it) {
        v_cycle();
        double rz = 0.0, z_old_r = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            rz += double(r[i]) * z[i];
            z_old_r += double(old_r[i]) * z[i];
        }
        const float beta = cg_beta(float(rz), float(z_old_r), old_rz);
        old_rz = float(rz);
        for (std::size_t i = 0; i < n; ++i)
            p[i] = z[i] + beta * p[i];
        double pq = 0.0;
        each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            pq += double(p[std::size_t(i)]) * k.laplacian_cell(k.levels[0], c, kCellDirection);
        });
        const float alpha = cg_alpha(old_rz, float(pq));
        for (std::size_t i = 0; i < n; ++i) {
            x[i] += alpha * p[i];
            old_r[i] = r[i];
            z[i] = 0.0f;
        }
        residual = 0.0f;
        each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            r[std::size_t(i)] = b[std::size_t(i)] - k.laplacian_cell(k.levels[0], c, kCellSolution);
            residual = std::max(residual, std::abs(r[std::size_t(i)]));
        });
        done = check.done(residual);
        if (!done) ++checks;
    }
    std::copy_n(x.begin(), n, z.begin());
    return residual;
}

float CpuWind::Impl::max_residual() {
    float worst = 0.0f;
    each_cell(k.levels[0],
              [&](int, glm::ivec3 c) { worst = std::max(worst, std::abs(k.residual_cell(k.levels[0], c))); });
    return worst;
}

Result<WindStats> CpuWind::step(float dt, const CpuSolid* solid) {
    if (Status s = detail::validate_dt(dt); !s) return s;
    Impl& m = *impl_;
    auto& k = m.k;
    const SolverDesc& desc = m.desc;
    k.open_sides = shaderio::open_sides_for(k.ambient);
    if (solid) {
        const glm::ivec3 voxels = k.dims * int(desc.voxels_per_cell);
        if (!solid->occupied.empty() && solid->occupied.size() != std::size_t(voxels.x) * voxels.y * voxels.z)
            return Status::failure("CpuSolid::occupied must hold one byte per voxel of the grid");
    }
    WindStats stats;
    // solid_cells.comp also makes each cell's confinement force and speed from the field the step starts
    // with.
    if (desc.vorticity != 0.0f)
        m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            k.confinement[std::size_t(i)] = k.cell_confinement(c, desc.vorticity);
        });
    m.solid_pass(solid, stats);
    if (solid) stats.moving_fragments = std::uint32_t(solid->fragments.size());
    m.coarse_weights();

    std::vector<float>& u = k.face[shaderio::kFieldVelocity];
    // scroll.comp's kScrollAmbientChange.
    if (m.ambient_change != glm::vec3(0.0f)) {
        m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
            if (k.face_open(a, f)) u[std::size_t(i)] += m.ambient_change[a];
        });
        m.ambient_change = glm::vec3(0.0f);
    }
    std::vector<float>& tmp = k.face[shaderio::kFieldTmp];
    std::vector<float>& forward = k.face[shaderio::kFieldScratch];
    if (desc.advection != Advection::None) {
        if (desc.advection == Advection::MacCormack) {
            std::vector<float>& low = k.face[shaderio::kFieldLow];
            std::vector<float>& high = k.face[shaderio::kFieldHigh];
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                glm::vec2 range;
                forward[std::size_t(i)] = k.advect_face_range(a, f, dt, range);
                low[std::size_t(i)] = range.x;
                high[std::size_t(i)] = range.y;
            });
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                tmp[std::size_t(i)] = k.maccormack_face(a, f, dt);
            });
        } else {
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                tmp[std::size_t(i)] = k.advect_face(shaderio::kFieldVelocity, a, f, dt);
            });
        }
    }
    // advect.comp's one pass: the advected value (tmp; the velocity itself without advection) with the
    // emitters, the ambient wind and confinement from the vorticity the last step ended with, while the
    // velocity still holds the old field (which confinement's step limit reads).
    const std::vector<float>& advected = desc.advection != Advection::None ? tmp : u;
    const float rate = detail::emitter_rate(dt, desc.emitter_response);
    std::vector<float> forced(m.faces());
    m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        forced[std::size_t(i)] = k.forced_face(advected[std::size_t(i)], a, f, rate, dt, desc.vorticity);
    });
    u = std::move(forced);
    if (desc.viscosity > 0.0f) {
        const float alpha = desc.viscosity * dt / (desc.cell_size * desc.cell_size);
        std::uint32_t from = shaderio::kFieldVelocity;
        for (std::uint32_t it = 0; it < detail::kViscosityIterations; ++it) {
            const std::uint32_t to = shaderio::diffuse_target(from);
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                k.face[to][std::size_t(i)] = k.diffuse_face(from, a, f, alpha);
            });
            from = to;
        }
        u = k.face[from];
    }

    // Projection, in the GPU's order of passes and checks. φ still holds the last step's solution.
    std::vector<float>& phi = k.cell[shaderio::kCellPressure];
    std::vector<float>& rhs = k.cell[shaderio::kCellRhs];
    float before = 0.0f;
    m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        float diag, off;
        k.cell_operator(k.levels[0], c, shaderio::kCellPressure, 0.0f, diag, off);
        const float d = diag > 0.0f ? k.cell_divergence(c) : 0.0f;
        rhs[std::size_t(i)] = d;
        k.cell[shaderio::kCellTarget][std::size_t(i)] = d;
        before = std::max(before, std::abs(d));
        if (diag > 0.0f) ++stats.fluid_cells;
    });
    // The goal is relative to b, not to the first residual: a warm start that begins near the solution
    // must still reach tolerance · max |b|.
    // The Jacobi baseline starts from zero, as jacobi.comp does.
    const bool jacobi = desc.pressure == PressureSolver::Jacobi;
    float residual = m.start_solve(desc.warm_start && m.has_guess && !jacobi);
    Impl::Check check{desc.tolerance * before, residual, before};
    std::uint32_t checks = 0;
    bool done = check.done(residual);
    if (!done) ++checks;
    if (desc.pressure == PressureSolver::Multigrid) {
        for (std::uint32_t cycle = 0; cycle < desc.max_cycles && !done; ++cycle) {
            m.v_cycle();
            residual = m.max_residual();
            done = check.done(residual);
            if (!done) ++checks;
        }
        stats.cycles = std::min(checks, desc.max_cycles);
    } else if (desc.pressure == PressureSolver::MultigridPCG) {
        residual = m.conjugate_gradients(check, residual, done, checks);
        stats.cycles = std::min(checks, desc.max_cycles);
    } else {
        std::vector<float>& other = k.cell[shaderio::kCellSolutionB];
        std::vector<float> next(m.cells());
        const std::uint32_t blocks = (desc.max_iterations + detail::kJacobiBlock - 1) / detail::kJacobiBlock;
        for (std::uint32_t block = 0; block < blocks && !done; ++block) {
            for (std::uint32_t it = 0; it < detail::kJacobiBlock; ++it) {
                const std::uint32_t from = (it & 1) ? shaderio::kCellSolutionB : shaderio::kCellPressure;
                std::vector<float>& to = (it & 1) ? phi : other;
                m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
                    next[std::size_t(i)] = k.jacobi_cell(k.levels[0], c, from);
                });
                std::copy(next.begin(), next.end(), to.begin());
            }
            residual = m.max_residual();
            done = check.done(residual);
            if (!done) ++checks;
        }
        stats.cycles = std::min(checks, blocks) * detail::kJacobiBlock;
    }
    stats.diverged = check.diverged;
    stats.divergence_before = before;
    // finish.comp's φ (kCellPhi, 0 after a diverged solve), which the projection reads.
    std::vector<float>& result = k.cell[shaderio::kCellPhi];
    for (std::size_t i = 0; i < m.cells(); ++i)
        result[i] = check.diverged ? 0.0f : phi[i];
    std::vector<float> projected(m.faces());
    m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        projected[std::size_t(i)] = k.project_face(a, f, !check.diverged);
    });
    u = std::move(projected);
    m.extend();
    // finish.comp: the final residual and divergence, and the vorticity the next step's confinement reads.
    float after = 0.0f, left = 0.0f;
    m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        float diag, lap;
        k.cell_operator(k.levels[0], c, shaderio::kCellPhi, result[std::size_t(i)], diag, lap);
        if (diag > 0.0f) {
            after = std::max(after, std::abs(k.cell_divergence(c)));
            left = std::max(left, std::abs(k.cell[shaderio::kCellTarget][std::size_t(i)] - lap));
        }
        k.vorticity[std::size_t(i)] = k.cell_vorticity(c);
    });
    stats.divergence_after = after;
    stats.residual = left;
    stats.converged = !check.diverged && left <= desc.tolerance * before;
    m.last_dt = dt;
    m.has_guess = true;
    return stats;
}

} // namespace gust
