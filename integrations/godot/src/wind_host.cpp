#include "wind_host.hpp"

#include <chrono>
#include <cmath>
#include <cstring>

namespace gust::integration {

namespace {

bool finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string str(float v) {
    return std::to_string(v);
}

} // namespace

std::string validate(const WindHostConfig& config) {
    for (int a = 0; a < 3; ++a) {
        if (config.cells[a] < 8 || config.cells[a] > 256) {
            return "cells." + std::string(1, "xyz"[a]) + " = " + std::to_string(config.cells[a]) +
                   ": each axis must have 8 to 256 cells";
        }
    }
    if (config.voxels_per_cell < 1 || config.voxels_per_cell > 8) {
        return "voxels_per_cell = " + std::to_string(config.voxels_per_cell) + ": must be 1 to 8";
    }
    const float min_cell = 1e-4f * float(config.voxels_per_cell);
    if (!std::isfinite(config.cell_size) || config.cell_size < min_cell || config.cell_size > 1000.0f) {
        return "cell_size = " + str(config.cell_size) + ": must be a length in metres from " + str(min_cell) +
               " (1e-4 per voxel) to 1000";
    }
    if (!finite(config.ambient)) {
        return "ambient must be finite";
    }
    if (config.quality < 0 || config.quality > 2) {
        return "quality = " + std::to_string(config.quality) + ": must be 0 (low), 1 (medium) or 2 (high)";
    }
    if (!finite(config.focus)) {
        return "the node's position must be finite";
    }
    return "";
}

WindSettings quality_settings(std::int32_t quality) {
    WindSettings s;
    if (quality <= 0) {
        s.advection = WindAdvection::SemiLagrangian;
        s.cycles_per_step = 1;
        s.vorticity = 0.0f;
    } else if (quality >= 2) {
        s.cycles_per_step = 4;
    }
    return s;
}

Outcome WindHost::create(const WindHostConfig& config, const Hooks& hooks) {
    destroy();
    if (std::string message = validate(config); !message.empty()) {
        return {ErrorCode::InvalidArgument, message};
    }
    SystemDesc desc;
    for (int a = 0; a < 3; ++a) {
        desc.domain.cells[a] = config.cells[a];
    }
    desc.domain.cell_size = config.cell_size;
    desc.domain.voxels_per_cell = config.voxels_per_cell;
    desc.domain.focus = config.focus;
    desc.wind = quality_settings(config.quality);
    desc.hooks = hooks;
    desc.snapshot = true;
    if (Outcome o = System::create(desc, system_); !o) {
        return o;
    }
    config_ = config;
    steps_ = 0;
    return system_->set_ambient(config.ambient);
}

void WindHost::destroy() {
    system_.reset();
    meshes_.clear();
    obstacles_.clear();
    steps_ = 0;
}

void WindHost::begin_obstacles() {
    for (auto& [key, o] : obstacles_) {
        o.seen = false;
    }
}

Outcome WindHost::add_mesh(std::uint64_t mesh_key, std::span<const float> positions,
                           std::span<const std::uint32_t> indices) {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no wind System (invalid properties)"};
    }
    MeshDesc desc;
    desc.positions = positions.data();
    desc.vertex_count = std::uint32_t(positions.size() / 3);
    desc.indices = indices.data();
    desc.index_count = std::uint32_t(indices.size());
    MeshId id = 0;
    if (Outcome o = system_->create_mesh(desc, id); !o) {
        return o;
    }
    meshes_[mesh_key] = id;
    return {};
}

Outcome WindHost::report_obstacle(std::uint64_t key, std::uint64_t mesh_key, const Mat4& transform) {
    auto mesh = meshes_.find(mesh_key);
    if (!system_ || mesh == meshes_.end()) {
        return {ErrorCode::InvalidHandle, "obstacle reported before its mesh was added"};
    }
    auto it = obstacles_.find(key);
    if (it != obstacles_.end() && it->second.mesh_key != mesh_key) {
        system_->destroy_instance(it->second.instance);
        obstacles_.erase(it);
        it = obstacles_.end();
    }
    if (it == obstacles_.end()) {
        Obstacle o;
        o.mesh_key = mesh_key;
        o.transform = transform;
        o.seen = true;
        if (Outcome r = system_->create_instance(mesh->second, transform, false, o.instance); !r) {
            return r;
        }
        obstacles_[key] = o;
        return {};
    }
    Obstacle& o = it->second;
    o.seen = true;
    if (std::memcmp(o.transform.m, transform.m, sizeof(transform.m)) == 0) {
        return {};
    }
    if (!o.moving) {
        // A static instance that moves would re-voxelize the whole static set every frame and push no air:
        // from its first move on it is a moving instance, already in motion from its last transform.
        InstanceId moving = 0;
        if (Outcome r = system_->create_moving_instance(mesh->second, transform, o.transform, moving); !r) {
            return r;
        }
        system_->destroy_instance(o.instance);
        o.instance = moving;
        o.moving = true;
    } else if (Outcome r = system_->set_transform(o.instance, transform); !r) {
        return r;
    }
    o.transform = transform;
    return {};
}

void WindHost::end_obstacles() {
    if (!system_) {
        return;
    }
    for (auto it = obstacles_.begin(); it != obstacles_.end();) {
        if (it->second.seen) {
            ++it;
            continue;
        }
        system_->destroy_instance(it->second.instance);
        it = obstacles_.erase(it);
    }
    for (auto it = meshes_.begin(); it != meshes_.end();) {
        bool used = false;
        for (const auto& [key, o] : obstacles_) {
            used = used || o.mesh_key == it->first;
        }
        if (used) {
            ++it;
            continue;
        }
        system_->destroy_mesh(it->second);
        it = meshes_.erase(it);
    }
}

std::size_t WindHost::moving_obstacles() const {
    std::size_t n = 0;
    for (const auto& [key, o] : obstacles_) {
        n += o.moving ? 1 : 0;
    }
    return n;
}

Outcome WindHost::set_emitters(std::span<const WindEmitter> emitters) {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no wind System (invalid properties)"};
    }
    return system_->set_emitters(emitters);
}

Outcome WindHost::set_ambient(const Vec3& velocity) {
    config_.ambient = velocity;
    if (!system_) {
        return {};
    }
    return system_->set_ambient(velocity);
}

Outcome WindHost::step(float dt) {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no wind System (invalid properties)"};
    }
    const auto start = std::chrono::steady_clock::now();
    Outcome o = system_->step(dt);
    last_step_ms_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (o) {
        ++steps_;
    }
    return o;
}

void WindHost::sample(std::span<const Vec3> points, std::span<Vec3> velocities, const Vec3& fallback) const {
    if (system_ && system_->sample(points, velocities)) {
        return;
    }
    for (Vec3& v : velocities) {
        v = fallback;
    }
}

Outcome WindHost::read_field(WindField& field) const {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no wind System (invalid properties)"};
    }
    SnapshotInfo info;
    Vec3 probe{};
    Vec3 ignored{};
    if (Outcome o = system_->sample({&probe, 1}, {&ignored, 1}, info); !o) {
        return o;
    }
    const std::uint32_t nx = info.extent[0], ny = info.extent[1], nz = info.extent[2];
    std::vector<Vec3> points(std::size_t(nx) * ny * nz);
    std::vector<Vec3> velocities(points.size());
    std::size_t n = 0;
    for (std::uint32_t k = 0; k < nz; ++k) {
        for (std::uint32_t j = 0; j < ny; ++j) {
            for (std::uint32_t i = 0; i < nx; ++i) {
                points[n++] = {info.origin.x + (float(i) + 0.5f) * info.cell_size,
                               info.origin.y + (float(j) + 0.5f) * info.cell_size,
                               info.origin.z + (float(k) + 0.5f) * info.cell_size};
            }
        }
    }
    SnapshotInfo used;
    if (Outcome o = system_->sample(points, velocities, used); !o) {
        return o;
    }
    if (used.frame != info.frame) {
        // A step published between the two calls: its domain may have scrolled; the next read gets it whole.
        return {ErrorCode::NotReady, "a step was published while the field was read"};
    }
    field.rgba.resize(points.size() * 4);
    for (std::size_t c = 0; c < velocities.size(); ++c) {
        field.rgba[4 * c + 0] = velocities[c].x;
        field.rgba[4 * c + 1] = velocities[c].y;
        field.rgba[4 * c + 2] = velocities[c].z;
        field.rgba[4 * c + 3] = 1.0f;
    }
    for (int a = 0; a < 3; ++a) {
        field.extent[a] = info.extent[a];
    }
    field.origin = info.origin;
    field.cell_size = info.cell_size;
    field.frame = info.frame;
    return {};
}

std::string WindHost::device_name() const {
    return system_ ? system_->device_name() : "";
}

} // namespace gust::integration
