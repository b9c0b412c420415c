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

// The inverse of an affine matrix (last row 0, 0, 0, 1); false when its 3x3 part is singular.
bool affine_inverse(const Mat4& a, Mat4& out) {
    const float* m = a.m;
    // Cofactors of the 3x3 part (column-major: element (row r, column c) is m[4c + r]).
    const float c00 = m[5] * m[10] - m[9] * m[6], c01 = m[9] * m[2] - m[1] * m[10],
                c02 = m[1] * m[6] - m[5] * m[2];
    const float c10 = m[8] * m[6] - m[4] * m[10], c11 = m[0] * m[10] - m[8] * m[2],
                c12 = m[4] * m[2] - m[0] * m[6];
    const float c20 = m[4] * m[9] - m[8] * m[5], c21 = m[8] * m[1] - m[0] * m[9],
                c22 = m[0] * m[5] - m[4] * m[1];
    const float det = m[0] * c00 + m[4] * c01 + m[8] * c02;
    if (!std::isfinite(det) || std::fabs(det) < 1e-12f) {
        return false;
    }
    const float inv = 1.0f / det;
    float* o = out.m;
    o[0] = c00 * inv, o[1] = c01 * inv, o[2] = c02 * inv, o[3] = 0.0f;
    o[4] = c10 * inv, o[5] = c11 * inv, o[6] = c12 * inv, o[7] = 0.0f;
    o[8] = c20 * inv, o[9] = c21 * inv, o[10] = c22 * inv, o[11] = 0.0f;
    for (int r = 0; r < 3; ++r) {
        o[12 + r] = -(o[r] * m[12] + o[4 + r] * m[13] + o[8 + r] * m[14]);
    }
    o[15] = 1.0f;
    return true;
}

} // namespace

Mat4 multiply(const Mat4& a, const Mat4& b) {
    Mat4 out;
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            float sum = 0.0f;
            for (int k = 0; k < 4; ++k) {
                sum += a.m[4 * k + r] * b.m[4 * c + k];
            }
            out.m[4 * c + r] = sum;
        }
    }
    return out;
}

Outcome default_skin(std::span<const Mat4> rests, std::span<const std::int32_t> parents,
                     std::vector<SkinBind>& binds) {
    const std::size_t n = rests.size();
    if (parents.size() != n) {
        return {ErrorCode::InvalidArgument, "a parent for every bone is needed"};
    }
    std::vector<Mat4> global(n);
    std::vector<char> done(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        // Walk up to the first bone already composed (or a root), then compose down again.
        std::vector<std::size_t> chain;
        for (std::size_t b = i; !done[b];) {
            if (chain.size() > n) {
                return {ErrorCode::InvalidArgument, "bone " + std::to_string(i) + "'s parents form a cycle"};
            }
            chain.push_back(b);
            const std::int32_t p = parents[b];
            if (p < 0) {
                break;
            }
            if (std::size_t(p) >= n) {
                return {ErrorCode::InvalidArgument,
                        "bone " + std::to_string(b) + "'s parent " + std::to_string(p) + " is no bone"};
            }
            b = std::size_t(p);
        }
        for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
            const std::int32_t p = parents[*it];
            global[*it] = p < 0 ? rests[*it] : multiply(global[std::size_t(p)], rests[*it]);
            done[*it] = 1;
        }
    }
    binds.assign(n, {});
    for (std::size_t i = 0; i < n; ++i) {
        binds[i].bone = std::int32_t(i);
        if (!affine_inverse(global[i], binds[i].pose)) {
            return {ErrorCode::InvalidArgument, "bone " + std::to_string(i) + "'s rest cannot be inverted"};
        }
    }
    return {};
}

Outcome skin_palette(std::span<const Mat4> bone_poses, std::span<const SkinBind> binds,
                     std::vector<Mat4>& palette) {
    palette.resize(binds.size());
    for (std::size_t i = 0; i < binds.size(); ++i) {
        const std::int32_t bone = binds[i].bone;
        if (bone < 0 || std::size_t(bone) >= bone_poses.size()) {
            return {ErrorCode::InvalidArgument, "bind " + std::to_string(i) + " follows bone " +
                                                    std::to_string(bone) + ", not one of the skeleton's " +
                                                    std::to_string(bone_poses.size())};
        }
        palette[i] = multiply(bone_poses[std::size_t(bone)], binds[i].pose);
    }
    return {};
}

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
    if (config.cascades < 1 || config.cascades > 8) {
        return "cascades = " + std::to_string(config.cascades) + ": must be 1 to 8";
    }
    if (config.ratio != 2 && config.ratio != 4) {
        return "ratio = " + std::to_string(config.ratio) + ": must be 2 or 4";
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

Outcome WindHost::create(const WindHostConfig& config, const Hooks& hooks, const HostDevice* host,
                         std::uint32_t exported_copies, const std::uint8_t* device_uuid) {
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
    desc.domain.cascades = config.cascades;
    desc.domain.ratio = config.ratio;
    desc.wind = quality_settings(config.quality);
    desc.hooks = hooks;
    desc.host = host;
    desc.snapshot = true;
    desc.exported_copies = exported_copies;
    desc.device_uuid = device_uuid;
    if (Outcome o = System::create(desc, system_); !o) {
        return o;
    }
    config_ = config;
    steps_ = 0;
    return system_->set_ambient(config.ambient);
}

Outcome WindHost::export_wind_copy(std::uint32_t cascade, std::uint32_t slot, ExportedImage& out) {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no System"};
    }
    return system_->export_wind_copy(cascade, slot, out);
}

Outcome WindHost::copy_wind_textures(std::uint32_t slot) {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no System"};
    }
    return system_->copy_wind_textures(slot);
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
    meshes_[mesh_key] = {id, false, false};
    return {};
}

Outcome WindHost::add_skinned_mesh(std::uint64_t mesh_key, const SkinnedMeshData& data) {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no wind System (invalid properties)"};
    }
    if (data.joint_count < 1 || data.joint_count > kMaxJoints) {
        return {ErrorCode::InvalidArgument, "a skin of " + std::to_string(data.joint_count) +
                                                " joints: gust takes 1 to " + std::to_string(kMaxJoints)};
    }
    const std::size_t vertices = data.positions.size() / 3;
    if (data.joints.size() != 4 * vertices || data.weights.size() != 4 * vertices) {
        return {ErrorCode::InvalidArgument, "4 bone indices and 4 weights a vertex are needed (" +
                                                std::to_string(vertices) + " vertices, " +
                                                std::to_string(data.joints.size()) + " indices, " +
                                                std::to_string(data.weights.size()) + " weights)"};
    }
    std::vector<std::uint16_t> joints(data.joints.size());
    for (std::size_t i = 0; i < joints.size(); ++i) {
        const std::int32_t j = data.joints[i];
        // An unused influence may name any joint: Godot pads with bone 0 at weight 0.
        if (j < 0 || std::uint32_t(j) >= data.joint_count) {
            if (data.weights[i] != 0.0f) {
                return {ErrorCode::InvalidArgument, "vertex " + std::to_string(i / 4) + " has bone index " +
                                                        std::to_string(j) + ", the skin has " +
                                                        std::to_string(data.joint_count) + " binds"};
            }
            joints[i] = 0;
            continue;
        }
        joints[i] = std::uint16_t(j);
    }
    MeshSkin skin;
    skin.joint_count = data.joint_count;
    skin.joints = joints.data();
    skin.weights = data.weights.data();
    MeshDesc desc;
    desc.positions = data.positions.data();
    desc.vertex_count = std::uint32_t(vertices);
    desc.indices = data.indices.data();
    desc.index_count = std::uint32_t(data.indices.size());
    desc.deforming = true;
    desc.skin = &skin;
    MeshId id = 0;
    if (Outcome o = system_->create_mesh(desc, id); !o) {
        return o;
    }
    meshes_[mesh_key] = {id, true, false};
    return {};
}

Outcome WindHost::set_bones(std::uint64_t mesh_key, std::span<const Mat4> palette) {
    auto mesh = meshes_.find(mesh_key);
    if (!system_ || mesh == meshes_.end() || !mesh->second.skinned) {
        return {ErrorCode::InvalidHandle, "bones set before the skinned mesh was added"};
    }
    const bool first = !mesh->second.posed;
    if (Outcome o = system_->set_bones(mesh->second.id, palette.data(), std::uint32_t(palette.size()), first);
        !o) {
        return o;
    }
    mesh->second.posed = true;
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
        if (Outcome r = system_->create_instance(mesh->second.id, transform, false, o.instance); !r) {
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
    if (!o.moving && !mesh->second.skinned) {
        // A static instance that moves would re-voxelize the whole static set every frame and push no air:
        // from its first move on it is a moving instance, already in motion from its last transform.
        InstanceId moving = 0;
        if (Outcome r = system_->create_moving_instance(mesh->second.id, transform, o.transform, moving);
            !r) {
            return r;
        }
        system_->destroy_instance(o.instance);
        o.instance = moving;
        o.moving = true;
    } else if (Outcome r = system_->set_transform(o.instance, transform); !r) {
        return r;
    }
    o.moving = true;
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
        system_->destroy_mesh(it->second.id);
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

Outcome WindHost::set_focus(const Vec3& focus) {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no wind System (invalid properties)"};
    }
    if (focus.x == config_.focus.x && focus.y == config_.focus.y && focus.z == config_.focus.z) {
        return {};
    }
    config_.focus = focus;
    return system_->set_focus(focus);
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

Outcome WindHost::read_field(WindField& field, std::uint32_t cascade) const {
    if (!system_) {
        return {ErrorCode::InvalidHandle, "no wind System (invalid properties)"};
    }
    if (cascade >= config_.cascades) {
        return {ErrorCode::InvalidArgument, "cascade " + std::to_string(cascade) + ": the wind has " +
                                                std::to_string(config_.cascades) + " cascades"};
    }
    SnapshotInfo info;
    Vec3 probe{};
    Vec3 ignored{};
    if (Outcome o = system_->sample({&probe, 1}, {&ignored, 1}, info); !o) {
        return o;
    }
    const std::uint32_t nx = info.extent[0], ny = info.extent[1], nz = info.extent[2];
    // Cascade k shares the finest cascade's centre and cell count, its cells ratio^k as wide.
    const float cell = info.cell_size * std::pow(float(config_.ratio), float(cascade));
    const Vec3 origin{info.origin.x + 0.5f * float(nx) * (info.cell_size - cell),
                      info.origin.y + 0.5f * float(ny) * (info.cell_size - cell),
                      info.origin.z + 0.5f * float(nz) * (info.cell_size - cell)};
    std::vector<Vec3> points(std::size_t(nx) * ny * nz);
    std::vector<Vec3> velocities(points.size());
    std::size_t n = 0;
    for (std::uint32_t k = 0; k < nz; ++k) {
        for (std::uint32_t j = 0; j < ny; ++j) {
            for (std::uint32_t i = 0; i < nx; ++i) {
                points[n++] = {origin.x + (float(i) + 0.5f) * cell, origin.y + (float(j) + 0.5f) * cell,
                               origin.z + (float(k) + 0.5f) * cell};
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
    field.origin = origin;
    field.cell_size = cell;
    field.frame = info.frame;
    return {};
}

std::span<const WindTexture> WindHost::wind_textures() const {
    return system_ ? system_->wind_textures() : std::span<const WindTexture>();
}

std::string WindHost::device_name() const {
    return system_ ? system_->device_name() : "";
}

} // namespace gust::integration
