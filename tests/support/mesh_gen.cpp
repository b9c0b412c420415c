#include "mesh_gen.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <utility>

namespace gust::test {
namespace {

static_assert(sizeof(glm::vec3) == 12, "TestMesh::view() assumes tightly packed positions");

/// std::mt19937's sequence is fixed by the standard; the distributions are not, so the mapping to reals
/// is ours. Only +-*/ and sqrt (correctly rounded in IEEE 754) touch the numbers, so meshes are
/// bit-identical everywhere.
class Rng {
  public:
    explicit Rng(std::uint32_t seed) : engine_(seed) {}

    /// Uniform in [0, 1) with 53 random bits.
    double unit() {
        const double hi = static_cast<double>(engine_() >> 5);
        const double lo = static_cast<double>(engine_() >> 6);
        return (hi * 67108864.0 + lo) * (1.0 / 9007199254740992.0);
    }
    double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
    /// Integer in [0, n), n > 0; the modulo bias is irrelevant for test meshes.
    std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>(engine_() % n); }
    glm::dvec3 in_box(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
    /// A random unit vector (rejection sampling of the unit ball).
    glm::dvec3 direction() {
        for (;;) {
            const glm::dvec3 p = in_box(-1.0, 1.0);
            const double len2 = glm::dot(p, p);
            if (len2 > 1e-6 && len2 <= 1.0) return p / std::sqrt(len2);
        }
    }
    /// A random direction scaled by a length uniform in [lo, hi).
    glm::dvec3 offset(double lo, double hi) {
        const double length = uniform(lo, hi);
        return length * direction();
    }
    /// Three points uniform in the cube of half-width `s` around `c`, drawn in order (function
    /// arguments would be evaluated in an unspecified order).
    std::array<glm::dvec3, 3> around(const glm::dvec3& c, double s) {
        const glm::dvec3 a = c + s * in_box(-1, 1);
        const glm::dvec3 b = c + s * in_box(-1, 1);
        return {a, b, c + s * in_box(-1, 1)};
    }

  private:
    std::mt19937 engine_;
};

/// Builds a mesh from grid-space points (voxel units from the grid's min corner).
class GridMeshBuilder {
  public:
    explicit GridMeshBuilder(const GridDesc& grid)
        : origin_(grid.origin), h_(static_cast<double>(grid.voxel_size)) {}

    std::uint32_t vertex(const glm::dvec3& grid_point) {
        mesh_.positions.emplace_back(origin_ + grid_point * h_);
        return static_cast<std::uint32_t>(mesh_.positions.size() - 1);
    }
    void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        mesh_.indices.insert(mesh_.indices.end(), {a, b, c});
    }
    void triangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
        const std::uint32_t ia = vertex(a);
        const std::uint32_t ib = vertex(b);
        triangle(ia, ib, vertex(c));
    }
    void triangle(const std::array<glm::dvec3, 3>& v) { triangle(v[0], v[1], v[2]); }
    TestMesh take() { return std::move(mesh_); }

  private:
    glm::dvec3 origin_;
    double h_;
    TestMesh mesh_;
};

/// A unit vector perpendicular to unit vector `d`.
glm::dvec3 perpendicular(const glm::dvec3& d) {
    const glm::dvec3 other = std::abs(d.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    const glm::dvec3 p = glm::cross(d, other);
    return p / std::sqrt(glm::dot(p, p));
}

} // namespace

MeshView TestMesh::view() const {
    MeshView view;
    view.positions = positions.empty() ? nullptr : &positions[0].x;
    view.vertex_count = positions.size();
    view.position_stride = sizeof(glm::vec3);
    view.indices = indices.data();
    view.index_count = indices.size();
    return view;
}

TestMesh random_soup(std::uint32_t seed, std::size_t count, const GridDesc& grid) {
    Rng rng(seed);
    GridMeshBuilder builder(grid);
    const double res = grid.res;
    for (std::size_t t = 0; t < count; ++t) {
        const glm::dvec3 c = rng.in_box(-0.1 * res, 1.1 * res);
        const std::uint32_t kind = rng.below(100);
        if (kind < 35) { // small: up to a few voxels
            builder.triangle(rng.around(c, rng.uniform(0.2, 3.0)));
        } else if (kind < 55) { // tiny: well inside one voxel or straddling a voxel plane
            builder.triangle(rng.around(c, rng.uniform(1e-3, 0.5)));
        } else if (kind < 70) { // sliver: two vertices nearly equal
            const glm::dvec3 b = c + rng.offset(1e-3, 1e-2);
            builder.triangle(c, b, c + rng.offset(0.5, 4.0));
        } else if (kind < 90) { // needle: long and thin
            const glm::dvec3 d = rng.direction();
            const double length = rng.uniform(1.0, 0.5 * res);
            const double width = rng.uniform(0.01, 0.1);
            const double along = rng.unit();
            builder.triangle(c, c + length * d, c + along * length * d + width * perpendicular(d));
        } else { // large
            builder.triangle(rng.around(c, rng.uniform(res / 16, res / 4)));
        }
    }
    return builder.take();
}

TestMesh grid_aligned_boxes(const GridDesc& grid, std::size_t count, std::uint32_t seed) {
    // Quads over corner indices (bit 0 = x max, bit 1 = y max, bit 2 = z max), wound outwards.
    static constexpr std::array<std::array<std::uint32_t, 4>, 6> kFaces = {
        {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}}};
    Rng rng(seed);
    GridMeshBuilder builder(grid);
    for (std::size_t b = 0; b < count; ++b) {
        glm::dvec3 lo;
        glm::dvec3 hi;
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t extent = 1 + rng.below(std::max(1u, grid.res / 4));
            const std::uint32_t first = rng.below(grid.res - extent + 1);
            lo[a] = first;
            hi[a] = first + extent;
        }
        std::uint32_t corners[8];
        for (std::uint32_t c = 0; c < 8; ++c) {
            corners[c] =
                builder.vertex({(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z});
        }
        for (const auto& f : kFaces) {
            builder.triangle(corners[f[0]], corners[f[1]], corners[f[2]]);
            builder.triangle(corners[f[0]], corners[f[2]], corners[f[3]]);
        }
    }
    return builder.take();
}

TestMesh huge_triangles(const GridDesc& grid) {
    const double res = grid.res;
    const glm::dvec3 centre(0.5 * res);
    // Offsets in grid widths from the grid's centre, off the voxel lattice so that no plane passes exactly
    // through voxel corners: whether exact touching counts is for hand-made tests, not this generic one.
    struct Plane {
        glm::dvec3 normal;
        glm::dvec3 offset;
    };
    const Plane planes[] = {{{0.05, 0.02, 1.0}, {0.0, 0.0, 0.037}},
                            {{1.0, 1.0, 1.0}, {0.0123457, -0.0213411, 0.00817}},
                            {{1.0, 2.0, 3.0}, {0.1, -0.05, 0.07}},
                            {{-0.3, 1.0, 0.2}, {0.0, -0.2, 0.0}}};
    // Circumradius 20 grid widths: the inradius (10) exceeds the grid's half diagonal (0.87).
    const double radius = 20.0 * res;
    const double sin120 = 0.5 * std::sqrt(3.0);
    GridMeshBuilder builder(grid);
    for (const Plane& plane : planes) {
        const glm::dvec3 n = plane.normal / std::sqrt(glm::dot(plane.normal, plane.normal));
        const glm::dvec3 t1 = perpendicular(n);
        const glm::dvec3 t2 = glm::cross(n, t1);
        const glm::dvec3 p = centre + plane.offset * res;
        builder.triangle(p + radius * t1, p + radius * (-0.5 * t1 + sin120 * t2),
                         p + radius * (-0.5 * t1 - sin120 * t2));
    }
    return builder.take();
}

TestMesh vast_triangles(const GridDesc& grid) {
    const double res = grid.res, far = 1e8 * res;
    GridMeshBuilder builder(grid);
    const double y = 0.3721 * res, x = 0.6133 * res;
    builder.triangle({-far, y, -far}, {far, y, -far}, {0.0, y, far});
    builder.triangle({x, -far, -far}, {x, -far, far}, {x, far, 0.0});
    return builder.take();
}

TestMesh partly_outside(const GridDesc& grid, std::uint32_t seed, std::size_t count) {
    Rng rng(seed);
    GridMeshBuilder builder(grid);
    const double res = grid.res;
    const auto outside = [res](const glm::dvec3& p) {
        return glm::any(glm::lessThan(p, glm::dvec3(0.0))) || glm::any(glm::greaterThan(p, glm::dvec3(res)));
    };
    for (std::size_t t = 0; t < count; ++t) {
        const glm::dvec3 a = rng.in_box(0.0, res);
        glm::dvec3 b;
        do {
            b = rng.in_box(-0.5 * res, 1.5 * res);
        } while (!outside(b));
        const double along = rng.unit();
        const glm::dvec3 c = a + along * (b - a) + rng.offset(0.1, 4.0);
        builder.triangle(a, b, c);
    }
    return builder.take();
}

BadTriangles bad_triangles() {
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    constexpr float kInf = std::numeric_limits<float>::infinity();
    BadTriangles bad;
    // Dyadic coordinates keep the collinear triangles exactly collinear after any power-of-two scaling.
    bad.mesh.positions = {
        {0.125f, 0.125f, 0.25f}, {0.875f, 0.25f, 0.375f}, {0.375f, 0.75f, 0.625f}, // 0-2: good
        {0.25f, 0.625f, 0.125f}, {0.75f, 0.875f, 0.875f}, {0.125f, 0.375f, 0.75f}, // 3-5: good
        {kNaN, 0.5f, 0.5f},      {0.5f, kInf, 0.5f},      {0.5f, 0.5f, -kInf},     // 6-8: non-finite
        {0.125f, 0.25f, 0.5f},   {0.25f, 0.5f, 0.5f},     {0.375f, 0.75f, 0.5f},   // 9-11: on one line
        {kNaN, kNaN, kNaN},                                                        // 12: never referenced
        {0.5f, 0.125f, 0.5f},    {0.5f, 0.875f, 0.25f},   {0.875f, 0.5f, 0.75f},   // 13-15: good
    };
    bad.mesh.indices = {
        0,  1,  2,  // good
        0,  1,  6,  // NaN
        7,  3,  4,  // +Inf
        8,  8,  8,  // -Inf, repeated
        6,  7,  8,  // all non-finite
        3,  4,  5,  // good
        0,  0,  1,  // repeated vertex
        2,  2,  2,  // a point
        9,  10, 11, // collinear
        13, 14, 15, // good
    };
    bad.expected_rejected = 4;
    bad.expected_zero_area = 3;
    return bad;
}

TestMesh icosphere(int subdivisions, glm::vec3 centre, float radius) {
    const double phi = 0.5 * (1.0 + std::sqrt(5.0));
    std::vector<glm::dvec3> points = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                                      {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                                      {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
    std::vector<std::uint32_t> indices = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                                          4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                                          6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
    for (glm::dvec3& p : points)
        p /= std::sqrt(glm::dot(p, p));
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
        const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
            const auto [it, inserted] = midpoints.try_emplace(std::minmax(a, b), 0u);
            if (inserted) {
                const glm::dvec3 m = points[a] + points[b];
                points.push_back(m / std::sqrt(glm::dot(m, m)));
                it->second = static_cast<std::uint32_t>(points.size() - 1);
            }
            return it->second;
        };
        std::vector<std::uint32_t> finer;
        finer.reserve(indices.size() * 4);
        for (std::size_t t = 0; t < indices.size(); t += 3) {
            const std::uint32_t a = indices[t];
            const std::uint32_t b = indices[t + 1];
            const std::uint32_t c = indices[t + 2];
            const std::uint32_t ab = midpoint(a, b);
            const std::uint32_t bc = midpoint(b, c);
            const std::uint32_t ca = midpoint(c, a);
            finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        indices = std::move(finer);
    }
    TestMesh mesh;
    mesh.positions.reserve(points.size());
    for (const glm::dvec3& p : points)
        mesh.positions.emplace_back(glm::dvec3(centre) + p * double(radius));
    mesh.indices = std::move(indices);
    return mesh;
}

TestMesh box(glm::vec3 lo, glm::vec3 hi) {
    TestMesh mesh;
    for (int i = 0; i < 8; ++i)
        mesh.positions.push_back(
            glm::vec3((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z));
    const std::uint32_t faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    for (const auto& q : faces)
        mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    return mesh;
}

} // namespace gust::test
