// What a mesh asks of each voxelizer path, and the cost model VoxelizeMethod::Auto picks a path with
// (docs/cli.md, "How auto picks"): no path is run to decide.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <gust/gpu/context.hpp>
#include <gust/voxelizer/grid.hpp>

namespace gust {

/// Size sums over a mesh's triangles in mesh units, measured once on the host (GpuMesh keeps them from
/// Voxelizer::upload). Each triangle is projected along the axis of its normal's largest component,
/// as both paths project it. Only triangles with finite vertices and non-zero area count.
struct MeshSizes {
    std::uint64_t triangles = 0; ///< triangles counted
    double box_area = 0.0;       ///< sum of the projected bounding boxes' areas (w h)
    double box_span = 0.0;       ///< sum of the projected bounding boxes' sides (w + h)
    double projected_area = 0.0; ///< sum of the projected triangles' areas
    double cube_area = 0.0;      ///< sum of area (|nx| + |ny| + |nz|), n the unit normal
    double extent = 0.0;         ///< sum of the 3D bounding boxes' sides (x + y + z)
    glm::vec3 lo{0.0f};          ///< bounds of the counted triangles' vertices (lo > hi when none)
    glm::vec3 hi{-1.0f};
};

/// Measures `mesh`, whose indices must be in range (Voxelizer::upload checks them first). O(triangles).
MeshSizes measure_mesh(const MeshView& mesh);

/// Expected work of voxelizing meshes on a grid, in grid units (a voxel is 1): the mean over the
/// mesh's sub-voxel offsets of the Minkowski sums of each triangle with the pixel square (raster) or
/// the voxel cube (fragments), and of its projected bounding box grown by one column (compute).
struct VoxelizeWork {
    double triangles = 0.0; ///< triangles every path sets up
    double columns = 0.0;   ///< pixel columns the compute path walks: projected bounding boxes
    double pixels = 0.0;    ///< pixels the raster path shades: every pixel a projected triangle touches
    double fragments = 0.0; ///< voxel/triangle pairs the fragment list receives
    VoxelizeWork& operator+=(const VoxelizeWork& other);
};

/// The work of one placement of a mesh measured as `sizes`: `model` maps mesh to world space (its scale
/// is taken as the cube root of its determinant), and the part of the placed bounding box outside
/// `grid` is assumed to hold no surface work.
VoxelizeWork voxelize_work(const MeshSizes& sizes, const glm::mat4& model, const GridDesc& grid);

/// Predicted wall milliseconds of one blocking pass of each path.
struct PathCosts {
    double raster_ms = 0.0;
    double compute_ms = 0.0;
};

/// Milliseconds per unit of work of one path: fixed + per_triangle * triangles + per_item * items, where
/// the items are pixels (raster) or columns (compute).
struct PathCoefficients {
    double fixed_ms = 0.0;
    double per_triangle_ms = 0.0;
    double per_item_ms = 0.0;
};

/// The calibrated coefficients of both paths for a device: those fitted on lavapipe for CPU devices,
/// those fitted on an NVIDIA H100 for the others (docs/cli.md lists both and the runs they come from).
struct CostModel {
    PathCoefficients raster;
    PathCoefficients compute;
    /// Whether any run on such a device measured the raster path faster. False on GPUs: there `auto` takes
    /// the compute path whatever the coefficients predict (docs/cli.md, "How auto picks").
    bool raster_measured_faster = true;
    /// Costs of `work` with these coefficients.
    PathCosts predict(const VoxelizeWork& work) const;
    /// Whether `auto` takes the raster path for `work`: where it was measured faster on such a device and is
    /// predicted faster here (else the compute path).
    bool picks_raster(const VoxelizeWork& work) const;
};

/// The model gust uses on `device` (by DeviceInfo::type).
const CostModel& cost_model(const gpu::DeviceInfo& device);

} // namespace gust
