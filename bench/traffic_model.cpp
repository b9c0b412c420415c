#include "traffic_model.hpp"

#include "solver_setup.hpp"

#include <algorithm>

namespace gust::bench {

namespace {

/// The "solid" pass: solid_cells (the cells' voxels from the tree, split into parts, and each cell's
/// confinement force) and solid_motion.
Traffic solid_traffic(const Workload& w) {
    Traffic t;
    const double C = w.cells(0), parts = 4.0 * 2 * w.cut_cells * w.cell_words;
    // solid_cells: the last flags read, the flags and two labels stored per cell, the parts (and static
    // voxels, at most as many words) of a cut cell, the tree once. Clearing the last step's moving cells'
    // motion is left out (at most one per fragment).
    t.add(16 * C + 1.5 * parts + w.tree_bytes, 16 * C + 1.5 * parts + w.tree_bytes);
    // ... and each cell's confinement force and speed: seven vorticities, six faces, one vec4 stored.
    t.add(C * (7 * 16 + 6 * 4 + 16), 32 * C + 4 * w.faces(0), 0);
    // solid_motion: key and half-float velocity, four 4-byte atomics, per fragment.
    t.add(44 * w.fragments, 44 * w.fragments);
    return t;
}

/// The "fill" pass: the outside-air fill's union-find, linking each cell's parts to its three upper
/// neighbours' and finding each part's root (fill_link, fill_finish).
Traffic fill_traffic(const Workload& w) {
    Traffic t;
    const double C = w.cells(0), parts = 4.0 * 2 * w.cut_cells * w.cell_words;
    // fill_link: the flags of the cell and three neighbours, the parts of cut cells and their neighbours,
    // the labels of each union (about two finds of two loads each), per cell.
    t.add(C * (4 * 4 + 3 * 2 * 8) + 4 * parts, 12 * C + parts);
    // fill_finish: flags, parts of cut cells, a find per part, the label and the solid fraction stored.
    t.add(C * (4 + 2 * 8 + 2 * 4 + 4) + parts, 16 * C + parts);
    return t;
}

/// The "faces" pass: solid_faces (with the fluid links) and fluid_finish, then coarse_weights (every coarser
/// level's weights from level 0's, one dispatch).
Traffic faces_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0), air = 4.0 * w.cut_cells * w.cell_words;
    // solid_faces: two flags, the open count (a byte) and solid velocity stored; a face of a cut cell (six
    // per cut cell) also reads both cells' air. The motion sums of moving cells are left out (at most
    // 6 x 16 B per fragment).
    t.add(13 * F + 6 * 2 * air, 4 * C + 5 * F + air);
    // The fluid links and fluid_finish run in this scene: the ground slab, which the domain's sides cut,
    // holds outside air below the air above it in the lowest cells. The links, in solid_faces: per cell the
    // flags, six open counts (a word each) and about three unions (two finds of two loads each), counted as
    // the separate pass they were; fluid_finish: the flags and a find per cell.
    t.add(C * (4 + 6 * 4 + 3 * 2 * 8), 8 * C + F);
    t.add(C * (4 + 2 * 4), 8 * C);
    if (w.levels.size() < 2) return t;
    // coarse_weights: a face of level l reads the level-0 faces it covers (the factors of every finer level
    // multiplied, one along its own axis) and stores its weight; the dispatch reads level 0's once.
    double accessed = 0.0, unique = Workload::weight(0) * F;
    glm::ivec3 k(1);
    for (std::size_t l = 1; l < w.levels.size(); ++l) {
        k *= w.levels[l - 1].factor;
        for (std::uint32_t axis = 0; axis < 3; ++axis) {
            glm::ivec3 span = k;
            span[int(axis)] = 1;
            const double count = gust::shaderio::face_count(w.levels[l].dims, axis),
                         span_faces = double(span.x) * span.y * span.z;
            accessed += count * (4 * span_faces + 4);
            unique += count * 4;
        }
    }
    t.add(accessed, unique);
    return t;
}

/// The "advect" pass: semi-Lagrangian, or MacCormack's forward (which keeps the range it blended), then
/// backward with the clamped correction in one dispatch; the pass that writes the velocity (the only one,
/// or MacCormack's second)
/// also adds the emitters, the ambient domain faces and vorticity confinement from the last step's
/// vorticity (the two cells' forces, made by solid_cells).
Traffic advect_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0);
    // Each trace reads the velocity at the face (its own value and four of each other component) and
    // samples it at the midpoint (3 components x 8 loads); a sample of a field is 8 loads.
    const double trace = (9 + 3 * 8) * 4, confine = 2 * 16;
    if (w.advection != gust::Advection::MacCormack) {
        t.add(F * (trace + 8 * 4 + confine + 4), 8 * F + 16 * C); // velocity -> tmp
        return t;
    }
    t.add(F * (trace + 8 * 4 + 3 * 4), 16 * F); // velocity -> scratch, low and high
    // scratch traced back with the velocity, corrected from scratch, velocity, low and high -> tmp
    t.add(F * (trace + 8 * 4 + 4 * 4 + confine + 4), 20 * F + 16 * C);
    return t;
}

/// The "pressure" pass with the default MGPCG (wind_solver.cpp, record_step): the warm start's q (start.comp,
/// beside the advection, which sums b·q), then per iteration smooth.comp's first pass at level 0 (the first
/// iteration's also makes b) (the iterate, its residual and the check, then smoothing),
/// the downward smoothing per level above the coarse solve (each restricting its right-hand side from the
/// finer level first), coarse_solve.comp (every coarser level in one workgroup, restricting its first), the
/// upward smoothing per level (at level 0 with the sums for beta), and cg.comp (the new direction and the sum
/// of p·Lp).
Traffic pressure_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0), W = Workload::weight(0) * F;
    // b, in the solve's first pass (no dispatch of its own): six face fluxes (3 loads each), b and r_old
    // stored.
    t.add(C * (18 + 2) * 4, 8 * F + 8 * C, 0);
    // warm: q = Lφ (six weights, seven φ) stored in a dispatch of its own, and per face in the advection's
    // last pass q below and above and the solid's velocity for b·q.
    if (w.warm_start) t.add(C * (13 + 1) * 4 + F * 3 * 4, W + 8 * C + 4 * F);
    const std::size_t coarse = w.coarse_level(), last = w.levels.size() - 1;
    // A tile of kTileSide^3 cells loads its halo too: (side + 2)^3 values per side^3 cells.
    const double side = gust::shaderio::kTileSide,
                 halo = (side + 2) * (side + 2) * (side + 2) / (side * side * side);
    Traffic cycle;
    // smooth, first pass: six weights, the iterate x + αp at the cell and six neighbours (two loads each), b
    // and the last residual read; x, r_old, r and z stored.
    cycle.add(C * (6 + 7 * 2 + 2 + 4) * 4, W + 32 * C);
    for (std::size_t l = 0; l < coarse; ++l) {
        // The restriction, in the next level's smoothing (or the coarse solve's, which counts the dispatch):
        // a coarse cell computes its children's residuals (six weights, seven φ and b each) and stores b.
        cycle.add(w.cells(l) * 14 * 4 + 4 * w.cells(l + 1),
                  Workload::weight(l) * w.faces(l) + 8 * w.cells(l) + 4 * w.cells(l + 1), 0);
        // downward smoothing from zero at the levels between: six weights read, z stored.
        if (l + 1 < coarse)
            cycle.add(w.cells(l + 1) * 7 * 4, Workload::weight(l + 1) * w.faces(l + 1) + 4 * w.cells(l + 1));
    }
    // coarse_solve: the first level's right-hand side and the weights of each relaxed cell (half the cells
    // per half-sweep, down and up at every level but the coarsest, kCoarseSweeps on it) from memory, the
    // correction stored; the values themselves stay in shared memory.
    double coarse_accessed = 8 * w.cells(coarse), coarse_unique = 8 * w.cells(coarse);
    for (std::size_t m = coarse; m <= last; ++m) {
        const double half_sweeps = m < last ? 2.0 * 2 * w.smoothing : 2.0 * gust::detail::kCoarseSweeps;
        coarse_accessed += half_sweeps * w.cells(m) / 2 * 6 * 4;
        coarse_unique += Workload::weight(m) * w.faces(m);
    }
    cycle.add(coarse_accessed, coarse_unique);
    // upward smoothing at each level below the coarse solve: six weights and b read, z stored, and per tile
    // value (halo included) the downward z and its prolonged correction (three coarse weights, eight coarse
    // values); at level 0 also r_old for the sums z·r and z·r_old.
    for (std::size_t l = coarse; l-- > 0;) {
        const double old_residual = l == 0 ? 1 : 0;
        cycle.add(w.cells(l) * (8 + old_residual + halo * 12) * 4,
                  Workload::weight(l) * w.faces(l) + (12 + 4 * old_residual) * w.cells(l) +
                      Workload::weight(l + 1) * w.faces(l + 1) + 4 * w.cells(l + 1));
    }
    // cg: the direction z + βp at the cell and six neighbours (two loads each), six weights, p stored.
    cycle.add(C * (7 * 2 + 6 + 1) * 4, W + 12 * C);
    t.add(w.cycles * cycle.accessed, w.cycles * cycle.unique,
          std::uint64_t(w.cycles * double(cycle.dispatches) + 0.5));
    return t;
}

/// The "project" pass: the gradient subtracted per face with both layers of the air's velocity extended
/// into closed faces, then the cells' end of the step (finish.comp).
Traffic project_traffic(const Workload& w) {
    Traffic t;
    const double F = w.faces(0), C = w.cells(0), W = Workload::weight(0) * F;
    // project: the weight (read again for the second layer), the velocity and φ = x + αp of both cells (two
    // loads each), the face stored; the closed faces' neighbours are left out.
    t.add(F * 8 * 4, W + 8 * F + 8 * C);
    // finish: φ (two loads) stored, the residual from six weights, six neighbours' φ and b, the divergence
    // after (six face fluxes of 3 loads), the vorticity from six cell velocities of 6 faces, vec4 stored.
    t.add(C * ((2 + 1 + 6 + 12 + 1 + 18 + 36) * 4 + 16), W + 8 * F + 32 * C);
    return t;
}

} // namespace

double Workload::faces(std::size_t l) const {
    return double(gust::shaderio::faces_total(levels[l].dims));
}

double Workload::cells(std::size_t l) const {
    const glm::ivec3 d = levels[l].dims;
    return double(d.x) * d.y * d.z;
}

std::size_t Workload::coarse_level() const {
    std::size_t coarse = levels.size() - 1;
    while (coarse > 0 && cells(coarse - 1) <= double(gust::shaderio::kCoarseCells))
        --coarse;
    return coarse;
}

std::vector<std::pair<std::string, Traffic>> step_traffic(const Workload& w) {
    return {{"solid", solid_traffic(w)},       {"fill", fill_traffic(w)},
            {"faces", faces_traffic(w)},       {"advect", advect_traffic(w)},
            {"pressure", pressure_traffic(w)}, {"project", project_traffic(w)}};
}

} // namespace gust::bench
