#include "solver/solid_world.hpp"

#include <gtest/gtest.h>

namespace gust::test {

SolidWorld::SolidWorld(gpu::Context& ctx, const SolverDesc& desc, std::uint32_t branching)
    : ctx_(ctx), desc_(desc) {
    auto grid = voxel_grid(desc, branching);
    EXPECT_TRUE(grid) << grid.message();
    if (!grid) return;
    grid_ = *grid;
    WorldDesc world;
    world.grid = grid_;
    world.tree.branching = branching;
    world.tree.hysteresis = 0;
    world.method = VoxelizeMethod::Compute;
    auto created = VoxelWorld::create(ctx, world);
    EXPECT_TRUE(created) << created.message();
    if (created) world_ = std::move(*created);
}

void SolidWorld::update(const std::vector<Body>& bodies, float dt) {
    ASSERT_TRUE(world_);
    meshes_.clear();
    meshes_.reserve(bodies.size());
    for (const Body& body : bodies) {
        auto mesh = world_->upload(body.mesh.view());
        ASSERT_TRUE(mesh) << mesh.message();
        meshes_.push_back(std::move(*mesh));
    }
    std::vector<GpuInstance> statics, dynamics;
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        GpuInstance instance{&meshes_[i], bodies[i].model, bodies[i].prev_model};
        (bodies[i].prev_model ? dynamics : statics).push_back(instance);
    }
    world_->set_static(statics);
    auto frame = world_->step(dynamics, dt);
    ASSERT_TRUE(frame) << frame.message();
}

SolidSource SolidWorld::source() const {
    return solid_source(*world_);
}

CpuSolid SolidWorld::cpu() const {
    CpuSolid solid;
    const glm::uvec3 voxels = desc_.cells * desc_.voxels_per_cell;
    solid.occupied.assign(std::size_t(voxels.x) * voxels.y * voxels.z, 0);
    auto keys = world_->tree().leaf_voxels();
    EXPECT_TRUE(keys) << keys.message();
    if (!keys) return solid;
    for (std::uint32_t key : *keys) {
        const glm::uvec3 v(key & 1023u, (key >> 10) & 1023u, (key >> 20) & 1023u);
        if (v.x < voxels.x && v.y < voxels.y && v.z < voxels.z)
            solid.occupied[v.x + std::size_t(voxels.x) * (v.y + std::size_t(voxels.y) * v.z)] =
                CpuSolid::kMoving;
    }
    // The static voxelizer's fragments (one per voxel and triangle) mark the static solid.
    auto fixed = world_->static_voxelizer().read_fragments();
    EXPECT_TRUE(fixed) << fixed.message();
    if (!fixed) return solid;
    for (std::uint32_t key : *fixed) {
        const glm::uvec3 v(key & 1023u, (key >> 10) & 1023u, (key >> 20) & 1023u);
        if (v.x < voxels.x && v.y < voxels.y && v.z < voxels.z)
            solid.occupied[v.x + std::size_t(voxels.x) * (v.y + std::size_t(voxels.y) * v.z)] =
                CpuSolid::kStatic;
    }
    const Voxelizer& moving = world_->dynamic_voxelizer();
    auto fragments = moving.read_fragments();
    auto velocities = moving.read_velocities();
    EXPECT_TRUE(fragments && velocities);
    if (!fragments || !velocities) return solid;
    for (std::size_t i = 0; i < fragments->size() && i < velocities->size(); ++i) {
        const std::uint32_t key = (*fragments)[i];
        solid.fragments.emplace_back(glm::ivec3(key & 1023u, (key >> 10) & 1023u, (key >> 20) & 1023u),
                                     (*velocities)[i]);
    }
    return solid;
}

} // namespace gust::test
