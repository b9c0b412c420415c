// What the parts of gust_bench_tree share: the seed's figures and the goals, the command line's options,
// the rows each measurement fills, and the report that turns them into the results block (tree_report.cpp).
#pragma once

#include "bench_common.hpp"

#include <cstdint>
#include <filesystem>
#include <gust/gpu/context.hpp>
#include <gust/voxelizer/sparse_tree.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <string>
#include <vector>

namespace gust::bench::tree {

/// The seed's second table: ms per tree build at depths 1..10 over 512^3 fragments (RTX 2070 Super).
constexpr double kSeedDepthMs[] = {0.355, 0.362, 0.467, 0.442, 0.471, 0.497, 0.572, 0.677, 0.835, 0.782};
constexpr std::uint64_t kSeedTriangles = 7219045;
/// The seed's third table at 512^3, in bytes.
constexpr std::uint64_t kSeedGridBytes = 536870912;
constexpr std::uint64_t kSeedFragmentBytes = 13889024;
constexpr std::uint64_t kSeedTreeBytes = 26030592;
/// The goals: tree bytes at most 0.3x the fragment list's, an incremental frame at most 0.2x a
/// rebuild.
constexpr double kBytesGoal = 0.3;
constexpr double kFrameGoal = 0.2;
/// Bytes per fragment of the voxelizer's velocity list (uvec2 of half floats).
constexpr std::uint64_t kVelocityBytes = 8;

/// What the command line asked for.
struct Options {
    std::filesystem::path assets = GUST_ASSETS_DIR;
    int repeat = 3;
    int frames = 30;
    bool quick = false;
    std::string write;
    std::string device;
};

/// The sizes --quick shrinks.
struct Plan {
    std::uint32_t depth_res = 512;                          ///< fragment grid of the depth table
    std::uint32_t max_octree_depth = 9;                     ///< deepest b = 2 row of the depth table
    std::vector<std::uint32_t> byte_res = {256, 512, 1024}; ///< grids of the bytes table
    std::uint32_t world_res = 256;                          ///< grid of the walk-through
    float world_h = 0.1f;                                   ///< its voxel size, metres
    int frames = 30;                                        ///< timed frames per kind
    int warmup_frames = 12;                                 ///< untimed incremental frames (> hysteresis)
    int rebuild_warmup = 2;                                 ///< untimed rebuild frames
};

/// The fragments of one voxelization of the dragon, and what the host made of them.
struct Voxelized {
    std::uint32_t res = 0;
    gust::GridDesc grid;
    double wall_ms = 0.0;
    std::uint64_t fragments = 0;
    std::vector<std::uint32_t> unique; ///< sorted unique voxel keys
};

/// One tree built from scratch over one fragment list.
struct TreeRow {
    std::uint32_t fragment_res = 0;
    std::uint32_t branching = 0;
    std::uint32_t depth = 0;
    std::uint32_t shift = 0; ///< fragment grid = tree grid << shift
    int runs = 0;            ///< timed builds; 0 when built only for its bytes
    std::string error;
    double wall_ms = -1.0; ///< best wall-clock time around update()
    double gpu_ms = -1.0;  ///< summed timestamp passes of that build; < 0 without timestamps
    gust::TreeStats stats;
    std::uint64_t host_voxels = 0; ///< unique fragment voxels at the tree's resolution, counted on the host
    std::uint32_t growths = 0;     ///< pool doublings before the tree fit
    /// Voxels per axis of the tree's leaves.
    std::uint32_t res() const { return fragment_res >> shift; }
    /// Whether every build of this row succeeded.
    bool ok() const { return error.empty(); }
    /// Leaf mask blocks in use, the last entry of the per-level counts.
    std::uint64_t leaf_bricks() const {
        return stats.nodes_per_level.empty() ? 0 : stats.nodes_per_level.back();
    }
};

/// One measured step of the walk-through.
struct FrameSample {
    double wall_ms = 0.0; ///< around VoxelWorld::step()
    double gpu_ms = 0.0;  ///< its summed passes
    double pose_ms = 0.0; ///< CPU skinning and the upload of the posed vertices, outside the step
    gust::WorldFrame frame;
};

/// The walk-through's outcome.
struct WorldResult {
    std::string scene; ///< what was placed where, for the results block
    std::uint64_t static_triangles = 0;
    std::uint64_t dynamic_triangles = 0;
    gust::GridDesc grid;
    std::vector<FrameSample> incremental;
    std::vector<FrameSample> rebuild;
    std::uint32_t growths = 0;    ///< pool growths over all frames, warm-up included
    std::uint32_t hysteresis = 0; ///< frames a stale block is kept before it is coarsened
};

/// Median of `values` (mean of the middle two for an even count), the statistic frames are reported in.
double median(std::vector<double> values);

/// The Markdown body of the results block: heading, command, machine, the three sections and notes.
std::string render(const std::vector<TreeRow>& depth_rows, const std::vector<TreeRow>& byte_rows,
                   const std::vector<Voxelized>& grids, const WorldResult& world, std::uint64_t triangles,
                   const Plan& plan, const gust::gpu::DeviceInfo& device, const RunInfo& run);

} // namespace gust::bench::tree
