#include <algorithm>
#include <cmath>
#include <gust/voxelizer/voxel_world.hpp>

namespace gust {

namespace {

bool same_instance(const GpuInstance& a, const GpuInstance& b) {
    return a.mesh == b.mesh && a.model == b.model;
}

void append_ms(std::vector<std::pair<std::string, double>>& out, const std::string& prefix,
               const std::vector<std::pair<std::string, double>>& passes) {
    for (const auto& [name, ms] : passes)
        out.emplace_back(prefix + name, ms);
}

} // namespace

Result<std::unique_ptr<VoxelWorld>> VoxelWorld::create(gpu::Context& ctx, const WorldDesc& desc) {
    if (Status s = validate_grid(desc.grid); !s) return s;
    std::unique_ptr<VoxelWorld> world(new VoxelWorld(desc));
    world->desc_.tree.res = desc.grid.res;
    auto static_voxelizer = Voxelizer::create(ctx);
    if (!static_voxelizer) return static_voxelizer.status();
    world->static_ = std::move(*static_voxelizer);
    auto dynamic_voxelizer = Voxelizer::create(ctx);
    if (!dynamic_voxelizer) return dynamic_voxelizer.status();
    world->dynamic_ = std::move(*dynamic_voxelizer);
    auto tree = SparseTree::create(ctx, world->desc_.tree);
    if (!tree) return tree.status();
    world->tree_ = std::move(*tree);
    return world;
}

void VoxelWorld::set_static(std::vector<GpuInstance> instances) {
    const bool same = instances.size() == static_set_.size() &&
                      std::equal(instances.begin(), instances.end(), static_set_.begin(), same_instance);
    if (!same) static_dirty_ = true;
    static_set_ = std::move(instances);
}

Status VoxelWorld::move_grid(glm::vec3 origin) {
    if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z))
        return Status::failure("grid origin must be finite");
    if (origin == desc_.grid.origin) return Status{};
    desc_.grid.origin = origin;
    static_dirty_ = true;
    return Status{};
}

Result<WorldFrame> VoxelWorld::step(std::span<const GpuInstance> dynamic, float dt) {
    if (!(dt > 0.0f))
        return Result<WorldFrame>::failure("frame time must be > 0 s, got " + std::to_string(dt));
    WorldFrame out;
    out.frame = frame_;
    const bool rebuild = static_dirty_;
    if (rebuild) {
        auto stats = static_->voxelize(static_set_, desc_.grid, desc_.method);
        if (!stats) return stats.status();
        last_static_ = *stats;
        append_ms(out.ms, "voxelize_static_", stats->ms);
    }
    auto dyn = dynamic_->voxelize(dynamic, desc_.grid, desc_.method, dt);
    if (!dyn) return dyn.status();
    append_ms(out.ms, "voxelize_", dyn->ms);

    const FragmentSource static_source{static_->fragment_buffer().address(),
                                       static_->fragment_count_address(), static_->fragment_capacity()};
    const FragmentSource dynamic_source{dynamic_->fragment_buffer().address(),
                                        dynamic_->fragment_count_address(), dynamic_->fragment_capacity()};
    auto tree = tree_->update(rebuild ? &static_source : nullptr, &dynamic_source);
    if (!tree) return tree.status();
    // Refinement stopped where a pool ran out: grow both pools and rebuild this frame's tree from the
    // kept fragment lists, so no frame is left partial.
    while (tree->exhausted > 0) {
        const std::uint32_t nodes = tree_->node_capacity(), masks = tree_->mask_capacity();
        if (Status s = tree_->reserve(nodes * 2, masks * 2); !s) return s;
        ++out.pool_growths;
        tree = tree_->update(&static_source, &dynamic_source);
        if (!tree) return tree.status();
    }
    static_dirty_ = false;
    append_ms(out.ms, "", tree->ms);
    out.static_rebuilt = rebuild;
    out.static_voxelize = last_static_;
    out.dynamic_voxelize = *dyn;
    out.tree = *tree;
    ++frame_;
    return out;
}

} // namespace gust
