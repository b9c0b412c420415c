// The wind solver's memory traffic per pass of one step, counted from its kernels (shaders/solver/*.comp and
// solver_kernels.h) as solver/src/wind_solver.cpp records them: the byte model of gust_bench_solver's
// "Bytes per step against the bandwidth floor" table.
//
// Counting rule, for an interior face or cell (all neighbours inside the grid, every face open), 4 bytes per
// float or word:
//   accessed: every load and store a thread issues, as if no cache existed (an advected face's velocity at
//             its centre, its velocity sample at the midpoint and its field sample are 9 + 3 x 8 + 8 loads);
//   unique:   every array element a dispatch touches, once (a perfect cache: a neighbour read by six threads
//             counts once); this is what a kernel must move at the least, so unique bytes over the copy
//             bandwidth is the floor.
// Uniform parameters (bindings, level table, emitters, the solver's state) are not counted, nor the
// shared-memory traffic of the tiled smoothing and the one-workgroup coarse solve; the tree's pools count
// once (pool_bytes) in both; each moving fragment's four atomics count as reads and writes of 4 bytes. The
// texels finish.comp writes for the plugin's wind texture are the plugin's output and are left out.
#pragma once

#include "solver/solver_io.h"

#include <cstdint>
#include <gust/solver/wind_solver.hpp>
#include <memory_resource>
#include <string>
#include <utility>
#include <vector>

namespace gust::bench {

/// Bytes one pass moves, counted both ways, and the dispatches it records.
struct Traffic {
    double accessed = 0.0;
    double unique = 0.0;
    std::uint64_t dispatches = 0;
    /// Adds `n` dispatches moving `accessed_bytes` and `unique_bytes` in all.
    void add(double accessed_bytes, double unique_bytes, std::uint64_t n = 1) {
        accessed += accessed_bytes;
        unique += unique_bytes;
        dispatches += n;
    }
};

/// What the byte counts depend on: the grid hierarchy and what one step found.
struct Workload {
    std::pmr::vector<gust::shaderio::GridLevel> levels;
    gust::Advection advection = gust::Advection::SemiLagrangian;
    std::uint32_t smoothing = 0;  ///< SolverDesc::smoothing
    std::uint32_t cell_words = 0; ///< words of a cell's voxel set
    double cycles = 0.0;          ///< V-cycles per step (median)
    bool warm_start = false;      ///< the solve starts from the last step's pressure
    double cut_cells = 0.0;       ///< cells holding solid voxels
    double fragments = 0.0;       ///< moving fragments
    double tree_bytes = 0.0;      ///< live bytes of the tree's pools
    /// Faces and cells of level l.
    double faces(std::size_t l) const;
    double cells(std::size_t l) const;
    /// Bytes of one face's weight at level l: level 0 keeps a byte per face (open_counts), coarser levels
    /// a float. Accessed bytes count each weight load as the 4-byte word it is.
    static double weight(std::size_t l) { return l == 0 ? 1.0 : 4.0; }
    /// The level coarse_solve.comp starts at: the finest whose cells, and every coarser level's, fit
    /// kCoarseCells (as WindSolver::create picks it).
    std::size_t coarse_level() const;
};

/// The byte model of one step with the MGPCG solver, per timed pass in the order the solver records them
/// ("solid", "fill", "faces", "advect", "pressure", "project").
std::vector<std::pair<std::string, Traffic>> step_traffic(const Workload& w);

} // namespace gust::bench
