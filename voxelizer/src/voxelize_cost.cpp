#include <algorithm>
#include <cmath>
#include <gust/voxelizer/voxelize_cost.hpp>

namespace gust {

namespace {

/// Fitted by `gust_bench_voxelize_model --repeat 5` on llvmpipe (LLVM 15.0.6, 256 bits) with 2 cores of
/// an AMD EPYC, 2026-11-24, over ten meshes of assets/ at 64^3 to 1024^3 (docs/cli.md, "How auto picks").
/// llvmpipe runs vertex and geometry shaders on one thread, hence the raster path's cost per triangle.
constexpr CostModel kCpuModel{{0.22, 6.6e-4, 3.8e-5}, {0.36, 6.6e-5, 1.9e-5}};

/// Fitted the same way to the ten H100 rows of docs/results.md's voxelize-gpu block (2026-11-22), with the
/// work of the same meshes and grids: there the compute path was the faster in every row, as in both rows
/// of the H200 check (2026-11-27), so `auto` does not weigh the raster path on GPUs.
constexpr CostModel kGpuModel{{0.43, 2.2e-6, 5.9e-6}, {0.53, 0.0, 7.0e-8}, false};

bool finite(const glm::vec3& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

/// Fraction of the grid-space box [lo, hi], grown by half a voxel so that a flat box keeps a thickness,
/// that lies inside the grid.
double inside_fraction(const glm::dvec3& lo, const glm::dvec3& hi, double res) {
    double fraction = 1.0;
    for (int a = 0; a < 3; ++a) {
        const double l = lo[a] - 0.5, h = hi[a] + 0.5;
        fraction *= std::max(0.0, std::min(h, res) - std::max(l, 0.0)) / (h - l);
    }
    return fraction;
}

} // namespace

MeshSizes measure_mesh(const MeshView& mesh) {
    // Double precision throughout: a float's cross product overflows for edges past about 1.8e19, and an
    // infinite area made the first fragment list as large as the device allows (and the moving meshes'
    // velocity list larger).
    MeshSizes s;
    glm::vec3 lo(HUGE_VALF), hi(-HUGE_VALF);
    for (std::size_t t = 0; t + 2 < mesh.index_count; t += 3) {
        const glm::vec3 f0 = mesh.position(mesh.indices[t]);
        const glm::vec3 f1 = mesh.position(mesh.indices[t + 1]);
        const glm::vec3 f2 = mesh.position(mesh.indices[t + 2]);
        if (!finite(f0) || !finite(f1) || !finite(f2)) continue;
        const glm::dvec3 p0(f0), p1(f1), p2(f2);
        const glm::vec3 tlo = glm::min(f0, glm::min(f1, f2));
        const glm::vec3 thi = glm::max(f0, glm::max(f1, f2));
        const glm::dvec3 size = glm::max(p0, glm::max(p1, p2)) - glm::min(p0, glm::min(p1, p2));
        const glm::dvec3 an = glm::abs(glm::cross(p1 - p0, p2 - p0));
        if (an.x + an.y + an.z == 0.0) continue;
        // The shaders' dominant_axis (tri_box.h): ties go to the later axis.
        const int w = an.x > an.y && an.x > an.z ? 0 : (an.y > an.z ? 1 : 2);
        const int u = (w + 1) % 3, v = (w + 2) % 3;
        ++s.triangles;
        s.box_area += size[u] * size[v];
        s.box_span += size[u] + size[v];
        s.projected_area += 0.5 * an[w];
        s.cube_area += 0.5 * (an.x + an.y + an.z);
        s.extent += size.x + size.y + size.z;
        lo = glm::min(lo, tlo);
        hi = glm::max(hi, thi);
    }
    if (s.triangles > 0) {
        s.lo = lo;
        s.hi = hi;
    }
    return s;
}

VoxelizeWork& VoxelizeWork::operator+=(const VoxelizeWork& other) {
    triangles += other.triangles;
    columns += other.columns;
    pixels += other.pixels;
    fragments += other.fragments;
    return *this;
}

VoxelizeWork voxelize_work(const MeshSizes& sizes, const glm::mat4& model, const GridDesc& grid) {
    VoxelizeWork work;
    work.triangles = double(sizes.triangles);
    if (sizes.triangles == 0) return work;
    const glm::dmat3 linear = glm::dmat3(glm::mat3(model)) / double(grid.voxel_size);
    const double det = std::abs(glm::determinant(linear));
    double scale = std::cbrt(det);
    if (!(scale > 0.0) || !std::isfinite(scale))
        scale = std::max({glm::length(linear[0]), glm::length(linear[1]), glm::length(linear[2])});
    if (!std::isfinite(scale)) return work;

    glm::dvec3 lo(HUGE_VAL), hi(-HUGE_VAL);
    const glm::dvec3 origin(grid.origin);
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 p((corner & 1) ? sizes.hi.x : sizes.lo.x, (corner & 2) ? sizes.hi.y : sizes.lo.y,
                          (corner & 4) ? sizes.hi.z : sizes.lo.z);
        const glm::dvec3 g =
            (glm::dvec3(glm::vec3(model * glm::vec4(p, 1.0f))) - origin) / double(grid.voxel_size);
        lo = glm::min(lo, g);
        hi = glm::max(hi, g);
    }
    const double inside = inside_fraction(lo, hi, double(grid.res));
    if (!std::isfinite(inside)) return work;
    const double s2 = scale * scale, t = work.triangles;
    work.columns = inside * (s2 * sizes.box_area + scale * sizes.box_span + t);
    work.pixels = inside * (s2 * sizes.projected_area + scale * sizes.box_span + t);
    work.fragments = inside * (s2 * sizes.cube_area + scale * sizes.extent + t);
    return work;
}

PathCosts CostModel::predict(const VoxelizeWork& work) const {
    PathCosts costs;
    costs.raster_ms =
        raster.fixed_ms + raster.per_triangle_ms * work.triangles + raster.per_item_ms * work.pixels;
    costs.compute_ms =
        compute.fixed_ms + compute.per_triangle_ms * work.triangles + compute.per_item_ms * work.columns;
    return costs;
}

bool CostModel::picks_raster(const VoxelizeWork& work) const {
    if (!raster_measured_faster) return false;
    const PathCosts costs = predict(work);
    return costs.raster_ms < costs.compute_ms;
}

const CostModel& cost_model(const gpu::DeviceInfo& device) {
    return device.type == "cpu" ? kCpuModel : kGpuModel;
}

} // namespace gust
