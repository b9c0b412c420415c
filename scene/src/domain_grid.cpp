#include <gust/scene/domain_grid.hpp>

namespace gust {

SolverDesc domain_solver_desc(const DomainDesc& domain) {
    SolverDesc desc;
    desc.cells = domain.cells;
    desc.cell_size = domain.cell_size;
    desc.origin = domain.center - glm::vec3(domain.cells) * domain.cell_size * 0.5f;
    desc.voxels_per_cell = domain.voxels_per_cell;
    return desc;
}

SystemDesc system_desc(const SceneDesc& scene) {
    SystemDesc desc;
    const DomainDesc& d = scene.domain;
    for (int a = 0; a < 3; ++a)
        desc.domain.cells[a] = d.cells[a];
    desc.domain.cell_size = d.cell_size;
    desc.domain.voxels_per_cell = d.voxels_per_cell;
    desc.domain.branching = d.branching;
    desc.domain.hysteresis = d.hysteresis;
    desc.domain.cascades = d.cascades;
    desc.domain.ratio = d.ratio;
    // The System centres its domain on the focus: min corner center − cells·cell_size/2, as the scene's.
    desc.domain.focus = {d.center.x, d.center.y, d.center.z};
    const SolverSettings& s = scene.solver;
    WindSettings& w = desc.wind;
    w.advection = s.advection == "none"         ? WindAdvection::None
                  : s.advection == "maccormack" ? WindAdvection::MacCormack
                                                : WindAdvection::SemiLagrangian;
    w.pressure = s.pressure == "jacobi"      ? WindPressure::Jacobi
                 : s.pressure == "multigrid" ? WindPressure::Multigrid
                                             : WindPressure::MultigridPCG;
    w.tolerance = s.tolerance;
    w.max_cycles = s.max_cycles;
    w.cycles_per_step = s.cycles_per_step;
    w.max_iterations = s.max_iterations;
    w.vorticity = s.vorticity;
    w.viscosity = s.viscosity;
    w.max_solid_speed = s.max_solid_speed;
    return desc;
}

Result<GridDesc> domain_grid(const DomainDesc& domain) {
    return voxel_grid(domain_solver_desc(domain), domain.branching);
}

} // namespace gust
