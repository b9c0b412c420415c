// CpuWind's state and the kernels over its host arrays, shared by its step (cpu_wind.cpp) and its solid
// boundary (cpu_wind_solid.cpp).
#pragma once

#include "solver_setup.hpp"

#include <gust/solver/cpu_wind.hpp>
#include <vector>

namespace gust {

namespace shaderio {

/// The kernels over host arrays: the accessors solver_kernels.h asks for, then the kernels themselves.
struct HostKernels {
    glm::ivec3 dims;
    float h = 1.0f;
    glm::vec3 origin{0.0f}, ambient{0.0f};
    uint open_sides = 0;
    std::vector<GridLevel> levels;
    std::vector<GpuEmitter> emitters; ///< omni first (omni_first)
    uint omni = 0;
    std::vector<float> face[kFaceFields]; ///< kField*
    std::vector<float> weights;
    std::vector<float> cell[kCellFields]; ///< kCell*
    std::vector<vec4> vorticity;
    std::vector<vec4> confinement;

    ivec3 grid_dims() const { return dims; }
    float grid_h() const { return h; }
    vec3 grid_origin() const { return origin; }
    uint grid_open_sides() const { return open_sides; }
    float load_face(uint field, int index) const { return face[field][std::size_t(index)]; }
    float load_weight(int index) const { return weights[std::size_t(index)]; }
    float load_cell(uint field, int index) const { return cell[field][std::size_t(index)]; }
    vec4 load_vorticity(int index) const { return vorticity[std::size_t(index)]; }
    vec4 load_confinement(int index) const { return confinement[std::size_t(index)]; }
    float load_phi(int index) const { return cell[kCellPhi][std::size_t(index)]; }
    GridLevel load_level(uint l) const { return levels[l]; }
    uint emitter_count() const { return uint(emitters.size()); }
    uint omni_count() const { return omni; }
    GpuEmitter load_emitter(uint i) const { return emitters[i]; }
    /// CpuWind is one grid, not a nest of cascades: the ambient wind lies beyond it.
    float beyond_component(uint axis, vec3) const { return ambient[int(axis)]; }
    float border_relaxation(uint, ivec3) const { return 0.0f; }
    bool inner_face(uint, ivec3, float& u) const {
        u = 0.0f;
        return false;
    }

#include "solver/solver_kernels.h"
};

} // namespace shaderio

using shaderio::CellBits;
using shaderio::GridLevel;
using shaderio::kCellWords;

struct CpuWind::Impl {
    SolverDesc desc;
    shaderio::HostKernels k;
    std::vector<float> solid_fraction;
    std::vector<std::uint32_t> flags;      ///< shaderio::kCell*
    std::vector<CellBits> parts;           ///< kCellParts per cell
    std::vector<CellBits> fixed;           ///< per cell, its static solid voxels
    std::vector<glm::ivec4> motion;        ///< per cell, as cell_motion
    std::vector<std::uint32_t> roots;      ///< per part node: its set's root (the smallest node id)
    std::vector<glm::ivec4> region_motion; ///< two per root node, as region_motion
    std::uint32_t face_mask[6 * kCellWords];
    float last_dt = 0.0f;
    glm::vec3 ambient_change{0.0f}; ///< set_ambient's change since the last step (WindSolver's likewise)
    bool has_guess = false;         ///< as WindSolver's: φ may start the next solve

    std::size_t faces() const { return std::size_t(shaderio::faces_total(k.dims)); }
    std::size_t cells() const { return std::size_t(k.dims.x) * k.dims.y * k.dims.z; }

    template <typename F> void each_face(F&& f) {
        for (int i = 0; i < int(faces()); ++i) {
            std::uint32_t axis;
            const glm::ivec3 at = shaderio::face_from_index(k.dims, i, axis);
            f(i, axis, at);
        }
    }
    template <typename F> void each_cell(const GridLevel& level, F&& f) {
        const int n = level.dims.x * level.dims.y * level.dims.z;
        for (int i = 0; i < n; ++i)
            f(i, shaderio::cell_from_index(level.dims, i));
    }

    void solid_pass(const CpuSolid* solid, WindStats& stats);
    /// The outside-air fill: roots per part node, and each cell's air (flags, solid fraction).
    void fill(std::uint32_t& sealed_cells);
    /// Seals the cells whose open faces reach no open side (pockets of the pressure equation).
    void seal_pockets(std::uint32_t& sealed_cells);
    CellBits part_of(std::size_t cell, std::uint32_t part) const;
    CellBits air_of(std::size_t cell) const;
    CellBits static_of(std::size_t cell) const;
    /// As solver_common.glsl's solid_of.
    CellBits solid_of(std::size_t cell) const;
    /// As fill_finish.comp's add_contacts.
    void add_contacts(std::size_t cell, std::uint32_t part, std::uint32_t root, CellBits faces[6]);
    /// As solver_common.glsl's region_of.
    glm::ivec4 region_of(std::uint32_t root) const;
    /// As solid_faces.comp's solid_layer_motion and air_cell_motion.
    glm::ivec4 solid_layer_motion(std::size_t i, const CellBits& layer) const;
    glm::ivec4 air_cell_motion(std::size_t i, const CellBits& layer, CellBits faces[6]) const;
    glm::ivec4 solid_motion_of(std::size_t cell) const;
    void extend();
    void coarse_weights();
    void smooth(std::uint32_t l);
    void v_cycle();
    float max_residual();
    float start_solve(bool warm);
    /// check.comp's test: within the tolerance, or diverged (solve_diverged); stops the solve either way.
    struct Check {
        float goal = 0.0f, first = 0.0f, b_max = 0.0f;
        bool diverged = false;
        bool done(float residual) {
            if (residual <= goal) return true;
            diverged = shaderio::solve_diverged(residual, first, b_max);
            return diverged;
        }
    };
    float conjugate_gradients(Check& check, float residual, bool& done, std::uint32_t& checks);
};

} // namespace gust
