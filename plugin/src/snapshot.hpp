// The wind snapshot (SystemDesc::snapshot): each cell's velocity and open fraction, published on the CPU at
// every collected frame, read by any number of threads (System::sample) while one thread steps. No lock:
// a small ring of copies, each with a count of the readers inside it.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <glm/glm.hpp>
#include <gust/gust.hpp>
#include <memory_resource>
#include <span>
#include <vector>

namespace gust::detail {

/// One cascade's grid in a snapshot.
struct SnapshotLevel {
    glm::vec3 origin{0.0f}; ///< the grid's min corner, m
    float cell_size = 1.0f; ///< m
    glm::ivec3 extent{0};   ///< cells per axis
    std::size_t first = 0;  ///< its first cell in SnapshotData::cells
};

/// One published field: what System::sample answers from.
struct SnapshotData {
    explicit SnapshotData(std::pmr::memory_resource* memory) : cells(memory), levels(memory) {}
    /// Per cell of every cascade, finest first (x fastest): velocity (m/s), w = 1 − solid fraction.
    std::pmr::vector<glm::vec4> cells;
    std::pmr::vector<SnapshotLevel> levels; ///< the cascades, finest first
    glm::vec3 ambient{0.0f};                ///< the ambient wind of that frame (beyond every cascade)
    std::uint64_t frame = 0;                ///< WindTexture::frame of the step it was written by
};

/// The copies readers sample and the writer fills. The writer (one thread) takes a copy that is neither
/// published nor held by a reader, fills it and publishes it; a reader holds the published copy for the
/// duration of one sample call. With kCopies copies the writer always finds one free unless kCopies − 1
/// readers each still hold an older copy, in which case that frame is not published (the previous one stays).
class SnapshotRing {
  public:
    static constexpr int kCopies = 3;
    /// Allocates the copies for `cells` cells and `levels` cascades (on the creating thread).
    SnapshotRing(std::size_t cells, std::size_t levels, std::pmr::memory_resource* memory);

    /// Writer: a copy to fill, or null when every unpublished copy is held by a reader.
    SnapshotData* begin_write();
    /// Writer: makes the copy begin_write returned the one readers get.
    void publish(SnapshotData* data);

    /// Reader: the latest published copy, held until release (null: nothing published yet).
    const SnapshotData* acquire(int& held);
    void release(int held);

    /// Host bytes of the copies.
    std::size_t bytes() const;

  private:
    std::array<SnapshotData, kCopies> copies_;
    std::array<std::atomic<std::uint32_t>, kCopies> readers_{};
    std::atomic<int> published_{-1};
};

/// The velocity at each point from `data`, as the wind texture's sampler would read it (trilinear on cell
/// centres, clamped to the edge), with query's rules: in a cell without air the cell's own (its solid's)
/// velocity; the finest cascade that holds the point, blended into the next coarser one over its last
/// cascade_blend_cells cells (as gust_wind.glsl does); beyond every cascade the ambient wind. Points are
/// finite; both spans the same size.
void sample_snapshot(const SnapshotData& data, std::span<const Vec3> points, std::span<Vec3> velocities);

/// Half floats (IEEE binary16) to float.
float half_to_float(std::uint16_t h);

} // namespace gust::detail
