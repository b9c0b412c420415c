// System's answers: wind queries, the texture, stats and the debug views (include/gust/gust.hpp); the
// OpenVDB export is in system_export.cpp.
#include "system_impl.hpp"

#include <algorithm>

namespace gust {

using namespace detail;

namespace {
Outcome check_points(std::span<const Vec3> points) {
    if (points.size() > kMaxQueryPoints)
        return invalid(std::to_string(points.size()) + " points, more than the " +
                       std::to_string(kMaxQueryPoints) + " a query takes");
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!finite(points[i])) return invalid("point " + std::to_string(i) + " is not finite");
    return {};
}
} // namespace

Outcome System::query(std::span<const Vec3> points, std::span<Vec3> velocities, WindReading reading) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("query");
    return impl_->query(points, velocities, reading);
}

Outcome System::Impl::query(std::span<const Vec3> points, std::span<Vec3> velocities, WindReading reading) {
    if (reading != WindReading::Wind && reading != WindReading::Solver)
        return invalid("reading " + std::to_string(int(reading)) + " is not a WindReading");
    if (velocities.size() != points.size())
        return invalid("velocities holds " + std::to_string(velocities.size()) + " entries for " +
                       std::to_string(points.size()) + " points");
    if (Outcome o = check_points(points); !o) return o;
    return guarded([&]() -> Outcome {
        std::pmr::vector<glm::vec3> at(points.size(), &memory);
        for (std::size_t i = 0; i < points.size(); ++i)
            at[i] = to_glm(points[i]);
        auto answers =
            solver->sample(at, reading == WindReading::Wind ? PointSample::Wind : PointSample::Field);
        if (!answers) return device_failure(answers.status());
        for (std::size_t i = 0; i < points.size(); ++i)
            velocities[i] = to_vec3((*answers)[i]);
        return {};
    });
}

Outcome System::query_async(std::span<const Vec3> points, QueryId& id) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("query_async");
    id = 0;
    if (Outcome o = check_points(points); !o) return o;
    return guarded([&]() -> Outcome {
        Impl::Pending pending(&impl_->memory);
        pending.points.reserve(points.size());
        for (const Vec3& p : points)
            pending.points.push_back(to_glm(p));
        const QueryId next = impl_->next_id++;
        impl_->queries.emplace(next, std::move(pending));
        id = next;
        return {};
    });
}

Outcome System::fetch(QueryId id, std::span<Vec3> velocities) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("fetch");
    auto it = impl_->queries.find(id);
    if (it == impl_->queries.end())
        return Outcome(ErrorCode::InvalidHandle, "no query " + std::to_string(id));
    if (!it->second.ready)
        return Outcome(ErrorCode::NotReady, "query " + std::to_string(id) + " is answered by the next step");
    if (velocities.size() != it->second.answer.size())
        return invalid("velocities holds " + std::to_string(velocities.size()) + " entries for " +
                       std::to_string(it->second.answer.size()) + " points");
    for (std::size_t i = 0; i < velocities.size(); ++i)
        velocities[i] = to_vec3(it->second.answer[i]);
    impl_->queries.erase(it);
    return {};
}

Outcome System::wind_at(const Vec3& point, WindSample& sample) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("wind_at");
    sample = {};
    if (!finite(point)) return invalid("point is not finite");
    const float h = impl_->solver_desc.cell_size;
    const Vec3 points[7] = {point,
                            {point.x - h, point.y, point.z},
                            {point.x + h, point.y, point.z},
                            {point.x, point.y - h, point.z},
                            {point.x, point.y + h, point.z},
                            {point.x, point.y, point.z - h},
                            {point.x, point.y, point.z + h}};
    Vec3 v[7];
    if (Outcome o = impl_->query(points, v, WindReading::Wind); !o) return o;
    glm::vec3 mean(0.0f);
    for (int i = 1; i < 7; ++i)
        mean += to_glm(v[i]) / 6.0f;
    const glm::vec3 here = to_glm(v[0]);
    sample.speed = glm::length(here);
    sample.direction = sample.speed > 0.0f ? to_vec3(here / sample.speed) : Vec3{};
    sample.gust = glm::length(here - mean);
    return {};
}

const WindTexture& System::wind_texture() const {
    return impl_->frame->textures().front();
}

std::span<const WindTexture> System::wind_textures() const {
    return impl_->frame->textures();
}
const FrameStats& System::stats() const {
    return impl_->stats;
}

Outcome System::set_dispatch_timing(bool on) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_dispatch_timing");
    return impl_->frame->time_dispatches(on);
}

Outcome System::read_stats(FrameStats& out) const {
    return guarded([&]() -> Outcome {
        const std::lock_guard lock(impl_->stats_mutex);
        out = impl_->stats;
        return {};
    });
}

Outcome System::sample(std::span<const Vec3> points, std::span<Vec3> velocities) const {
    SnapshotInfo info;
    return sample(points, velocities, info);
}

Outcome System::sample(std::span<const Vec3> points, std::span<Vec3> velocities, SnapshotInfo& info) const {
    info = {};
    if (velocities.size() != points.size())
        return invalid("velocities holds " + std::to_string(velocities.size()) + " entries for " +
                       std::to_string(points.size()) + " points");
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!finite(points[i])) return invalid("point " + std::to_string(i) + " is not finite");
    if (!impl_->snapshot)
        return Outcome(ErrorCode::NotEnabled,
                       "the snapshot is off: create the System with SystemDesc::snapshot");
    int held = 0;
    const SnapshotData* data = impl_->snapshot->acquire(held);
    if (!data) return Outcome(ErrorCode::NotReady, "no step has published a snapshot yet");
    sample_snapshot(*data, points, velocities);
    info.frame = data->frame;
    const SnapshotLevel& finest = data->levels.front();
    info.origin = to_vec3(finest.origin);
    info.cell_size = finest.cell_size;
    for (int a = 0; a < 3; ++a)
        info.extent[a] = std::uint32_t(finest.extent[a]);
    impl_->snapshot->release(held);
    return {};
}
Vec3 System::domain_origin() const {
    return to_vec3(impl_->solver->origin());
}
const char* System::device_name() const {
    return impl_->ctx->info().name.c_str();
}
QueueInfo System::queue_info() const {
    return {.family = impl_->ctx->queue_family(), .async_compute = !impl_->ctx->info().graphics_queue};
}

Outcome System::debug_voxel_grid(VoxelGridInfo& info) const {
    const GridDesc& grid = impl_->world->grid();
    const SparseTree& tree = impl_->world->tree();
    info = {};
    info.origin = to_vec3(grid.origin);
    info.voxel_size = grid.voxel_size;
    std::fill(std::begin(info.resolution), std::end(info.resolution), grid.res);
    info.depth = tree.depth();
    info.branching = tree.branching();
    return {};
}

Outcome System::debug_voxels(std::span<VoxelCoord> out, std::size_t& count) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("debug_voxels");
    count = 0;
    return guarded([&]() -> Outcome {
        auto keys = impl_->world->tree().leaf_voxels();
        if (!keys) return device_failure(keys.status());
        const std::size_t written = std::min(out.size(), keys->size());
        for (std::size_t v = 0; v < written; ++v) {
            const glm::uvec3 c = unpack_voxel((*keys)[v]);
            out[v] = {c.x, c.y, c.z};
        }
        count = keys->size();
        return {};
    });
}

Outcome System::debug_tree_nodes(std::span<TreeNode> out, std::size_t& count) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("debug_tree_nodes");
    count = 0;
    return guarded([&]() -> Outcome {
        // SparseTree decodes its own pool, coarse levels first, so a short `out` still holds them whole.
        // A pool that does not decode (a block linked twice or out of range) breaks an internal invariant.
        auto nodes = impl_->world->tree().nodes();
        if (!nodes) {
            static_cast<void>(impl_->check(false, "the tree's node pool decodes", __LINE__));
            return device_failure(nodes.status());
        }
        const GridDesc& grid = impl_->world->grid();
        const std::size_t written = std::min(out.size(), nodes->size());
        for (std::size_t i = 0; i < written; ++i) {
            const TreeNodeView& v = (*nodes)[i];
            TreeNode& n = out[i];
            n.min = to_vec3(grid.origin + glm::vec3(v.min) * grid.voxel_size);
            n.size = float(v.extent) * grid.voxel_size;
            n.level = v.level;
            n.state = v.state == TreeNodeView::State::Static    ? TreeNodeState::Static
                      : v.state == TreeNodeView::State::Reached ? TreeNodeState::Reached
                                                                : TreeNodeState::Stale;
            n.refined = v.refined;
        }
        count = nodes->size();
        return {};
    });
}

} // namespace gust
