// The C ABI (gust.h), its answers: wind queries, the texture, stats and the debug views over
// gust::System (gust_c_internal.hpp has the registry and the conversions).
#include "gust_c_internal.hpp"

using namespace gust::capi;

extern "C" {

namespace {
gust_result query(const char* function, gust_system system, const gust_vec3* points, size_t count,
                  gust_vec3* velocities, gust_wind_reading reading) {
    return on_system(system, function, [&](gust::System& s) -> gust::Outcome {
        if (reading != GUST_WIND_READING_WIND && reading != GUST_WIND_READING_SOLVER)
            return invalid("reading " + std::to_string(int(reading)) + " is not a gust_wind_reading");
        if (count > 0 && !points) return invalid("points is NULL but count is " + std::to_string(count));
        if (count > 0 && !velocities)
            return invalid("velocities is NULL but count is " + std::to_string(count));
        if (count > gust::kMaxQueryPoints)
            return invalid(std::to_string(count) + " points, more than GUST_MAX_QUERY_POINTS");
        const std::vector<gust::Vec3> in = to_cpp(points, count);
        std::vector<gust::Vec3> out(count);
        gust::Outcome outcome = s.query(in, out, gust::WindReading(reading));
        if (outcome) to_c(out, velocities);
        return outcome;
    });
}
} // namespace

gust_result gust_system_query(gust_system system, const gust_vec3* points, size_t count,
                              gust_vec3* velocities) {
    return query("gust_system_query", system, points, count, velocities, GUST_WIND_READING_WIND);
}

gust_result gust_system_query_reading(gust_system system, const gust_vec3* points, size_t count,
                                      gust_vec3* velocities, gust_wind_reading reading) {
    return query("gust_system_query_reading", system, points, count, velocities, reading);
}

gust_result gust_system_query_async(gust_system system, const gust_vec3* points, size_t count,
                                    gust_query* query) {
    return on_system(system, "gust_system_query_async", [&](gust::System& s) -> gust::Outcome {
        if (!query) return invalid("query (the output) is NULL");
        *query = 0;
        if (count > 0 && !points) return invalid("points is NULL but count is " + std::to_string(count));
        if (count > gust::kMaxQueryPoints)
            return invalid(std::to_string(count) + " points, more than GUST_MAX_QUERY_POINTS");
        const std::vector<gust::Vec3> in = to_cpp(points, count);
        gust::QueryId id = 0;
        gust::Outcome outcome = s.query_async(in, id);
        if (outcome) *query = id;
        return outcome;
    });
}

gust_result gust_system_fetch(gust_system system, gust_query query, gust_vec3* velocities, size_t count) {
    return on_system(system, "gust_system_fetch", [&](gust::System& s) -> gust::Outcome {
        if (count > 0 && !velocities)
            return invalid("velocities is NULL but count is " + std::to_string(count));
        std::vector<gust::Vec3> out(count);
        gust::Outcome outcome = s.fetch(query, out);
        if (outcome) to_c(out, velocities);
        return outcome;
    });
}

gust_result gust_system_wind_at(gust_system system, gust_vec3 point, gust_wind_sample* sample) {
    return on_system(system, "gust_system_wind_at", [&](gust::System& s) -> gust::Outcome {
        if (!sample) return invalid("sample (the output) is NULL");
        gust::WindSample w;
        gust::Outcome outcome = s.wind_at(to_cpp(point), w);
        if (outcome) *sample = to_c(w);
        return outcome;
    });
}

gust_result gust_system_wind_texture(gust_system system, gust_wind_texture* texture) {
    return on_system(system, "gust_system_wind_texture", [&](gust::System& s) -> gust::Outcome {
        if (!texture) return invalid("texture (the output) is NULL");
        *texture = to_c(s.wind_texture());
        return {};
    });
}

gust_result gust_system_cascade_texture(gust_system system, uint32_t cascade, gust_wind_texture* texture) {
    return on_system(system, "gust_system_cascade_texture", [&](gust::System& s) -> gust::Outcome {
        if (!texture) return invalid("texture (the output) is NULL");
        const std::span<const gust::WindTexture> textures = s.wind_textures();
        if (cascade >= textures.size())
            return invalid("cascade " + std::to_string(cascade) + " is beyond the last, " +
                           std::to_string(textures.size() - 1));
        *texture = to_c(textures[cascade]);
        return {};
    });
}

gust_result gust_system_stats(gust_system system, gust_frame_stats* stats) {
    return on_system(system, "gust_system_stats", [&](gust::System& s) -> gust::Outcome {
        if (!stats) return invalid("stats (the output) is NULL");
        *stats = to_c(s.stats());
        return {};
    });
}

gust_result gust_system_sample(gust_system system, const gust_vec3* points, size_t count,
                               gust_vec3* velocities, uint64_t* frame) {
    return on_system_reader(system, "gust_system_sample", [&](const gust::System& s) -> gust::Outcome {
        if (frame) *frame = 0;
        if (count > 0 && !points) return invalid("points is NULL but count is " + std::to_string(count));
        if (count > 0 && !velocities)
            return invalid("velocities is NULL but count is " + std::to_string(count));
        // gust_vec3 and gust::Vec3 are both three floats (gust_c.cpp checks): no copy.
        const std::span in(reinterpret_cast<const gust::Vec3*>(points), count);
        const std::span out(reinterpret_cast<gust::Vec3*>(velocities), count);
        gust::SnapshotInfo info;
        gust::Outcome outcome = s.sample(in, out, info);
        if (outcome && frame) *frame = info.frame;
        return outcome;
    });
}

gust_result gust_system_stats_nodes_per_level(gust_system system, uint64_t* nodes, uint32_t capacity,
                                              uint32_t* count) {
    return on_system(system, "gust_system_stats_nodes_per_level", [&](gust::System& s) -> gust::Outcome {
        if (!count) return invalid("count (the output) is NULL");
        if (!nodes && capacity > 0)
            return invalid("nodes is NULL but capacity is " + std::to_string(capacity));
        const auto& levels = s.stats().nodes_per_level;
        *count = count32(levels.size());
        std::copy_n(levels.begin(), std::min<std::size_t>(capacity, levels.size()), nodes);
        return {};
    });
}

gust_result gust_system_stats_pass_count(gust_system system, uint32_t* count) {
    return on_system(system, "gust_system_stats_pass_count", [&](gust::System& s) -> gust::Outcome {
        if (!count) return invalid("count (the output) is NULL");
        *count = count32(s.stats().ms.size());
        return {};
    });
}

gust_result gust_system_stats_pass(gust_system system, uint32_t index, const char** name, double* ms) {
    return on_system(system, "gust_system_stats_pass", [&](gust::System& s) -> gust::Outcome {
        const auto& passes = s.stats().ms;
        if (index >= passes.size()) {
            return invalid("index " + std::to_string(index) + " out of range (" +
                           std::to_string(passes.size()) + " passes)");
        }
        if (name) *name = passes[index].first.c_str();
        if (ms) *ms = passes[index].second;
        return {};
    });
}

gust_result gust_system_set_dispatch_timing(gust_system system, bool on) {
    return on_system(system, "gust_system_set_dispatch_timing",
                     [&](gust::System& s) { return s.set_dispatch_timing(on); });
}

gust_result gust_system_export_wind_copy(gust_system system, uint32_t cascade, uint32_t slot,
                                         gust_exported_image* image) {
    return on_system(system, "gust_system_export_wind_copy", [&](gust::System& s) -> gust::Outcome {
        if (!image) return invalid("image (the output) is NULL");
        gust::ExportedImage e;
        if (gust::Outcome o = s.export_wind_copy(cascade, slot, e); !o) return o;
        *image = {.fd = e.fd,
                  .allocation_size = e.allocation_size,
                  .memory_type_index = e.memory_type_index,
                  .format = e.format,
                  .extent = {e.extent[0], e.extent[1], e.extent[2]},
                  .usage = e.usage};
        return {};
    });
}

gust_result gust_system_copy_wind_textures(gust_system system, uint32_t slot) {
    return on_system(system, "gust_system_copy_wind_textures",
                     [&](gust::System& s) { return s.copy_wind_textures(slot); });
}

gust_result gust_system_domain_origin(gust_system system, gust_vec3* origin) {
    return on_system(system, "gust_system_domain_origin", [&](gust::System& s) -> gust::Outcome {
        if (!origin) return invalid("origin (the output) is NULL");
        *origin = to_c(s.domain_origin());
        return {};
    });
}

gust_result gust_system_device_name(gust_system system, const char** name) {
    return on_system(system, "gust_system_device_name", [&](gust::System& s) -> gust::Outcome {
        if (!name) return invalid("name (the output) is NULL");
        *name = s.device_name();
        return {};
    });
}

gust_result gust_system_queue_info(gust_system system, gust_queue_info* info) {
    return on_system(system, "gust_system_queue_info", [&](gust::System& s) -> gust::Outcome {
        if (!info) return invalid("info (the output) is NULL");
        const gust::QueueInfo queue = s.queue_info();
        *info = {queue.family, queue.async_compute};
        return {};
    });
}

gust_result gust_system_debug_voxel_grid(gust_system system, gust_voxel_grid_info* info) {
    return on_system(system, "gust_system_debug_voxel_grid", [&](gust::System& s) -> gust::Outcome {
        if (!info) return invalid("info (the output) is NULL");
        gust::VoxelGridInfo grid;
        gust::Outcome outcome = s.debug_voxel_grid(grid);
        if (outcome) {
            info->origin = to_c(grid.origin);
            info->voxel_size = grid.voxel_size;
            std::copy_n(grid.resolution, 3, info->resolution);
            info->depth = grid.depth;
            info->branching = grid.branching;
        }
        return outcome;
    });
}

gust_result gust_system_debug_voxels(gust_system system, gust_voxel_coord* voxels, size_t capacity,
                                     size_t* count) {
    return on_system(system, "gust_system_debug_voxels", [&](gust::System& s) {
        return fill_list<gust::VoxelCoord>(
            voxels, capacity, count, "voxels",
            [&](std::span<gust::VoxelCoord> out, std::size_t& total) { return s.debug_voxels(out, total); },
            [](const gust::VoxelCoord& v) {
                return gust_voxel_coord{v.i, v.j, v.k};
            });
    });
}

gust_result gust_system_debug_tree_nodes(gust_system system, gust_tree_node* nodes, size_t capacity,
                                         size_t* count) {
    return on_system(system, "gust_system_debug_tree_nodes", [&](gust::System& s) {
        return fill_list<gust::TreeNode>(
            nodes, capacity, count, "nodes",
            [&](std::span<gust::TreeNode> out, std::size_t& total) { return s.debug_tree_nodes(out, total); },
            [](const gust::TreeNode& n) {
                return gust_tree_node{.min = to_c(n.min),
                                      .size = n.size,
                                      .level = n.level,
                                      .state = static_cast<gust_tree_node_state>(n.state),
                                      .refined = n.refined};
            });
    });
}

} // extern "C"
