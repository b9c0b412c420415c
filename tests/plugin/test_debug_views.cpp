// The debug views of System (debug_voxel_grid, debug_voxels, debug_tree_nodes) and the static set's
// re-voxelization on change, checked against boxes whose extents are known by hand.
#include "system_test_support.hpp"

#include <algorithm>
#include <array>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <vector>

namespace gust::test {
namespace {

// small_desc's domain: 16 x 8 x 16 cells of 1 m around (0, 4, 0), 2 voxels per cell, branching 4. The
// longest axis needs 32 voxels, so the tree is 4^3 = 64 voxels of 0.5 m across, from (-8, 0, -8).
constexpr float kVoxel = 0.5f;
constexpr std::uint32_t kRes = 64;
constexpr std::uint32_t kDepth = 3;
constexpr float kOrigin[3] = {-8.0f, 0.0f, -8.0f};

/// An axis-aligned world box, m.
struct Bounds {
    std::array<float, 3> lo, hi;
};

/// Box(1) placed at `centre` spans centre ± 1 m: 4 voxels a side, faces on voxel planes when the centre is.
Bounds box_at(float x, float y, float z) {
    return {{x - 1.0f, y - 1.0f, z - 1.0f}, {x + 1.0f, y + 1.0f, z + 1.0f}};
}

/// A voxel's closed box meets a face of the box exactly when its box lies within the box grown by one
/// voxel and not strictly inside the box (the mesh is the surface only). The 2 m box is n = 4 voxels wide
/// with faces on voxel planes, so the voxel layers on both sides of each face are occupied:
/// (n + 2)^3 − (n − 2)^3.
constexpr std::size_t kBoxVoxels = 6 * 6 * 6 - 2 * 2 * 2;

/// Everything a span-filling debug call lists: asks for the count with an empty span, then fills a list
/// of that size and checks the call gives the same count again.
template <class T>
std::vector<T> all_of(System& system, Outcome (System::*call)(std::span<T>, std::size_t&)) {
    std::size_t count = 0;
    EXPECT_TRUE((system.*call)({}, count));
    std::vector<T> list(count);
    std::size_t again = 0;
    const Outcome o = (system.*call)(list, again);
    EXPECT_TRUE(o) << o.message();
    EXPECT_EQ(again, count);
    return list;
}

std::vector<VoxelCoord> all_voxels(System& system) {
    return all_of(system, &System::debug_voxels);
}

std::vector<TreeNode> all_nodes(System& system) {
    return all_of(system, &System::debug_tree_nodes);
}

/// Voxels of `voxels` that lie outside the surface of `box` (see kBoxVoxels), as "(i,j,k)" strings.
std::vector<std::string> off_surface(const std::vector<VoxelCoord>& voxels, const Bounds& box) {
    std::vector<std::string> off;
    const float eps = 1e-4f;
    for (const VoxelCoord& v : voxels) {
        const std::uint32_t c[3] = {v.i, v.j, v.k};
        bool within_grown = true, strictly_inside = true;
        for (int a = 0; a < 3; ++a) {
            const float lo = kOrigin[a] + float(c[a]) * kVoxel, hi = lo + kVoxel;
            within_grown = within_grown && lo >= box.lo[a] - kVoxel - eps && hi <= box.hi[a] + kVoxel + eps;
            strictly_inside = strictly_inside && lo > box.lo[a] + eps && hi < box.hi[a] - eps;
        }
        if (!within_grown || strictly_inside)
            off.push_back("(" + std::to_string(v.i) + "," + std::to_string(v.j) + "," + std::to_string(v.k) +
                          ")");
    }
    return off;
}

/// The node of `nodes` that holds the centre of voxel `v` at `level`, or null.
const TreeNode* node_holding(const std::vector<TreeNode>& nodes, const VoxelCoord& v, std::uint32_t level) {
    const std::uint32_t c[3] = {v.i, v.j, v.k};
    for (const TreeNode& n : nodes) {
        if (n.level != level) continue;
        const float m[3] = {n.min.x, n.min.y, n.min.z};
        bool inside = true;
        for (int a = 0; a < 3; ++a) {
            const float centre = kOrigin[a] + (float(c[a]) + 0.5f) * kVoxel;
            inside = inside && centre > m[a] && centre < m[a] + n.size;
        }
        if (inside) return &n;
    }
    return nullptr;
}

class SystemDebugViews : public SystemTest {
  protected:
    MeshId box_mesh() {
        if (mesh_ == 0) {
            EXPECT_TRUE(system_->create_mesh(box_.desc(), mesh_));
        }
        return mesh_;
    }
    void step() {
        const Outcome o = system_->step(0.05f);
        ASSERT_TRUE(o) << o.message();
    }
    MeshId mesh_ = 0;
};

TEST_F(SystemDebugViews, theVoxelGridIsTheTreesCubeAtTheDomainsCorner) {
    VoxelGridInfo grid;
    ASSERT_TRUE(system_->debug_voxel_grid(grid));
    EXPECT_EQ(grid.origin.x, kOrigin[0]);
    EXPECT_EQ(grid.origin.y, kOrigin[1]);
    EXPECT_EQ(grid.origin.z, kOrigin[2]);
    EXPECT_EQ(grid.voxel_size, kVoxel);
    for (std::uint32_t r : grid.resolution)
        EXPECT_EQ(r, kRes);
    EXPECT_EQ(grid.depth, kDepth);
    EXPECT_EQ(grid.branching, 4u);

    ASSERT_TRUE(system_->set_focus({3.0f, 4.0f, -2.0f}));
    step();
    ASSERT_TRUE(system_->debug_voxel_grid(grid));
    EXPECT_EQ(grid.origin.x, kOrigin[0] + 3.0f) << "the grid follows the focus in whole cells";
    EXPECT_EQ(grid.origin.y, kOrigin[1]);
    EXPECT_EQ(grid.origin.z, kOrigin[2] - 2.0f);
}

TEST_F(SystemDebugViews, voxelsOfAStaticBoxAreItsSurfaceAndMatchTheStats) {
    InstanceId box = 0;
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(-3.0f, 2.0f, 0.0f), false, box));
    step();

    std::size_t count = 0;
    ASSERT_TRUE(system_->debug_voxels({}, count)) << "an empty span asks for the count";
    EXPECT_EQ(count, system_->stats().voxels);
    EXPECT_EQ(count, kBoxVoxels);

    const std::vector<VoxelCoord> voxels = all_voxels(*system_);
    ASSERT_EQ(voxels.size(), kBoxVoxels);
    const std::vector<std::string> off = off_surface(voxels, box_at(-3.0f, 2.0f, 0.0f));
    EXPECT_TRUE(off.empty()) << off.size() << " voxels off the box's surface, first " << off.front();
    std::set<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> unique;
    for (const VoxelCoord& v : voxels) {
        EXPECT_LT(v.i, kRes);
        EXPECT_LT(v.j, kRes);
        EXPECT_LT(v.k, kRes);
        unique.insert({v.k, v.j, v.i});
    }
    EXPECT_EQ(unique.size(), voxels.size()) << "each voxel once";
    EXPECT_TRUE(std::is_sorted(voxels.begin(), voxels.end(), [](const VoxelCoord& a, const VoxelCoord& b) {
        return std::tie(a.k, a.j, a.i) < std::tie(b.k, b.j, b.i);
    })) << "ordered by k, then j, then i";
}

TEST_F(SystemDebugViews, aShortSpanGetsTheFirstVoxelsAndTheTotal) {
    InstanceId box = 0;
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(-3.0f, 2.0f, 0.0f), false, box));
    step();
    const std::vector<VoxelCoord> voxels = all_voxels(*system_);
    ASSERT_GT(voxels.size(), 10u);

    const VoxelCoord sentinel{7777, 7777, 7777};
    std::vector<VoxelCoord> few(11, sentinel);
    std::size_t count = 0;
    ASSERT_TRUE(system_->debug_voxels(std::span(few).first(10), count));
    EXPECT_EQ(count, voxels.size());
    for (std::size_t v = 0; v < 10; ++v)
        EXPECT_TRUE(few[v].i == voxels[v].i && few[v].j == voxels[v].j && few[v].k == voxels[v].k) << v;
    EXPECT_EQ(few[10].i, sentinel.i) << "nothing past the span is written";

    std::vector<TreeNode> nodes = all_nodes(*system_);
    ASSERT_GT(nodes.size(), 3u);
    std::vector<TreeNode> three(3);
    ASSERT_TRUE(system_->debug_tree_nodes(three, count));
    EXPECT_EQ(count, nodes.size());
    for (std::size_t n = 0; n < 3; ++n) {
        EXPECT_EQ(three[n].level, nodes[n].level);
        EXPECT_EQ(three[n].min.x, nodes[n].min.x);
        EXPECT_EQ(three[n].size, nodes[n].size);
    }
}

TEST_F(SystemDebugViews, treeNodesNestAndCoverEveryVoxel) {
    InstanceId box = 0;
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(-3.0f, 2.0f, 0.0f), false, box));
    step();
    const std::vector<TreeNode> nodes = all_nodes(*system_);
    ASSERT_EQ(nodes.size(), system_->stats().nodes);

    ASSERT_FALSE(nodes.empty());
    const TreeNode& root = nodes.front();
    EXPECT_EQ(root.level, 0u);
    EXPECT_EQ(root.min.x, kOrigin[0]);
    EXPECT_EQ(root.min.y, kOrigin[1]);
    EXPECT_EQ(root.min.z, kOrigin[2]);
    EXPECT_EQ(root.size, float(kRes) * kVoxel);
    EXPECT_EQ(root.state, TreeNodeState::Static);
    EXPECT_TRUE(root.refined);

    const float eps = 1e-4f;
    std::uint32_t previous_level = 0;
    for (std::size_t n = 1; n < nodes.size(); ++n) {
        const TreeNode& node = nodes[n];
        ASSERT_GE(node.level, previous_level) << "level by level from the root";
        previous_level = node.level;
        ASSERT_GE(node.level, 1u) << "one root";
        ASSERT_LT(node.level, kDepth);
        EXPECT_EQ(node.size, root.size / float(1u << (2 * node.level))) << "each level is 4 times finer";
        const bool nested = std::any_of(nodes.begin(), nodes.end(), [&](const TreeNode& parent) {
            return parent.level + 1 == node.level && parent.refined && node.min.x >= parent.min.x - eps &&
                   node.min.y >= parent.min.y - eps && node.min.z >= parent.min.z - eps &&
                   node.min.x + node.size <= parent.min.x + parent.size + eps &&
                   node.min.y + node.size <= parent.min.y + parent.size + eps &&
                   node.min.z + node.size <= parent.min.z + parent.size + eps;
        });
        EXPECT_TRUE(nested) << "node " << n << " (level " << node.level
                            << ") lies in no refined node above it";
    }
    EXPECT_EQ(previous_level, kDepth - 1) << "the last level holds the leaf bricks";

    for (const VoxelCoord& v : all_voxels(*system_)) {
        const TreeNode* brick = node_holding(nodes, v, kDepth - 1);
        ASSERT_NE(brick, nullptr) << "voxel (" << v.i << "," << v.j << "," << v.k << ") has no brick";
        EXPECT_TRUE(brick->refined) << "a brick with voxels has its occupancy mask";
        EXPECT_EQ(brick->state, TreeNodeState::Static);
    }
}

TEST_F(SystemDebugViews, nodesTellWhatReachedThemThisFrame) {
    InstanceId fixed = 0, moving = 0;
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(-3.0f, 2.0f, 0.0f), false, fixed));
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(4.0f, 2.0f, 4.0f), true, moving));
    step();
    // The moving box spans [3, 5] x [1, 3] x [3, 5] m, so the voxel at its min corner is (22, 2, 22).
    const VoxelCoord corner{22, 2, 22};
    std::vector<TreeNode> nodes = all_nodes(*system_);
    const TreeNode* brick = node_holding(nodes, corner, kDepth - 1);
    ASSERT_NE(brick, nullptr);
    EXPECT_EQ(brick->state, TreeNodeState::Reached);
    const TreeNode* wall = node_holding(nodes, VoxelCoord{8, 2, 14}, kDepth - 1); // the static box's corner
    ASSERT_NE(wall, nullptr);
    EXPECT_EQ(wall->state, TreeNodeState::Static);
    EXPECT_TRUE(std::any_of(nodes.begin(), nodes.end(), [](const TreeNode& n) {
        return n.state == TreeNodeState::Stale;
    })) << "the siblings no fragment reached";

    // One frame after the moving box left, its bricks are still allocated (hysteresis) but stale.
    ASSERT_TRUE(system_->set_transform(moving, translation(4.0f, 2.0f, -5.0f)));
    step();
    nodes = all_nodes(*system_);
    brick = node_holding(nodes, corner, kDepth - 1);
    ASSERT_NE(brick, nullptr);
    EXPECT_EQ(brick->state, TreeNodeState::Stale);
}

TEST_F(SystemDebugViews, staticInstancesAreVoxelizedAgainWhenAddedMovedOrDestroyed) {
    InstanceId box = 0;
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(-3.0f, 2.0f, 0.0f), false, box));
    step();
    ASSERT_EQ(system_->stats().voxels, kBoxVoxels);

    ASSERT_TRUE(system_->set_transform(box, translation(2.0f, 4.0f, -3.0f)));
    step();
    std::vector<VoxelCoord> voxels = all_voxels(*system_);
    EXPECT_EQ(voxels.size(), kBoxVoxels);
    std::vector<std::string> off = off_surface(voxels, box_at(2.0f, 4.0f, -3.0f));
    EXPECT_TRUE(off.empty()) << off.size() << " voxels not on the moved box, first " << off.front();

    ASSERT_TRUE(system_->destroy_instance(box));
    step();
    EXPECT_EQ(system_->stats().voxels, 0u);
    EXPECT_TRUE(all_voxels(*system_).empty());

    InstanceId again = 0;
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(1.0f, 3.0f, 1.0f), false, again));
    step();
    voxels = all_voxels(*system_);
    EXPECT_EQ(voxels.size(), kBoxVoxels);
    off = off_surface(voxels, box_at(1.0f, 3.0f, 1.0f));
    EXPECT_TRUE(off.empty()) << off.size() << " voxels not on the new box, first " << off.front();
}

/// Whether the last step voxelized the static set (its passes are timed as voxelize_static_*).
bool voxelized_static(const System& system) {
    const auto& ms = system.stats().ms;
    return std::any_of(ms.begin(), ms.end(),
                       [](const auto& pass) { return pass.first.rfind("voxelize_static_", 0) == 0; });
}

TEST_F(SystemDebugViews, anUnchangedStaticSetIsNotVoxelizedAgain) {
    InstanceId box = 0, moving = 0;
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(-3.0f, 2.0f, 0.0f), false, box));
    ASSERT_TRUE(system_->create_instance(box_mesh(), translation(4.0f, 2.0f, 4.0f), true, moving));
    step();
    ASSERT_TRUE(voxelized_static(*system_)) << "the first step voxelizes the static set";
    ASSERT_TRUE(system_->set_transform(moving, translation(4.5f, 2.0f, 4.0f)));
    step();
    EXPECT_FALSE(voxelized_static(*system_)) << "only a moving instance changed";
    ASSERT_TRUE(system_->set_transform(box, translation(-3.0f, 2.0f, 0.0f)));
    step();
    EXPECT_FALSE(voxelized_static(*system_)) << "the same transform again changes nothing";
    ASSERT_TRUE(system_->set_transform(box, translation(-2.0f, 2.0f, 0.0f)));
    step();
    EXPECT_TRUE(voxelized_static(*system_)) << "a static instance moved";
}

TEST_F(SystemDebugViews, anEmptyWorldHasOnlyTheRoot) {
    step();
    std::size_t voxels = 1;
    ASSERT_TRUE(system_->debug_voxels({}, voxels));
    EXPECT_EQ(voxels, 0u);
    const std::vector<TreeNode> nodes = all_nodes(*system_);
    ASSERT_EQ(nodes.size(), 1u);
    EXPECT_EQ(nodes[0].level, 0u);
    EXPECT_FALSE(nodes[0].refined);
    EXPECT_EQ(nodes[0].state, TreeNodeState::Stale);
}

} // namespace
} // namespace gust::test
