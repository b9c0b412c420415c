#include "gust/voxelizer/cpu_reference.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <glm/ext/vector_int3_sized.hpp>
#include <iterator>
#include <limits>
#include <thread>
#include <utility>

namespace gust {
namespace {

/// A triangle prepared for many box tests: its edges, normal and bounds are shared by every box.
class TriangleSat {
  public:
    explicit TriangleSat(const glm::dvec3 tri[3])
        : v_{tri[0], tri[1], tri[2]}, e_{tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]},
          n_(glm::cross(e_[0], e_[1])), lo_(glm::min(tri[0], glm::min(tri[1], tri[2]))),
          hi_(glm::max(tri[0], glm::max(tri[1], tri[2]))) {}

    const glm::dvec3& vertex(int i) const { return v_[i]; }
    const glm::dvec3& normal() const { return n_; }
    const glm::dvec3& lo() const { return lo_; }
    const glm::dvec3& hi() const { return hi_; }

    /// Separating-axis theorem for two convex sets (Akenine-Möller 2001): they are disjoint exactly when
    /// their projections are disjoint on one of the box normals, the triangle normal or a box-edge x
    /// triangle-edge cross product. Closed intervals, so touching is overlap.
    bool overlaps(const glm::dvec3& box_min, const glm::dvec3& box_max) const {
        // The box normals compare coordinates only, with no rounding at all.
        for (int a = 0; a < 3; ++a) {
            if (lo_[a] > box_max[a] || hi_[a] < box_min[a]) return false;
        }
        // Centring on the box keeps its projection symmetric: radius sum(|axis_k| * half_k).
        const glm::dvec3 centre = 0.5 * (box_min + box_max);
        const glm::dvec3 half = 0.5 * (box_max - box_min);
        const glm::dvec3 p[3] = {v_[0] - centre, v_[1] - centre, v_[2] - centre};
        const auto separated = [&](const glm::dvec3& axis) {
            const double d0 = glm::dot(axis, p[0]);
            const double d1 = glm::dot(axis, p[1]);
            const double d2 = glm::dot(axis, p[2]);
            const double radius = glm::dot(half, glm::abs(axis));
            return std::min({d0, d1, d2}) > radius || std::max({d0, d1, d2}) < -radius;
        };
        if (separated(n_)) return false;
        for (const glm::dvec3& f : e_) {
            // Cross products of the unit box axes with edge f; a zero axis (f parallel to a box axis)
            // projects everything to 0 and separates nothing, as it should.
            if (separated({0.0, -f.z, f.y}) || separated({f.z, 0.0, -f.x}) || separated({-f.y, f.x, 0.0})) {
                return false;
            }
        }
        return true;
    }

  private:
    glm::dvec3 v_[3];
    glm::dvec3 e_[3];
    glm::dvec3 n_;
    glm::dvec3 lo_;
    glm::dvec3 hi_;
};

/// A closed range of cell indices; empty when first > last.
struct CellRange {
    std::int64_t first = 0;
    std::int64_t last = -1;
    bool empty() const { return first > last; }
};

/// Cells c of [0, res) whose span [c - grow, c + 1 + grow] meets [lo, hi]. Widened by a relative hair so
/// that rounding in the callers' bounds can only add candidates for the exact test, never drop one.
CellRange cell_range(double lo, double hi, double grow, std::int64_t res) {
    constexpr double kSlack = 1e-7;
    const double first = std::ceil(lo - grow - kSlack * (1.0 + std::abs(lo))) - 1.0;
    const double last = std::floor(hi + grow + kSlack * (1.0 + std::abs(hi)));
    // Clamp in double first: huge triangles would overflow the integer conversion.
    const double first_clamped = std::max(first, 0.0);
    const double last_clamped = std::min(last, static_cast<double>(res - 1));
    if (!(first_clamped <= last_clamped)) return {};
    return {static_cast<std::int64_t>(first_clamped), static_cast<std::int64_t>(last_clamped)};
}

CellRange intersect(CellRange a, CellRange b) {
    return {std::max(a.first, b.first), std::min(a.last, b.last)};
}

/// Calls visit(glm::i64vec3 cell) for every cell of a res^3 grid of unit cells whose box
/// [cell - grow, cell + 1 + grow] meets the triangle. Rows of the first minor axis are bounded by the
/// triangle's extent across the row's slab, columns by the depth of the triangle's plane over the column,
/// so the exact test runs on O(area + perimeter) cells instead of the whole bounding box (which matters
/// for long needles and for planes spanning a 1024^3 grid).
template <class Visit>
void walk_triangle(const TriangleSat& tri, std::int64_t res, double grow, Visit&& visit) {
    CellRange bounds[3];
    for (int a = 0; a < 3; ++a) {
        bounds[a] = cell_range(tri.lo()[a], tri.hi()[a], grow, res);
        if (bounds[a].empty()) return;
    }
    const glm::dvec3& n = tri.normal();
    const glm::dvec3 an = glm::abs(n);
    // The dominant normal axis is the depth axis: the plane's depth over a column is then well defined.
    const int w = an.x >= an.y && an.x >= an.z ? 0 : (an.y >= an.z ? 1 : 2);
    const int u = (w + 1) % 3;
    const int v = (w + 2) % 3;
    const bool planar = n[w] != 0.0;
    const double d = glm::dot(n, tri.vertex(0));

    for (std::int64_t iu = bounds[u].first; iu <= bounds[u].last; ++iu) {
        const double s0 = static_cast<double>(iu) - grow;
        const double s1 = static_cast<double>(iu) + 1.0 + grow;
        double v_lo = std::numeric_limits<double>::infinity();
        double v_hi = -v_lo;
        const auto include = [&](double value) {
            v_lo = std::min(v_lo, value);
            v_hi = std::max(v_hi, value);
        };
        for (int i = 0; i < 3; ++i) {
            const glm::dvec3& a = tri.vertex(i);
            const glm::dvec3& b = tri.vertex((i + 1) % 3);
            if (a[u] >= s0 && a[u] <= s1) include(a[v]);
            for (const double s : {s0, s1}) {
                if ((a[u] < s && b[u] > s) || (a[u] > s && b[u] < s)) {
                    include(a[v] + (s - a[u]) / (b[u] - a[u]) * (b[v] - a[v]));
                }
            }
        }
        if (v_lo > v_hi) continue;
        const CellRange rows = intersect(bounds[v], cell_range(v_lo, v_hi, grow, res));
        for (std::int64_t iv = rows.first; iv <= rows.last; ++iv) {
            CellRange depth = bounds[w];
            if (planar) {
                const double t0 = static_cast<double>(iv) - grow;
                const double t1 = static_cast<double>(iv) + 1.0 + grow;
                double w_lo = std::numeric_limits<double>::infinity();
                double w_hi = -w_lo;
                for (const double su : {s0, s1}) {
                    for (const double tv : {t0, t1}) {
                        const double depth_at = (d - n[u] * su - n[v] * tv) / n[w];
                        w_lo = std::min(w_lo, depth_at);
                        w_hi = std::max(w_hi, depth_at);
                    }
                }
                depth = intersect(depth, cell_range(w_lo, w_hi, grow, res));
            }
            for (std::int64_t iw = depth.first; iw <= depth.last; ++iw) {
                glm::i64vec3 cell;
                cell[u] = iu;
                cell[v] = iv;
                cell[w] = iw;
                const glm::dvec3 box_min = glm::dvec3(cell) - grow;
                if (tri.overlaps(box_min, box_min + (1.0 + 2.0 * grow))) visit(cell);
            }
        }
    }
}

/// The scene's triangles addressed by one flat index, in grid space (voxel units, origin at the grid's
/// min corner) and double precision.
class SceneTriangles {
  public:
    SceneTriangles(std::span<const InstanceDesc> instances, const GridDesc& grid)
        : instances_(instances), origin_(grid.origin), h_(static_cast<double>(grid.voxel_size)) {
        first_.reserve(instances.size() + 1);
        first_.push_back(0);
        models_.reserve(instances.size());
        for (const InstanceDesc& instance : instances) {
            first_.push_back(first_.back() + instance.mesh.index_count / 3);
            models_.emplace_back(instance.model);
        }
    }

    std::uint64_t count() const { return first_.back(); }

    /// Reads triangle t into `out`; false when it has an out-of-range index or a non-finite vertex.
    bool read(std::uint64_t t, glm::dvec3 out[3]) const {
        const auto it = std::upper_bound(first_.begin(), first_.end(), t);
        const std::size_t instance = static_cast<std::size_t>(it - first_.begin()) - 1;
        const MeshView& mesh = instances_[instance].mesh;
        const std::size_t base = static_cast<std::size_t>(t - first_[instance]) * 3;
        for (std::size_t c = 0; c < 3; ++c) {
            const std::uint32_t index = mesh.indices[base + c];
            if (index >= mesh.vertex_count) return false;
            const glm::dvec4 world = models_[instance] * glm::dvec4(glm::dvec3(mesh.position(index)), 1.0);
            out[c] = (glm::dvec3(world) - origin_) / h_;
            if (!std::isfinite(out[c].x) || !std::isfinite(out[c].y) || !std::isfinite(out[c].z))
                return false;
        }
        return true;
    }

  private:
    std::span<const InstanceDesc> instances_;
    glm::dvec3 origin_;
    double h_;
    std::vector<std::uint64_t> first_; // first flat triangle of each instance, then the total
    std::vector<glm::dmat4> models_;
};

bool zero_area(const glm::dvec3 tri[3]) {
    return glm::cross(tri[1] - tri[0], tri[2] - tri[0]) == glm::dvec3(0.0);
}

std::uint32_t key_of(const glm::i64vec3& cell) {
    return pack_voxel(static_cast<std::uint32_t>(cell.x), static_cast<std::uint32_t>(cell.y),
                      static_cast<std::uint32_t>(cell.z));
}

/// Sorts pack_voxel keys (30 bits) and drops duplicates. Three stable 10-bit counting passes: O(n), where
/// std::sort took a third of a large voxelization's time.
void sort_unique(std::vector<std::uint32_t>& keys) {
    if (keys.size() < 1024) {
        std::sort(keys.begin(), keys.end());
    } else {
        std::vector<std::uint32_t> scratch(keys.size());
        for (int shift = 0; shift < 30; shift += 10) {
            std::array<std::size_t, 1025> offsets{};
            for (const std::uint32_t key : keys)
                ++offsets[((key >> shift) & 1023u) + 1];
            for (std::size_t b = 1; b < offsets.size(); ++b)
                offsets[b] += offsets[b - 1];
            for (const std::uint32_t key : keys)
                scratch[offsets[(key >> shift) & 1023u]++] = key;
            keys.swap(scratch);
        }
    }
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

/// Triangles binned by the blocks of voxels they meet, for the few per-voxel queries a diff needs.
class TriangleIndex {
  public:
    TriangleIndex(const SceneTriangles& scene, std::uint32_t res, double tolerance) {
        // Power-of-two blocks keep the scaling to block units exact; at most 64^3 blocks bounds memory.
        while ((res + block_ - 1) / block_ > 64)
            block_ *= 2;
        blocks_ = (res + block_ - 1) / block_;
        const double scale = 1.0 / static_cast<double>(block_);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> entries; // (block, triangle)
        for (std::uint64_t t = 0; t < scene.count(); ++t) {
            glm::dvec3 tri[3];
            if (!scene.read(t, tri)) continue;
            const glm::dvec3 scaled[3] = {tri[0] * scale, tri[1] * scale, tri[2] * scale};
            const auto id = static_cast<std::uint32_t>(triangles_.size());
            triangles_.emplace_back(tri);
            walk_triangle(TriangleSat(scaled), blocks_, tolerance * scale,
                          [&](const glm::i64vec3& block) { entries.emplace_back(block_id(block), id); });
        }
        std::sort(entries.begin(), entries.end());
        offsets_.assign(static_cast<std::size_t>(blocks_) * blocks_ * blocks_ + 1, 0);
        items_.reserve(entries.size());
        for (const auto& [block, triangle] : entries) {
            ++offsets_[block + 1];
            items_.push_back(triangle);
        }
        for (std::size_t b = 1; b < offsets_.size(); ++b)
            offsets_[b] += offsets_[b - 1];
    }

    /// True when some triangle meets voxel `cell`'s box grown by `grow` (|grow| <= the build tolerance).
    bool any_meets(const glm::i64vec3& cell, double grow) const {
        const std::uint32_t block = block_id(cell / static_cast<std::int64_t>(block_));
        const glm::dvec3 box_min = glm::dvec3(cell) - grow;
        const glm::dvec3 box_max = glm::dvec3(cell) + 1.0 + grow;
        for (std::uint32_t i = offsets_[block]; i < offsets_[block + 1]; ++i) {
            if (triangles_[items_[i]].overlaps(box_min, box_max)) return true;
        }
        return false;
    }

  private:
    std::uint32_t block_id(const glm::i64vec3& block) const {
        return static_cast<std::uint32_t>((block.z * blocks_ + block.y) * blocks_ + block.x);
    }

    std::uint32_t block_ = 1;
    std::uint32_t blocks_ = 1;
    std::vector<TriangleSat> triangles_;
    std::vector<std::uint32_t> offsets_;
    std::vector<std::uint32_t> items_;
};

} // namespace

bool triangle_box_overlap(const glm::dvec3 tri[3], const glm::dvec3& box_min, const glm::dvec3& box_max) {
    return TriangleSat(tri).overlaps(box_min, box_max);
}

CpuVoxelization voxelize_reference(std::span<const InstanceDesc> instances, const GridDesc& grid,
                                   double box_grow) {
    const SceneTriangles scene(instances, grid);
    const std::uint64_t count = scene.count();
    const auto res = static_cast<std::int64_t>(grid.res);
    const std::uint64_t hardware = std::max(1u, std::thread::hardware_concurrency());
    // Chunks small enough that a few grid-spanning triangles still spread over all threads.
    const std::uint64_t chunk_size = std::clamp<std::uint64_t>(count / (8 * hardware), 1, 1024);
    const std::uint64_t chunks = (count + chunk_size - 1) / chunk_size;

    struct Partial {
        std::vector<std::uint32_t> keys;
        std::uint64_t rejected = 0;
    };
    const auto threads = static_cast<unsigned>(std::clamp<std::uint64_t>(chunks, 1, hardware));
    std::vector<Partial> partials(threads);
    std::atomic<std::uint64_t> next_chunk{0};

    const auto work = [&](Partial& partial) {
        std::size_t compacted = 0;
        for (std::uint64_t chunk = next_chunk++; chunk < chunks; chunk = next_chunk++) {
            const std::uint64_t end = std::min(count, (chunk + 1) * chunk_size);
            for (std::uint64_t t = chunk * chunk_size; t < end; ++t) {
                glm::dvec3 tri[3];
                if (!scene.read(t, tri)) {
                    ++partial.rejected;
                    continue;
                }
                if (zero_area(tri)) continue;
                walk_triangle(TriangleSat(tri), res, box_grow,
                              [&](const glm::i64vec3& cell) { partial.keys.push_back(key_of(cell)); });
            }
            // Neighbouring triangles share voxels: deduplicating as the list doubles bounds memory.
            if (partial.keys.size() > 2 * compacted + (std::size_t{1} << 20)) {
                sort_unique(partial.keys);
                compacted = partial.keys.size();
            }
        }
    };
    std::vector<std::thread> pool;
    for (unsigned i = 1; i < threads; ++i)
        pool.emplace_back(work, std::ref(partials[i]));
    work(partials[0]);
    for (std::thread& thread : pool)
        thread.join();

    CpuVoxelization out;
    out.triangles = count;
    out.voxels = std::move(partials[0].keys);
    for (const Partial& partial : partials)
        out.rejected += partial.rejected;
    for (std::size_t i = 1; i < partials.size(); ++i) {
        out.voxels.insert(out.voxels.end(), partials[i].keys.begin(), partials[i].keys.end());
    }
    sort_unique(out.voxels);
    return out;
}

VoxelDiff diff_voxels(std::span<const std::uint32_t> candidate_sorted_unique,
                      std::span<const std::uint32_t> reference_sorted_unique) {
    VoxelDiff diff;
    std::set_difference(reference_sorted_unique.begin(), reference_sorted_unique.end(),
                        candidate_sorted_unique.begin(), candidate_sorted_unique.end(),
                        std::back_inserter(diff.missing));
    std::set_difference(candidate_sorted_unique.begin(), candidate_sorted_unique.end(),
                        reference_sorted_unique.begin(), reference_sorted_unique.end(),
                        std::back_inserter(diff.extra));
    return diff;
}

std::vector<std::uint32_t> unexplained_differences(const VoxelDiff& diff,
                                                   std::span<const InstanceDesc> instances,
                                                   const GridDesc& grid, double tolerance_voxels) {
    std::vector<std::uint32_t> unexplained;
    if (diff.missing.empty() && diff.extra.empty()) return unexplained;
    const double tolerance = std::abs(tolerance_voxels);
    const TriangleIndex index(SceneTriangles(instances, grid), grid.res, tolerance);
    for (const std::uint32_t key : diff.missing) {
        if (index.any_meets(glm::i64vec3(unpack_voxel(key)), -tolerance)) unexplained.push_back(key);
    }
    for (const std::uint32_t key : diff.extra) {
        const glm::uvec3 cell = unpack_voxel(key);
        const bool inside = cell.x < grid.res && cell.y < grid.res && cell.z < grid.res;
        if (!inside || !index.any_meets(glm::i64vec3(cell), tolerance)) unexplained.push_back(key);
    }
    std::sort(unexplained.begin(), unexplained.end());
    return unexplained;
}

} // namespace gust
