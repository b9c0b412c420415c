// The wind snapshot's ring of copies and its CPU sampler (snapshot.hpp).
#include "snapshot.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace gust::detail {

SnapshotRing::SnapshotRing(std::size_t cells, std::pmr::memory_resource* memory)
    : copies_{SnapshotData(memory), SnapshotData(memory), SnapshotData(memory)} {
    static_assert(kCopies == 3, "the initializer above names each copy");
    for (SnapshotData& copy : copies_)
        copy.cells.resize(cells);
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

void sample_snapshot(const SnapshotData& d, std::span<const Vec3> points, std::span<Vec3> velocities) {
    const glm::ivec3 n = d.extent;
    const glm::vec3 size = glm::vec3(n), inv_h = glm::vec3(1.0f / d.cell_size);
    const glm::ivec3 last = n - 1, low = glm::max(n - 2, glm::ivec3(0));
    const glm::vec4* cells = d.cells.data();
    const int row = n.x, slice = n.x * n.y;
    const auto lerp = [](const glm::vec4& a, const glm::vec4& b, float t) { return a + (b - a) * t; };
    for (std::size_t i = 0; i < points.size(); ++i) {
        // Cell units, as sample.comp: outside [0, n] (edges included) the ambient wind.
        const glm::vec3 p = (glm::vec3(points[i].x, points[i].y, points[i].z) - d.origin) * inv_h;
        if (!(p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.x <= size.x && p.y <= size.y && p.z <= size.z)) {
            velocities[i] = {d.ambient.x, d.ambient.y, d.ambient.z};
            continue;
        }
        // p >= 0 here, so truncation is floor.
        const glm::ivec3 c = glm::min(glm::ivec3(p), last);
        const glm::vec4& own = cells[c.x + row * c.y + slice * c.z];
        if (own.w == 0.0f) {
            // A cell without air: the solid's own velocity (query answers it there, not a blend).
            velocities[i] = {own.x, own.y, own.z};
            continue;
        }
        // The sampler: texel centres at c + 0.5, clamped to the edge.
        const glm::vec3 q = glm::clamp(p - 0.5f, glm::vec3(0.0f), glm::vec3(last));
        const glm::ivec3 i0 = glm::min(glm::ivec3(q), low);
        const glm::vec3 t = q - glm::vec3(i0);
        const int dx = i0.x < last.x ? 1 : 0, dy = i0.y < last.y ? row : 0, dz = i0.z < last.z ? slice : 0;
        const glm::vec4* c000 = cells + i0.x + row * i0.y + slice * i0.z;
        const glm::vec4 x00 = lerp(c000[0], c000[dx], t.x), x10 = lerp(c000[dy], c000[dy + dx], t.x);
        const glm::vec4 x01 = lerp(c000[dz], c000[dz + dx], t.x);
        const glm::vec4 x11 = lerp(c000[dz + dy], c000[dz + dy + dx], t.x);
        const glm::vec4 u = lerp(lerp(x00, x10, t.y), lerp(x01, x11, t.y), t.z);
        velocities[i] = {u.x, u.y, u.z};
    }
}

} // namespace gust::detail
