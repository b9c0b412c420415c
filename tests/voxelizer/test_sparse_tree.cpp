// The tree against from-scratch voxelization, frame after frame, for every branching factor.
#include "support/gpu_env.hpp"
#include "support/mesh_gen.hpp"
#include "tree/tree_io.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <gust/voxelizer/sparse_tree.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>

namespace gust::test {
namespace {

std::vector<std::uint32_t> sorted_unique(std::vector<std::uint32_t> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
}

/// A static box and a sphere that moves, voxelized on the GPU and fed to a tree.
class Scene {
  public:
    Scene(gpu::Context& ctx, std::uint32_t res, const TreeDesc& tree_desc) {
        grid.res = res;
        grid.voxel_size = 1.0f / float(res);
        wall = grid_aligned_boxes(grid, 1, 11);
        ball = icosphere(2, glm::vec3(0.0f), 0.12f);
        static_vox = std::move(Voxelizer::create(ctx).value());
        dynamic_vox = std::move(Voxelizer::create(ctx).value());
        wall_mesh = std::move(static_vox->upload(wall.view()).value());
        ball_mesh = std::move(dynamic_vox->upload(ball.view()).value());
        TreeDesc d = tree_desc;
        d.res = res;
        auto t = SparseTree::create(ctx, d);
        EXPECT_TRUE(t) << t.message();
        tree = std::move(t.value());
    }

    /// A path that repeats every 40 frames.
    static glm::vec3 ball_centre(int frame) {
        const float s = float(frame % 40) / 40.0f;
        return {0.15f + 0.7f * s, 0.5f + 0.2f * std::sin(6.2831853f * s), 0.45f};
    }

    /// One frame; returns the tree stats and checks the leaves against the union of both fragment lists.
    TreeStats frame(int n, bool rebuild_static, bool ball_present, bool check = true) {
        const GpuInstance wall_inst{&wall_mesh, glm::mat4(1.0f)};
        if (rebuild_static) {
            EXPECT_TRUE(static_vox->voxelize({&wall_inst, 1}, grid, VoxelizeMethod::Compute));
        }
        const GpuInstance ball_inst{&ball_mesh, glm::translate(glm::mat4(1.0f), ball_centre(n))};
        EXPECT_TRUE(
            dynamic_vox->voxelize({&ball_inst, ball_present ? 1u : 0u}, grid, VoxelizeMethod::Compute));
        const FragmentSource st{static_vox->fragment_buffer().address(), static_vox->fragment_count_address(),
                                static_vox->fragment_capacity()};
        const FragmentSource dy{dynamic_vox->fragment_buffer().address(),
                                dynamic_vox->fragment_count_address(), dynamic_vox->fragment_capacity()};
        auto stats = tree->update(rebuild_static ? &st : nullptr, &dy);
        EXPECT_TRUE(stats) << stats.message();
        if (check) {
            std::vector<std::uint32_t> expected = *static_vox->read_fragments();
            const auto dyn = *dynamic_vox->read_fragments();
            expected.insert(expected.end(), dyn.begin(), dyn.end());
            expected = sorted_unique(expected);
            const auto leaves = tree->leaf_voxels();
            EXPECT_TRUE(leaves);
            EXPECT_EQ(std::vector<std::uint32_t>(leaves->begin(), leaves->end()), expected) << "frame " << n;
            if (stats) {
                EXPECT_EQ(stats->voxels, expected.size()) << "frame " << n;
            }
        }
        return stats ? *stats : TreeStats{};
    }

    GridDesc grid;
    TestMesh wall, ball;
    std::unique_ptr<Voxelizer> static_vox, dynamic_vox;
    GpuMesh wall_mesh, ball_mesh;
    std::unique_ptr<SparseTree> tree;
};

using Param = std::tuple<std::uint32_t, std::uint32_t>; // branching, res

class TreeMatchesVoxelization : public GpuTestWithParam<Param> {};

TEST_P(TreeMatchesVoxelization, afterEveryFrameOfAMovingObjectBesideStaticGeometry) {
    const auto [branching, res] = GetParam();
    TreeDesc desc;
    desc.branching = branching;
    desc.hysteresis = 2;
    Scene scene(ctx(), res, desc);
    for (int n = 0; n < 12; ++n) {
        const TreeStats stats = scene.frame(n, n == 0, true);
        EXPECT_EQ(stats.exhausted, 0u);
        EXPECT_GT(stats.nodes, 1u);
    }
}

INSTANTIATE_TEST_SUITE_P(Branching, TreeMatchesVoxelization,
                         ::testing::Values(Param{2, 32}, Param{4, 64}, Param{8, 64}),
                         [](const ::testing::TestParamInfo<Param>& p) {
                             // Appended piecewise: GCC 12 warns (-Wrestrict) on the chained operator+.
                             std::string name = "b";
                             name += std::to_string(std::get<0>(p.param));
                             name += "_res";
                             name += std::to_string(std::get<1>(p.param));
                             return name;
                         });

using TreeTest = GpuTest;

TEST_F(TreeTest, rejectsBadShapes) {
    TreeDesc d;
    d.branching = 3;
    EXPECT_FALSE(SparseTree::create(ctx(), d));
    d.branching = 4;
    d.res = 128;
    auto r = SparseTree::create(ctx(), d);
    ASSERT_FALSE(r);
    EXPECT_NE(r.message().find("power"), std::string::npos);
    d.branching = 2;
    d.res = 2048;
    EXPECT_FALSE(SparseTree::create(ctx(), d));
}

TEST_F(TreeTest, shallowerTreeOverFinerFragmentsHoldsTheirParentVoxels) {
    TreeDesc desc;
    desc.branching = 2;
    Scene scene(ctx(), 64, desc);
    scene.frame(0, true, true, false);
    TreeDesc coarse;
    coarse.branching = 2;
    coarse.res = 16;
    coarse.fragment_shift = 2;
    auto tree = SparseTree::create(ctx(), coarse);
    ASSERT_TRUE(tree) << tree.message();
    const FragmentSource st{scene.static_vox->fragment_buffer().address(),
                            scene.static_vox->fragment_count_address(),
                            scene.static_vox->fragment_capacity()};
    auto stats = (*tree)->update(&st, nullptr);
    ASSERT_TRUE(stats) << stats.message();
    std::vector<std::uint32_t> expected;
    const std::vector<std::uint32_t> fine = *scene.static_vox->read_fragments();
    for (std::uint32_t key : fine) {
        const glm::uvec3 v = unpack_voxel(key) >> 2u;
        expected.push_back(pack_voxel(v.x, v.y, v.z));
    }
    const auto leaves = (*tree)->leaf_voxels();
    ASSERT_TRUE(leaves);
    EXPECT_EQ(std::vector<std::uint32_t>(leaves->begin(), leaves->end()), sorted_unique(expected));
    EXPECT_EQ((*tree)->depth(), 4u);
    coarse.fragment_shift = 7;
    EXPECT_FALSE(SparseTree::create(ctx(), coarse));
}

TEST_F(TreeTest, objectThatLeavesReturnsThePoolToItsBaseline) {
    TreeDesc desc;
    desc.branching = 4;
    desc.hysteresis = 0;
    Scene scene(ctx(), 64, desc);
    const TreeStats baseline = scene.frame(0, true, false);
    TreeStats with_ball;
    for (int n = 1; n < 6; ++n)
        with_ball = scene.frame(n, false, true);
    EXPECT_GT(with_ball.pool_bytes, baseline.pool_bytes);
    const TreeStats after = scene.frame(6, false, false);
    EXPECT_EQ(after.pool_bytes, baseline.pool_bytes);
    EXPECT_EQ(after.nodes, baseline.nodes);
    EXPECT_EQ(after.nodes_per_level, baseline.nodes_per_level);
    EXPECT_GT(after.coarsened, 0u);
}

TEST_F(TreeTest, hysteresisKeepsBlocksForKFramesThenCoarsens) {
    TreeDesc desc;
    desc.branching = 2;
    desc.hysteresis = 3;
    Scene scene(ctx(), 32, desc);
    const TreeStats baseline = scene.frame(0, true, false);
    // The ball stands still for two updates (2 and 3), then leaves; its blocks were last reached in
    // update 3 and stay while at most K = 3 updates have passed since.
    scene.frame(1, false, true);
    const TreeStats present = scene.frame(1, false, true);
    for (int n = 3; n <= 5; ++n) {
        const TreeStats s = scene.frame(n, false, false);
        EXPECT_EQ(s.pool_bytes, present.pool_bytes) << "update " << s.frame;
        EXPECT_EQ(s.coarsened, 0u);
    }
    const TreeStats gone = scene.frame(6, false, false);
    EXPECT_EQ(gone.pool_bytes, baseline.pool_bytes);
    EXPECT_GT(gone.coarsened, 0u);
}

TEST_F(TreeTest, manyFramesOfMotionDoNotGrowThePool) {
    TreeDesc desc;
    desc.branching = 4;
    desc.hysteresis = 1;
    Scene scene(ctx(), 16, desc);
    scene.frame(0, true, true, false);
    std::uint32_t node_mark = 0, mask_mark = 0;
    for (int n = 1; n < 2000; ++n) {
        const TreeStats s = scene.frame(n, false, true, n % 500 == 0);
        if (n == 80) {
            // Two full periods of the path: every state the pool goes through has occurred once.
            node_mark = s.node_blocks_used;
            mask_mark = s.mask_blocks_used;
        }
        if (n > 80) {
            ASSERT_LE(s.node_blocks_used, node_mark) << "frame " << n;
            ASSERT_LE(s.mask_blocks_used, mask_mark) << "frame " << n;
        }
    }
}

TEST_F(TreeTest, poolTooSmallGivesAValidPartialTreeThenTheFullOneOnceGrown) {
    TreeDesc desc;
    desc.branching = 2;
    desc.node_blocks = 6;
    desc.mask_blocks = 4;
    Scene scene(ctx(), 32, desc);
    const TreeStats partial = scene.frame(0, true, true, false);
    EXPECT_GT(partial.exhausted, 0u);
    std::vector<std::uint32_t> full = *scene.static_vox->read_fragments();
    const auto dyn = *scene.dynamic_vox->read_fragments();
    full.insert(full.end(), dyn.begin(), dyn.end());
    full = sorted_unique(full);
    const auto leaves = *scene.tree->leaf_voxels();
    EXPECT_LT(leaves.size(), full.size());
    EXPECT_TRUE(std::includes(full.begin(), full.end(), leaves.begin(), leaves.end()));
    ASSERT_TRUE(scene.tree->reserve(4096, 8192));
    const TreeStats grown = scene.frame(0, true, true);
    EXPECT_EQ(grown.exhausted, 0u);
}

TEST_F(TreeTest, sameSequenceTwiceGivesIdenticalTrees) {
    TreeDesc desc;
    desc.branching = 8;
    desc.hysteresis = 2;
    std::vector<std::vector<std::uint32_t>> runs[2];
    std::vector<std::uint64_t> nodes[2];
    for (int run = 0; run < 2; ++run) {
        Scene scene(ctx(), 64, desc);
        for (int n = 0; n < 8; ++n) {
            const TreeStats s = scene.frame(n, n == 0, true, false);
            nodes[run].push_back(s.nodes);
            const auto leaves = scene.tree->leaf_voxels();
            runs[run].emplace_back(leaves->begin(), leaves->end());
        }
    }
    EXPECT_EQ(runs[0], runs[1]);
    EXPECT_EQ(nodes[0], nodes[1]);
}

TEST(TreeSlots, slotOffsetIsTheChildsPositionInItsParent) {
    for (std::uint32_t log2_b : {1u, 2u, 3u}) {
        const std::uint32_t b = 1u << log2_b;
        // Slots count x fastest, then y, then z.
        std::uint32_t slot = 0;
        for (std::uint32_t z = 0; z < b; ++z)
            for (std::uint32_t y = 0; y < b; ++y)
                for (std::uint32_t x = 0; x < b; ++x, ++slot)
                    EXPECT_EQ(shaderio::slot_offset(slot, log2_b), glm::uvec3(x, y, z)) << "b " << b;
    }
}

/// A fragment list written by the test, not by the voxelizer.
struct KnownFragments {
    KnownFragments(gpu::Context& ctx, const std::vector<glm::uvec3>& voxels) {
        std::vector<std::uint32_t> keys;
        for (const glm::uvec3& v : voxels)
            keys.push_back(pack_voxel(v.x, v.y, v.z));
        const std::uint32_t count = std::uint32_t(keys.size());
        keys_ = std::move(gpu::Buffer::create(ctx, keys.size() * 4, gpu::MemoryUse::Device).value());
        count_ = std::move(gpu::Buffer::create(ctx, 4, gpu::MemoryUse::Device).value());
        EXPECT_TRUE(gpu::upload(ctx, keys_, keys.data(), keys.size() * 4));
        EXPECT_TRUE(gpu::upload(ctx, count_, &count, 4));
        source = {keys_.address(), count_.address(), keys.size()};
    }
    FragmentSource source;

  private:
    gpu::Buffer keys_, count_;
};

TEST_F(TreeTest, nodesAreDecodedLevelByLevelWithTheirCornersAndStates) {
    // b = 4, res 64: levels of 64, 16 and 4 voxels per node (the last: bricks).
    TreeDesc desc;
    desc.branching = 4;
    desc.res = 64;
    auto tree = SparseTree::create(ctx(), desc);
    ASSERT_TRUE(tree) << tree.message();
    const std::vector<glm::uvec3> walls = {{0, 0, 0}, {5, 9, 13}, {6, 9, 13}, {63, 63, 63}};
    const std::vector<glm::uvec3> mover = {{40, 2, 17}};
    const KnownFragments fixed(ctx(), walls), moving(ctx(), mover);
    ASSERT_TRUE((*tree)->update(&fixed.source, &moving.source));
    auto nodes = (*tree)->nodes();
    ASSERT_TRUE(nodes) << nodes.message();

    // By hand: the refined nodes of each level are the voxels' corners rounded down to that level's
    // extent; every node of a refined parent's block is listed.
    const std::uint32_t extent[3] = {64, 16, 4};
    using Corner = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>;
    std::set<Corner> refined[3], static_refined[3];
    for (std::uint32_t level = 0; level < 3; ++level) {
        for (const glm::uvec3& v : walls) {
            const glm::uvec3 c = v / extent[level] * extent[level];
            refined[level].insert({c.x, c.y, c.z});
            static_refined[level].insert({c.x, c.y, c.z});
        }
        for (const glm::uvec3& v : mover) {
            const glm::uvec3 c = v / extent[level] * extent[level];
            refined[level].insert({c.x, c.y, c.z});
        }
    }
    // Root; 64 children of the root; 64 for each refined level-1 node (two for walls, one for the mover
    // at (32, 0, 16), apart from the walls').
    ASSERT_EQ(refined[1].size(), 3u);
    ASSERT_EQ(nodes->size(), 1u + 64u + 64u * refined[1].size());
    std::map<std::uint32_t, std::set<Corner>> listed;
    std::uint32_t last_level = 0;
    for (const TreeNodeView& n : *nodes) {
        ASSERT_GE(n.level, last_level) << "coarse levels come first";
        last_level = n.level;
        ASSERT_LT(n.level, 3u);
        EXPECT_EQ(n.extent, extent[n.level]);
        const Corner c{n.min.x, n.min.y, n.min.z};
        EXPECT_TRUE(listed[n.level].insert(c).second) << "a node listed twice";
        EXPECT_EQ(n.refined, refined[n.level].count(c) == 1) << n.level << " " << n.min.x << " " << n.min.y;
        const TreeNodeView::State expected = static_refined[n.level].count(c) ? TreeNodeView::State::Static
                                             : refined[n.level].count(c)      ? TreeNodeView::State::Reached
                                                                              : TreeNodeView::State::Stale;
        EXPECT_EQ(n.state, expected) << "level " << n.level << " at " << n.min.x << " " << n.min.y << " "
                                     << n.min.z;
    }
    // Every child of a refined node, at its place in the parent.
    for (std::uint32_t level = 1; level < 3; ++level) {
        std::set<Corner> children;
        for (const auto& [x, y, z] : refined[level - 1])
            for (std::uint32_t slot = 0; slot < 64; ++slot) {
                const glm::uvec3 o(slot % 4, slot / 4 % 4, slot / 16);
                const glm::uvec3 c = glm::uvec3(x, y, z) + o * extent[level];
                children.insert({c.x, c.y, c.z});
            }
        EXPECT_EQ(listed[level], children) << "level " << level;
    }

    std::vector<std::uint32_t> expected_voxels;
    for (const auto& set : {walls, mover})
        for (const glm::uvec3& v : set)
            expected_voxels.push_back(pack_voxel(v.x, v.y, v.z));
    const auto leaves = (*tree)->leaf_voxels();
    ASSERT_TRUE(leaves) << leaves.message();
    EXPECT_EQ(std::vector<std::uint32_t>(leaves->begin(), leaves->end()), sorted_unique(expected_voxels));
}

TEST_F(TreeTest, grownPoolsHoldNothingUntilTheTreeIsRebuilt) {
    TreeDesc desc;
    desc.branching = 2;
    desc.res = 16;
    auto tree = SparseTree::create(ctx(), desc);
    ASSERT_TRUE(tree) << tree.message();
    const KnownFragments fixed(ctx(), {{1, 2, 3}, {9, 9, 9}});
    ASSERT_TRUE((*tree)->update(&fixed.source, nullptr));
    const TreePools before = (*tree)->pools();
    ASSERT_TRUE((*tree)->reserve(before.node_blocks, before.mask_blocks));
    EXPECT_FALSE((*tree)->rebuild_pending()) << "no growth, nothing dropped";
    ASSERT_TRUE((*tree)->reserve(before.node_blocks * 2, before.mask_blocks + 1));
    EXPECT_TRUE((*tree)->rebuild_pending());
    EXPECT_EQ((*tree)->pools().node_blocks, before.node_blocks * 2);
    EXPECT_TRUE((*tree)->leaf_voxels()->empty());
    EXPECT_EQ((*tree)->nodes()->size(), 1u);
    EXPECT_FALSE((*tree)->update(nullptr, &fixed.source)) << "an update that does not rebuild";
    ASSERT_TRUE((*tree)->update(&fixed.source, nullptr));
    EXPECT_FALSE((*tree)->rebuild_pending());
    const std::vector<std::uint32_t> expected = {pack_voxel(1, 2, 3), pack_voxel(9, 9, 9)};
    const auto leaves = (*tree)->leaf_voxels();
    ASSERT_TRUE(leaves);
    EXPECT_EQ(std::vector<std::uint32_t>(leaves->begin(), leaves->end()), expected);
}

TEST_F(TreeTest, fullPoolsCountEveryNodeRefined) {
    TreeDesc desc;
    desc.branching = 4;
    desc.res = 64;
    auto tree = SparseTree::create(ctx(), desc);
    ASSERT_TRUE(tree);
    // Node blocks: the root's, the root's children's, one per level-1 node (64); masks: 64 * 64 + block 0.
    EXPECT_EQ((*tree)->full_pools().node_blocks, 1u + 1u + 64u);
    EXPECT_EQ((*tree)->full_pools().mask_blocks, 4096u + 1u);
}

} // namespace
} // namespace gust::test
