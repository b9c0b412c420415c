// Deterministic triangle meshes for voxelizer tests. Every generator gives the same mesh for the same
// arguments on any standard library (std::mt19937 with our own mapping to reals), positions in world space.
#pragma once

#include "gust/voxelizer/grid.hpp"

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

namespace gust::test {

/// An owning indexed triangle mesh, world-space metres.
struct TestMesh {
    std::vector<glm::vec3> positions;   ///< tightly packed x,y,z
    std::vector<std::uint32_t> indices; ///< three per triangle
    /// A view borrowing this mesh's arrays; valid while the mesh lives unchanged.
    MeshView view() const;
};

/// `count` random triangles in and up to 10% of the grid around `grid`: small ones, sub-voxel ones,
/// slivers (two vertices 1e-3..1e-2 voxel apart), needles (up to half the grid long, 0.01..0.1 voxel
/// wide) and a few large ones. Three fresh vertices per triangle.
TestMesh random_soup(std::uint32_t seed, std::size_t count, const GridDesc& grid);

/// `count` axis-aligned boxes inside `grid`, 12 triangles each, whose corners lie on voxel planes
/// (origin + n h, exact when that sum is representable, e.g. h a power of two and origin a multiple of
/// it). Box b owns vertices [8b, 8b + 8) and indices [36b, 36b + 36), so tests can recover its extent.
TestMesh grid_aligned_boxes(const GridDesc& grid, std::size_t count, std::uint32_t seed);

/// Four triangles 20 grid widths across at assorted angles, each cutting the grid near its centre and
/// so large that the triangle covers its whole plane's section of the grid.
TestMesh huge_triangles(const GridDesc& grid);

/// Two triangles reaching 1e8 grid widths out, lying in planes of constant y and of constant x (off the
/// voxel planes), so that single precision keeps the planes exact: each covers its plane's whole section
/// of the grid. A rasterizer must clip them.
TestMesh vast_triangles(const GridDesc& grid);

/// `count` triangles straddling the grid's boundary: each has a vertex inside and one outside the grid.
TestMesh partly_outside(const GridDesc& grid, std::uint32_t seed, std::size_t count);

/// A mesh of rejected, zero-area and good triangles in the unit cube [0,1]^3, with its expected counts.
struct BadTriangles {
    TestMesh mesh; ///< NaN/Inf vertices, collinear and repeated-vertex triangles, good ones
    std::uint64_t expected_rejected = 0;  ///< triangles with a non-finite vertex
    std::uint64_t expected_zero_area = 0; ///< finite triangles whose vertices are collinear
};

/// Degenerate input for the rejection rules; the good triangles lie in [0.1, 0.9]^3.
BadTriangles bad_triangles();

/// A closed box (12 triangles) from lo to hi, world space.
TestMesh box(glm::vec3 lo, glm::vec3 hi);

/// A sphere of `radius` metres around `centre`: an icosahedron subdivided `subdivisions` times (20 * 4^s
/// triangles, shared vertices), vertices projected onto the sphere.
TestMesh icosphere(int subdivisions, glm::vec3 centre, float radius);

} // namespace gust::test
