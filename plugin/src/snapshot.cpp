// The wind snapshot's ring of copies and its CPU sampler (snapshot.hpp).
#include "snapshot.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <gust/solver/wind_solver.hpp>

namespace gust::detail {

SnapshotRing::SnapshotRing(std::size_t cells, std::size_t levels, std::pmr::memory_resource* memory)
    : copies_{SnapshotData(memory), SnapshotData(memory), SnapshotData(memory)} {
    static_assert(kCopies == 3, "the initializer above names each copy");
    for (SnapshotData& copy : copies_) {
        copy.cells.resize(cells);
        copy.levels.reserve(levels);
    }
}

SnapshotData* SnapshotRing::begin_write() {
    // A reader that saw an older publication may raise a count after this check; it then finds that copy
    // unpublished and lets go without reading (acquire), so the copy is free to fill.
    const int published = published_.load();
    for (int i = 0; i < kCopies; ++i)
        if (i != published && readers_[i].load() == 0) return &copies_[i];
    return nullptr;
}

void SnapshotRing::publish(SnapshotData* data) {
    published_.store(int(data - copies_.data()));
}

const SnapshotData* SnapshotRing::acquire(int& held) {
    // Raise the count, then check the copy is still the published one: the writer only fills a copy that
    // is unpublished and has no readers, so a copy found published after the count rose stays unchanged
    // until release. Each retry means a publication happened in between.
    for (;;) {
        const int i = published_.load();
        if (i < 0) return nullptr;
        readers_[i].fetch_add(1);
        if (published_.load() == i) {
            held = i;
            return &copies_[i];
        }
        readers_[i].fetch_sub(1);
    }
}

void SnapshotRing::release(int held) {
    readers_[held].fetch_sub(1);
}

std::size_t SnapshotRing::bytes() const {
    return std::size_t(kCopies) * copies_[0].cells.size() * sizeof(glm::vec4);
}

float half_to_float(std::uint16_t h) {
    const std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16;
    const std::uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
    if (exponent == 0) {
        // Zero or subnormal: mantissa · 2^-24.
        const float magnitude = std::ldexp(float(mantissa), -24);
        return sign ? -magnitude : magnitude;
    }
    if (exponent == 31) return std::bit_cast<float>(sign | 0x7f800000u | (mantissa << 13));
    return std::bit_cast<float>(sign | ((exponent + 112) << 23) | (mantissa << 13));
}

namespace {

/// Cell units of `point` in a cascade's grid (as sample.comp), and whether the grid holds it (edges
/// included).
bool grid_point(const SnapshotLevel& level, glm::vec3 point, glm::vec3& p) {
    const glm::vec3 size = glm::vec3(level.extent);
    p = (point - level.origin) / level.cell_size;
    return p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.x <= size.x && p.y <= size.y && p.z <= size.z;
}

/// The cells read as the wind texture's sampler reads them at cell units p: texel centres at c + 0.5,
/// trilinear, clamped to the edge.
glm::vec4 trilinear(const SnapshotLevel& level, const glm::vec4* cells, glm::vec3 p) {
    const glm::ivec3 n = level.extent;
    const glm::ivec3 last = n - 1, low = glm::max(n - 2, glm::ivec3(0));
    const int row = n.x, slice = n.x * n.y;
    const auto lerp = [](const glm::vec4& a, const glm::vec4& b, float t) { return a + (b - a) * t; };
    const glm::vec3 q = glm::clamp(p - 0.5f, glm::vec3(0.0f), glm::vec3(last));
    const glm::ivec3 i0 = glm::min(glm::ivec3(q), low);
    const glm::vec3 t = q - glm::vec3(i0);
    const int dx = i0.x < last.x ? 1 : 0, dy = i0.y < last.y ? row : 0, dz = i0.z < last.z ? slice : 0;
    const glm::vec4* c000 = cells + i0.x + row * i0.y + slice * i0.z;
    const glm::vec4 x00 = lerp(c000[0], c000[dx], t.x), x10 = lerp(c000[dy], c000[dy + dx], t.x);
    const glm::vec4 x01 = lerp(c000[dz], c000[dz + dx], t.x);
    const glm::vec4 x11 = lerp(c000[dz + dy], c000[dz + dy + dx], t.x);
    return lerp(lerp(x00, x10, t.y), lerp(x01, x11, t.y), t.z);
}

/// Cascade k's share of the answer at `point`, whose cell units in its grid are p (inside it): 1 for the
/// coarsest, else rising from 0 at its border to 1 over cascade_blend_cells of the next coarser
/// cascade's open fraction there.
float level_weight(const SnapshotData& d, std::size_t k, glm::vec3 point, glm::vec3 p) {
    if (k + 1 == d.levels.size()) return 1.0f;
    const glm::vec3 inside = glm::min(p, glm::vec3(d.levels[k].extent) - p);
    const float depth = std::min({inside.x, inside.y, inside.z});
    if (depth >= kCascadeBlendCells) return 1.0f;
    const SnapshotLevel& coarser = d.levels[k + 1];
    glm::vec3 q;
    grid_point(coarser, point, q);
    const float open = trilinear(coarser, d.cells.data() + coarser.first, q).w;
    return std::clamp(depth / cascade_blend_cells(open), 0.0f, 1.0f);
}

} // namespace

void sample_snapshot(const SnapshotData& d, std::span<const Vec3> points, std::span<Vec3> velocities) {
    for (std::size_t i = 0; i < points.size(); ++i) {
        const glm::vec3 point(points[i].x, points[i].y, points[i].z);
        // Finest first: each cascade takes its share of what the finer ones left.
        glm::vec3 sum(0.0f);
        float left = 1.0f;
        for (std::size_t k = 0; k < d.levels.size() && left > 0.0f; ++k) {
            glm::vec3 p;
            if (!grid_point(d.levels[k], point, p)) continue;
            const float weight = level_weight(d, k, point, p);
            sum += left * weight * glm::vec3(trilinear(d.levels[k], d.cells.data() + d.levels[k].first, p));
            left *= 1.0f - weight;
        }
        const glm::vec3 u = sum + left * d.ambient;
        velocities[i] = {u.x, u.y, u.z};
    }
}

} // namespace gust::detail
