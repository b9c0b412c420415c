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
    const auto at = [&](int x, int y, int z) { return cells[x + n.x * (y + n.y * z)]; };
    for (std::size_t i = 0; i < points.size(); ++i) {
        // Cell units, as sample.comp: outside [0, n] (edges included) the ambient wind.
        const glm::vec3 p = (glm::vec3(points[i].x, points[i].y, points[i].z) - d.origin) * inv_h;
        glm::vec3 u;
        if (!(p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.x <= size.x && p.y <= size.y && p.z <= size.z)) {
            u = d.ambient;
        } else {
            const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor(p)), glm::ivec3(0), last);
            const glm::vec4 own = at(c.x, c.y, c.z);
            if (own.w == 0.0f) {
                // A cell without air: the solid's own velocity (query answers it there, not a blend).
                u = glm::vec3(own);
            } else {
                // The sampler: texel centres at c + 0.5, clamped to the edge.
                const glm::vec3 q = glm::clamp(p - 0.5f, glm::vec3(0.0f), glm::vec3(last));
                const glm::ivec3 i0 = glm::min(glm::ivec3(q), low), i1 = glm::min(i0 + 1, last);
                const glm::vec3 t = q - glm::vec3(i0);
                const glm::vec3 c00 =
                    glm::mix(glm::vec3(at(i0.x, i0.y, i0.z)), glm::vec3(at(i1.x, i0.y, i0.z)), t.x);
                const glm::vec3 c10 =
                    glm::mix(glm::vec3(at(i0.x, i1.y, i0.z)), glm::vec3(at(i1.x, i1.y, i0.z)), t.x);
                const glm::vec3 c01 =
                    glm::mix(glm::vec3(at(i0.x, i0.y, i1.z)), glm::vec3(at(i1.x, i0.y, i1.z)), t.x);
                const glm::vec3 c11 =
                    glm::mix(glm::vec3(at(i0.x, i1.y, i1.z)), glm::vec3(at(i1.x, i1.y, i1.z)), t.x);
                u = glm::mix(glm::mix(c00, c10, t.y), glm::mix(c01, c11, t.y), t.z);
            }
        }
        velocities[i] = {u.x, u.y, u.z};
    }
}

} // namespace gust::detail
