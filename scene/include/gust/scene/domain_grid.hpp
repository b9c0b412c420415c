// The wind grid and voxel grid of a scene's domain (docs/design.md "Interfaces": voxels are cell_size /
// voxels_per_cell wide and indexed from the domain's min corner, wind cells likewise), and the System that
// runs the scene.
#pragma once

#include <gust/gpu/result.hpp>
#include <gust/gust.hpp>
#include <gust/scene/scene_file.hpp>
#include <gust/solver/wind_solver.hpp>
#include <gust/voxelizer/grid.hpp>

namespace gust {

/// The wind grid of a domain: its cells, cell size, voxels per cell and min corner
/// (center − cells·cell_size/2); numerics at their defaults.
SolverDesc domain_solver_desc(const DomainDesc& domain);

/// The System a scene describes (what `gust simulate` runs): its domain, centred on the focus (the domain's
/// center) with the tree's branching and hysteresis, and its solver settings; the device, submission,
/// voxelizer path and hooks are left at SystemDesc's defaults for the caller to set.
SystemDesc system_desc(const SceneDesc& scene);

/// The cubic voxel grid the tree covers (voxel_grid of the domain's wind grid). Voxels beyond the
/// domain's shorter axes exist in the tree but the wind ignores them.
Result<GridDesc> domain_grid(const DomainDesc& domain);

} // namespace gust
