#include "voxelizer/skin_io.h"
#include "voxelizer/voxelize_io.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <glm/gtc/packing.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <limits>
#include <sstream>

namespace gust {

namespace {
#include "gust_shaders/skin_comp.h"
#include "gust_shaders/voxelize_frag.h"
#include "gust_shaders/voxelize_geom.h"
#include "gust_shaders/voxelize_large_comp.h"
#include "gust_shaders/voxelize_shift_comp.h"
#include "gust_shaders/voxelize_tri_comp.h"
#include "gust_shaders/voxelize_vert.h"

using shaderio::kMaxGroupsX;
using shaderio::kShiftGroupSize;
using shaderio::kShiftMaxGroups;
using shaderio::kShiftPerThread;
using shaderio::kSkinGroupSize;
using shaderio::kSkinMaxGroupsX;
using shaderio::kVoxelizeGroupSize;
using shaderio::ShiftPush;
using shaderio::SkinPush;
using shaderio::VoxelizeCounters;
using shaderio::VoxelizeInstance;
using shaderio::VoxelizePush;

// The raster path draws a grid res texels square into the Context's attachmentless framebuffer.
static_assert(kMaxRes <= gpu::Context::kMaxFramebufferExtent);

/// Headroom over the expected fragment count when sizing the list before a pass: the expectation is a
/// mean over sub-voxel offsets (faces on voxel planes touch 11% more), and a pass that overflows is
/// redone. The slack keeps small meshes clear of it too.
constexpr double kFragmentHeadroom = 1.15;
constexpr std::uint64_t kFragmentSlack = 4096;

/// Large-triangle work items allocated before the first pass (each is one tile of a large triangle).
constexpr std::uint64_t kInitialLargeItems = 4096;

/// The smallest voxel size relative to the grid's largest coordinate: 2^-40 keeps 12 bits below a voxel
/// in the doubles of an OpenVDB transform (which refuses a voxel its doubles cannot resolve).
constexpr double kSmallestRelativeVoxel = 0x1p-40;

template <std::size_t N> std::span<const std::uint32_t> words(const std::uint32_t (&a)[N]) {
    return {a, N};
}

std::uint64_t triangles_of(std::span<const GpuInstance> instances) {
    std::uint64_t triangles = 0;
    for (const GpuInstance& inst : instances)
        triangles += inst.mesh->triangle_count();
    return triangles;
}

glm::mat4 world_to_grid(const GridDesc& grid) {
    const float inv_h = 1.0f / grid.voxel_size;
    glm::mat4 m(inv_h);
    m[3] = glm::vec4(-grid.origin * inv_h, 1.0f);
    return m;
}

/// The last frame's model matrix as the shaders' velocity (model · p − prev · p) / dt should see it for a
/// rigid mesh. When the frame's change T = model · prev⁻¹ is rigid, the screw motion whose flow for one
/// frame is T: its twist ξ = (ω, v) (the logarithm of T; Murray, Li and Sastry 1994, ch. 2) gives the
/// velocity ω × q + v at the surface's place q now, and (I − ξ̂) · model makes the shaders compute it. A
/// chord (q − T⁻¹ q) / dt instead is 2 sin(θ/2) / θ as fast for a turn of θ, points θ/2 off, and converges
/// (divergence 2 (cos θ − 1) / dt): a body spinning 110° a frame drew air into itself at 140 m³/s per m³
/// and drove the air around it to 5 times its surface speed. A change that is not rigid (a scale or a
/// shear) keeps the chord.
glm::mat4 screw_prev_model(const glm::mat4& model, const glm::mat4& prev) {
    const glm::dmat4 t = glm::dmat4(model) * glm::inverse(glm::dmat4(prev));
    const glm::dmat3 r(t);
    const glm::dmat3 gram = glm::transpose(r) * r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (std::abs(gram[i][j] - (i == j ? 1.0 : 0.0)) > 1e-4) return prev;
    if (glm::determinant(r) <= 0.0) return prev;
    const double cos_angle = std::clamp((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0, -1.0, 1.0);
    const double angle = std::acos(cos_angle);
    // glm is column-major: r[column][row].
    const glm::dvec3 skew(r[1][2] - r[2][1], r[2][0] - r[0][2], r[0][1] - r[1][0]);
    glm::dvec3 axis(0.0);
    if (angle > 1e-9 && std::sin(angle) > 1e-3) {
        axis = skew / (2.0 * std::sin(angle));
    } else if (angle > 1e-9) {
        // Near a half turn, (R + I) / 2 is about axis · axisᵀ: its largest column, normalised.
        const glm::dmat3 b = 0.5 * (r + glm::dmat3(1.0));
        int k = 0;
        for (int i = 1; i < 3; ++i)
            if (b[i][i] > b[k][k]) k = i;
        axis = glm::normalize(b[k]);
        if (glm::dot(axis, skew) < 0.0) axis = -axis;
    }
    const glm::dvec3 omega = angle * axis;
    const glm::dmat3 k_hat(0.0, omega.z, -omega.y, -omega.z, 0.0, omega.x, omega.y, -omega.x, 0.0);
    // v = V⁻¹ t, V⁻¹ = I − K/2 + c K², c = (1 − θ sin θ / (2 (1 − cos θ))) / θ² (1/12 as θ → 0).
    const double c = angle > 1e-4
                         ? (1.0 - angle * std::sin(angle) / (2.0 * (1.0 - cos_angle))) / (angle * angle)
                         : 1.0 / 12.0;
    const glm::dvec3 v = (glm::dmat3(1.0) - 0.5 * k_hat + c * k_hat * k_hat) * glm::dvec3(t[3]);
    glm::dmat4 step(glm::dmat3(1.0) - k_hat);
    step[3] = glm::dvec4(-v, 1.0);
    return glm::mat4(step * glm::dmat4(model));
}

} // namespace

const char* to_string(VoxelizeMethod method) {
    switch (method) {
    case VoxelizeMethod::Raster:
        return "raster";
    case VoxelizeMethod::Compute:
        return "compute";
    case VoxelizeMethod::Auto:
        return "auto";
    }
    return "unknown";
}

bool parse_method(const std::string& text, VoxelizeMethod& out) {
    for (VoxelizeMethod m : {VoxelizeMethod::Raster, VoxelizeMethod::Compute, VoxelizeMethod::Auto})
        if (text == to_string(m)) {
            out = m;
            return true;
        }
    return false;
}

Status check_method(VoxelizeMethod method, const gpu::DeviceInfo& device) {
    if (method == VoxelizeMethod::Raster && !device.graphics_queue)
        return Status::failure("the raster voxelizer needs a queue with graphics, and gust runs on a "
                               "compute-only (async compute) queue of '" +
                               std::string(device.name) + "': voxelize with the compute or auto path");
    return {};
}

Status validate_grid(const GridDesc& grid) {
    if (grid.res < kMinRes || grid.res > kMaxRes)
        return Status::failure("grid resolution " + std::to_string(grid.res) + " is outside [" +
                               std::to_string(kMinRes) + ", " + std::to_string(kMaxRes) + "]");
    if (!std::isfinite(grid.voxel_size) || grid.voxel_size <= 0.0f)
        return Status::failure("voxel size must be finite and > 0, got " + std::to_string(grid.voxel_size));
    if (!std::isfinite(grid.origin.x) || !std::isfinite(grid.origin.y) || !std::isfinite(grid.origin.z))
        return Status::failure("grid origin must be finite");
    if (!std::isfinite(grid.voxel_size * float(grid.res)))
        return Status::failure("grid extent overflows a float");
    // The voxelizer subtracts the origin before it scales, so a far-off grid still voxelizes its float
    // vertices; only the output's world transform needs a voxel to stand out against the coordinates.
    const glm::dvec3 lo = glm::dvec3(grid.origin);
    const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(lo + double(grid.voxel_size) * double(grid.res)));
    const double farthest = std::max({far.x, far.y, far.z});
    if (double(grid.voxel_size) < farthest * kSmallestRelativeVoxel) {
        std::ostringstream text;
        text << "voxel size " << grid.voxel_size << " is below 2^-40 of the grid's largest coordinate ("
             << farthest << "), finer than a double transform places voxels: move the grid nearer the "
             << "origin or use larger voxels";
        return Status::failure(text.str());
    }
    return {};
}

GridDesc grid_around(glm::vec3 lo, glm::vec3 hi, std::uint32_t res) {
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) lo = hi = glm::vec3(0.0f);
    const glm::vec3 extent = hi - lo;
    float edge = std::max({extent.x, extent.y, extent.z});
    if (!(edge > 0.0f)) edge = 1.0f;
    GridDesc grid;
    grid.res = res;
    grid.voxel_size = edge / float(std::max<std::uint32_t>(res, 3) - 2);
    grid.origin = 0.5f * (lo + hi) - 0.5f * float(res) * grid.voxel_size;
    return grid;
}

std::pair<glm::vec3, glm::vec3> mesh_bounds(const MeshView& mesh) {
    glm::vec3 lo(std::numeric_limits<float>::max());
    glm::vec3 hi(std::numeric_limits<float>::lowest());
    for (std::size_t i = 0; i < mesh.index_count; ++i) {
        if (mesh.indices[i] >= mesh.vertex_count) continue;
        const glm::vec3 p = mesh.position(mesh.indices[i]);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    return {lo, hi};
}

Result<std::unique_ptr<Voxelizer>> Voxelizer::create(gpu::Context& ctx, const VoxelizerDesc& desc) {
    std::unique_ptr<Voxelizer> v(new (ctx.memory()) Voxelizer(ctx));
    // Index 1 of each pass writes velocities; index 0 compiles them out (kVelocities).
    for (std::uint32_t with_velocity = 0; with_velocity < 2; ++with_velocity) {
        const std::uint32_t constants[] = {with_velocity};
        gpu::GraphicsPipelineDesc raster;
        raster.vertex = words(voxelize_vert);
        raster.geometry = words(voxelize_geom);
        raster.fragment = words(voxelize_frag);
        raster.push_constant_bytes = sizeof(VoxelizePush);
        raster.constants = constants;
        auto r = gpu::Pipeline::graphics(ctx, "gust voxelize_raster", raster);
        if (!r) return r.status();
        v->raster_[with_velocity] = std::move(*r);
        auto small = gpu::Pipeline::compute(ctx, "gust voxelize_tri", words(voxelize_tri_comp),
                                            sizeof(VoxelizePush), constants);
        if (!small) return small.status();
        v->compute_small_[with_velocity] = std::move(*small);
        auto large = gpu::Pipeline::compute(ctx, "gust voxelize_large", words(voxelize_large_comp),
                                            sizeof(VoxelizePush), constants);
        if (!large) return large.status();
        v->compute_large_[with_velocity] = std::move(*large);
    }
    auto shift =
        gpu::Pipeline::compute(ctx, "gust voxelize_shift", words(voxelize_shift_comp), sizeof(ShiftPush));
    if (!shift) return shift.status();
    v->shift_ = std::move(*shift);
    auto source_count = gpu::Buffer::create(ctx, sizeof(std::uint32_t), gpu::MemoryUse::Device, 0,
                                            "gust voxelizer slab source count");
    if (!source_count) return source_count.status();
    v->source_count_ = std::move(*source_count);
    auto skin = gpu::Pipeline::compute(ctx, "gust skin", words(skin_comp), sizeof(SkinPush));
    if (!skin) return skin.status();
    v->skin_ = std::move(*skin);
    auto profiler = gpu::Profiler::create(ctx);
    if (!profiler) return profiler.status();
    v->profiler_ = std::move(*profiler);
    auto skin_profiler = gpu::Profiler::create(ctx, 1);
    if (!skin_profiler) return skin_profiler.status();
    v->skin_profiler_ = std::move(*skin_profiler);
    auto counters = gpu::Buffer::create(ctx, sizeof(VoxelizeCounters), gpu::MemoryUse::Readback,
                                        VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, "gust voxelizer counters");
    if (!counters) return counters.status();
    v->counters_ = std::move(*counters);
    if (Status s = v->ensure_large_list(kInitialLargeItems); !s) return s;
    if (Status s = v->ensure_capacity(std::max<std::uint32_t>(desc.initial_capacity, 1)); !s) return s;
    return v;
}

std::uint64_t Voxelizer::fragment_limit() const {
    // Moving meshes keep a velocity (8 bytes) per fragment beside it, in one allocation too.
    const std::size_t entry_bytes = inv_dt_ > 0.0f ? sizeof(glm::uvec2) : sizeof(std::uint32_t);
    return std::min<std::uint64_t>(ctx_.info().max_allocation_size / entry_bytes, UINT32_MAX);
}

Status Voxelizer::ensure_capacity(std::uint64_t fragments) {
    if (fragments <= capacity_) return {};
    const std::uint64_t limit = fragment_limit();
    if (fragments > limit)
        return Status::failure("the fragment list needs " + std::to_string(fragments) +
                               " entries, more than one device allocation holds (" + std::to_string(limit) +
                               "); lower the resolution or split the scene");
    auto buffer = gpu::Buffer::create(ctx_, fragments * sizeof(std::uint32_t), gpu::MemoryUse::Device, 0,
                                      "gust voxelizer fragments");
    if (!buffer) return buffer.status();
    fragments_ = std::move(*buffer);
    capacity_ = fragments;
    return {};
}

Status Voxelizer::ensure_velocity_capacity() {
    if (velocities_ && velocities_.size() >= capacity_ * sizeof(glm::uvec2)) return {};
    auto buffer = gpu::Buffer::create(ctx_, capacity_ * sizeof(glm::uvec2), gpu::MemoryUse::Device, 0,
                                      "gust voxelizer velocities");
    if (!buffer) return buffer.status();
    velocities_ = std::move(*buffer);
    return {};
}

Status Voxelizer::ensure_instances(std::size_t count) {
    const VkDeviceSize bytes = std::max<std::size_t>(count, 1) * sizeof(VoxelizeInstance);
    if (instances_ && instances_.size() >= bytes) return {};
    auto buffer = gpu::Buffer::create(ctx_, bytes, gpu::MemoryUse::Device, 0, "gust voxelizer instances");
    if (!buffer) return buffer.status();
    instances_ = std::move(*buffer);
    return {};
}

Status Voxelizer::rotate_positions(GpuMesh& mesh) {
    if (!mesh.prev_positions_) {
        auto buffer = gpu::Buffer::create(ctx_, mesh.positions_.size(), gpu::MemoryUse::Device, 0,
                                          "gust voxelizer previous positions");
        if (!buffer) return buffer.status();
        mesh.prev_positions_ = std::move(*buffer);
    }
    // Last frame's positions become the previous ones; the older buffer takes this frame's.
    std::swap(mesh.positions_, mesh.prev_positions_);
    return {};
}

Status Voxelizer::update_positions(GpuMesh& mesh, std::span<const glm::vec3> positions) {
    if (positions.size() != mesh.vertices_)
        return Status::failure("got " + std::to_string(positions.size()) + " positions for a mesh of " +
                               std::to_string(mesh.vertices_) + " vertices");
    if (mesh.triangles_ == 0) return {};
    if (!ctx_.deferred()) {
        // A pose waiting for the skinning pass was made way for already: this one replaces it.
        if (mesh.staged_palette_.empty())
            if (Status s = rotate_positions(mesh); !s) return s;
        mesh.staged_palette_.clear();
        return gpu::upload(ctx_, mesh.positions_, positions.data(), positions.size_bytes());
    }
    // A second pose before the next frame replaces the first: last frame's stay the previous ones.
    if (!mesh.staged())
        if (Status s = rotate_positions(mesh); !s) return s;
    mesh.staged_.assign(positions.begin(), positions.end());
    mesh.staged_source_ = VK_NULL_HANDLE;
    mesh.staged_palette_.clear();
    return {};
}

Status Voxelizer::copy_positions(GpuMesh& mesh, VkBuffer source, VkDeviceSize offset) {
    if (source == VK_NULL_HANDLE) return Status::failure("the source buffer is null");
    if (mesh.triangles_ == 0) return {};
    if (!ctx_.deferred()) {
        if (mesh.staged_palette_.empty())
            if (Status s = rotate_positions(mesh); !s) return s;
        mesh.staged_palette_.clear();
        return ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
            const VkBufferCopy region{offset, 0, mesh.positions_.size()};
            ctx_.vk().vkCmdCopyBuffer(cmd, source, mesh.positions_.handle(), 1, &region);
        });
    }
    if (!mesh.staged())
        if (Status s = rotate_positions(mesh); !s) return s;
    mesh.staged_.clear();
    mesh.staged_source_ = source;
    mesh.staged_offset_ = offset;
    mesh.staged_palette_.clear();
    return {};
}

Status Voxelizer::pose_from_bones(GpuMesh& mesh, std::span<const glm::mat4> palette) {
    if (mesh.joints_ == 0) return Status::failure("the mesh has no skin");
    if (palette.size() != mesh.joints_)
        return Status::failure("got " + std::to_string(palette.size()) + " bone matrices for a skin of " +
                               std::to_string(mesh.joints_) + " joints");
    if (mesh.triangles_ == 0) return {};
    // Whether or not frames are in flight, the pose is written by the next recorded skinning pass; a
    // second pose before it replaces the first, and last frame's positions stay the previous ones.
    if (!mesh.staged())
        if (Status s = rotate_positions(mesh); !s) return s;
    mesh.staged_.clear();
    mesh.staged_source_ = VK_NULL_HANDLE;
    mesh.staged_palette_.assign(palette.begin(), palette.end());
    return {};
}

void Voxelizer::record_skinning(VkCommandBuffer cmd, std::span<const GpuInstance> instances) {
    bool any = false;
    for (const GpuInstance& inst : instances) {
        const GpuMesh& mesh = *inst.mesh;
        if (mesh.staged_palette_.empty()) continue;
        gpu::update(ctx_, cmd, mesh.palette_, mesh.staged_palette_.data(),
                    mesh.staged_palette_.size() * sizeof(glm::mat4));
        any = true;
    }
    if (!any) return;
    gpu::barrier(ctx_, cmd);
    skin_profiler_.reset(cmd);
    skin_profiler_.begin(cmd, "skin");
    for (const GpuInstance& inst : instances) {
        const GpuMesh& mesh = *inst.mesh;
        // A mesh placed by several instances is posed once.
        if (mesh.staged_palette_.empty()) continue;
        mesh.staged_palette_.clear();
        SkinPush push{};
        push.bind = mesh.bind_.address();
        push.joints = mesh.joint_indices_.address();
        push.weights = mesh.weights_.address();
        push.palette = mesh.palette_.address();
        push.positions = mesh.positions_.address();
        push.vertex_count = mesh.vertices_;
        const std::uint32_t groups = (mesh.vertices_ + kSkinGroupSize - 1) / kSkinGroupSize;
        skin_.bind(cmd, &push, sizeof(push));
        skin_.dispatch(cmd, std::min(groups, kSkinMaxGroupsX),
                       (groups + kSkinMaxGroupsX - 1) / kSkinMaxGroupsX, 1);
    }
    skin_profiler_.end(cmd);
    gpu::barrier(ctx_, cmd);
}

Status Voxelizer::ensure_large_list(std::uint64_t items) {
    if (items <= large_capacity_) return {};
    if (items > UINT32_MAX || items * sizeof(glm::uvec3) > ctx_.info().max_allocation_size)
        return Status::failure("the large-triangle queue needs " + std::to_string(items) +
                               " items, more than one device allocation holds");
    auto buffer = gpu::Buffer::create(ctx_, items * sizeof(glm::uvec3), gpu::MemoryUse::Device, 0,
                                      "gust voxelizer large triangles");
    if (!buffer) return buffer.status();
    large_list_ = std::move(*buffer);
    large_capacity_ = items;
    return {};
}

namespace {
/// Checks a skin for `vertices` vertices: joint_count in range, indices below it, weights finite, >= 0 and
/// not all 0 a vertex (such a vertex would collapse to the mesh's origin).
Status check_skin(const SkinView& skin, std::size_t vertices) {
    if (skin.joint_count == 0 || skin.joint_count > kMaxSkinJoints)
        return Status::failure("skin joint count " + std::to_string(skin.joint_count) + " is not in 1.." +
                               std::to_string(kMaxSkinJoints));
    if (vertices > 0 && (!skin.joints || !skin.weights))
        return Status::failure("skin joints or weights is null");
    for (std::size_t v = 0; v < vertices; ++v) {
        float sum = 0.0f;
        for (std::size_t i = 4 * v; i < 4 * v + 4; ++i) {
            if (skin.joints[i] >= skin.joint_count)
                return Status::failure("skin vertex " + std::to_string(v) + ": joint " +
                                       std::to_string(skin.joints[i]) + " out of range (" +
                                       std::to_string(skin.joint_count) + " joints)");
            if (!std::isfinite(skin.weights[i]) || skin.weights[i] < 0.0f)
                return Status::failure("skin vertex " + std::to_string(v) + ": weight " +
                                       std::to_string(skin.weights[i]) + " is not finite and >= 0");
            sum += skin.weights[i];
        }
        if (!(sum > 0.0f)) return Status::failure("skin vertex " + std::to_string(v) + ": all weights are 0");
    }
    return {};
}
} // namespace

Status Voxelizer::upload_skin(GpuMesh& mesh, const MeshView& view, const SkinView& skin) {
    const std::size_t vertices = view.vertex_count;
    struct Part {
        gpu::Buffer& buffer;
        std::size_t bytes;
        const void* data;
        const char* name;
    };
    std::pmr::vector<float> bind(3 * vertices, ctx_.memory());
    for (std::size_t v = 0; v < vertices; ++v) {
        const glm::vec3 p = view.position(v);
        std::memcpy(&bind[3 * v], &p, sizeof(p));
    }
    // Four uint16 a vertex are the two words (low half first) the shader reads on a little-endian host.
    const Part parts[] = {
        {mesh.bind_, bind.size() * sizeof(float), bind.data(), "gust voxelizer skin bind pose"},
        {mesh.joint_indices_, vertices * 4 * sizeof(std::uint16_t), skin.joints,
         "gust voxelizer skin joints"},
        {mesh.weights_, vertices * 4 * sizeof(float), skin.weights, "gust voxelizer skin weights"},
        {mesh.palette_, std::size_t(skin.joint_count) * sizeof(glm::mat4), nullptr,
         "gust voxelizer skin palette"},
    };
    for (const Part& part : parts) {
        auto buffer = gpu::Buffer::create(ctx_, part.bytes, gpu::MemoryUse::Device, 0, part.name);
        if (!buffer) return buffer.status();
        if (part.data)
            if (Status s = gpu::upload(ctx_, *buffer, part.data, part.bytes); !s) return s;
        part.buffer = std::move(*buffer);
    }
    mesh.joints_ = skin.joint_count;
    return {};
}

Result<GpuMesh> Voxelizer::upload(const MeshView& mesh, const SkinView* skin) {
    if (mesh.index_count % 3 != 0)
        return Result<GpuMesh>::failure("index count " + std::to_string(mesh.index_count) +
                                        " is not a multiple of 3");
    if (mesh.index_count && (!mesh.indices || !mesh.positions))
        return Result<GpuMesh>::failure("mesh has indices but a null index or position pointer");
    if (mesh.position_stride < 3 * sizeof(float))
        return Result<GpuMesh>::failure("position stride " + std::to_string(mesh.position_stride) +
                                        " is below 12 bytes");
    if (mesh.vertex_count > UINT32_MAX || mesh.index_count / 3 > UINT32_MAX / 3)
        return Result<GpuMesh>::failure("mesh is too large (more than 2^32 vertices or indices)");
    for (std::size_t i = 0; i < mesh.index_count; ++i)
        if (mesh.indices[i] >= mesh.vertex_count)
            return Result<GpuMesh>::failure("index " + std::to_string(mesh.indices[i]) + " at position " +
                                            std::to_string(i) + " is out of range (" +
                                            std::to_string(mesh.vertex_count) + " vertices)");
    if (skin)
        if (Status s = check_skin(*skin, mesh.vertex_count); !s) return s;
    GpuMesh out(ctx_.memory());
    out.triangles_ = std::uint32_t(mesh.index_count / 3);
    out.vertices_ = std::uint32_t(mesh.vertex_count);
    if (skin) out.joints_ = skin->joint_count;
    if (out.triangles_ == 0) return out;
    if (skin)
        if (Status s = upload_skin(out, mesh, *skin); !s) return s;
    out.sizes_ = measure_mesh(mesh);

    std::pmr::vector<float> packed(3 * mesh.vertex_count, ctx_.memory());
    for (std::size_t v = 0; v < mesh.vertex_count; ++v) {
        const glm::vec3 p = mesh.position(v);
        std::memcpy(&packed[3 * v], &p, sizeof(p));
    }
    auto positions = gpu::Buffer::create(ctx_, packed.size() * sizeof(float), gpu::MemoryUse::Device, 0,
                                         "gust voxelizer mesh positions");
    if (!positions) return positions.status();
    if (Status s = gpu::upload(ctx_, *positions, packed.data(), packed.size() * sizeof(float)); !s) return s;
    auto indices = gpu::Buffer::create(ctx_, mesh.index_count * sizeof(std::uint32_t), gpu::MemoryUse::Device,
                                       0, "gust voxelizer mesh indices");
    if (!indices) return indices.status();
    if (Status s = gpu::upload(ctx_, *indices, mesh.indices, mesh.index_count * sizeof(std::uint32_t)); !s)
        return s;
    out.positions_ = std::move(*positions);
    out.indices_ = std::move(*indices);
    return out;
}

Result<std::pmr::vector<VoxelizeMethod>> Voxelizer::prepare(std::span<const GpuInstance> instances,
                                                            const GridDesc& grid, VoxelizeMethod method,
                                                            float dt) {
    using Methods = Result<std::pmr::vector<VoxelizeMethod>>;
    if (Status s = validate_grid(grid); !s) return s;
    if (!std::isfinite(dt) || dt < 0.0f)
        return Methods::failure("frame time must be finite and >= 0, got " + std::to_string(dt));
    inv_dt_ = dt > 0.0f ? 1.0f / dt : 0.0f;
    for (const GpuInstance& inst : instances)
        if (!inst.mesh) return Methods::failure("an instance has no mesh");
    if (Status s = check_method(method, ctx_.info()); !s) return s;
    std::pmr::vector<VoxelizeMethod> methods(ctx_.memory());
    methods.reserve(instances.size());
    const CostModel& model = cost_model(ctx_.info());
    for (const GpuInstance& inst : instances) {
        if (method != VoxelizeMethod::Auto) {
            methods.push_back(method);
            continue;
        }
        methods.push_back(ctx_.info().graphics_queue &&
                                  model.picks_raster(voxelize_work(inst.mesh->sizes_, inst.model, grid))
                              ? VoxelizeMethod::Raster
                              : VoxelizeMethod::Compute);
    }
    return methods;
}

Result<VoxelizeStats> Voxelizer::voxelize(std::span<const GpuInstance> instances, const GridDesc& grid,
                                          VoxelizeMethod method, float dt) {
    auto methods = prepare(instances, grid, method, dt);
    if (!methods) return methods.status();
    auto stats = run(instances, *methods, grid);
    if (stats && !methods->empty()) stats->method = methods->back();
    return stats;
}

Status Voxelizer::record(VkCommandBuffer cmd, std::span<const GpuInstance> instances, const GridDesc& grid,
                         VoxelizeMethod method, float dt) {
    auto methods = prepare(instances, grid, method, dt);
    if (!methods) return methods.status();
    if (Status s = ensure_pass(instances, grid); !s) return s;
    record_pass(cmd, instances, *methods, grid);
    method_ = methods->empty() ? method_ : methods->back();
    return {};
}

Status Voxelizer::ensure_slab_pass(std::span<const GpuInstance> instances, const GridDesc& grid) {
    std::swap(fragments_, spare_);
    std::swap(capacity_, spare_capacity_);
    Status s = ensure_pass(instances, grid);
    // At least the source's slots, which a full pass needed (it grew them when it overflowed).
    if (s) s = ensure_capacity(spare_capacity_);
    if (!s) {
        std::swap(fragments_, spare_);
        std::swap(capacity_, spare_capacity_);
    }
    return s;
}

Result<VoxelizeStats> Voxelizer::voxelize_slabs(std::span<const GpuInstance> instances, const GridDesc& grid,
                                                VoxelizeMethod method, glm::ivec3 shift) {
    auto methods = prepare(instances, grid, method, 0.0f);
    if (!methods) return methods.status();
    if (Status s = ensure_slab_pass(instances, grid); !s) return s;
    VoxelizeStats stats(ctx_.memory());
    stats.triangles = triangles_of(instances);
    if (Status s = submit_pass(instances, *methods, grid, &shift, stats); !s) return s;
    if (!methods->empty()) stats.method = methods->back();
    return stats;
}

Status Voxelizer::record_slabs(VkCommandBuffer cmd, std::span<const GpuInstance> instances,
                               const GridDesc& grid, VoxelizeMethod method, glm::ivec3 shift) {
    auto methods = prepare(instances, grid, method, 0.0f);
    if (!methods) return methods.status();
    if (Status s = ensure_slab_pass(instances, grid); !s) return s;
    record_pass(cmd, instances, *methods, grid, &shift);
    method_ = methods->empty() ? method_ : methods->back();
    return {};
}

namespace {
/// What record_readback() writes: the counters, then the capacities the pass ran with.
struct Readback {
    VoxelizeCounters counters;
    std::uint32_t capacity;
    std::uint32_t large_capacity;
};
} // namespace

std::size_t Voxelizer::readback_bytes() {
    return sizeof(Readback);
}

void Voxelizer::record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const {
    static_assert(offsetof(Readback, capacity) == sizeof(VoxelizeCounters));
    const std::uint32_t capacities[2] = {std::uint32_t(capacity_), std::uint32_t(large_capacity_)};
    gpu::record_readback(ctx_, cmd, counters_, sizeof(VoxelizeCounters), dst, offset, capacities);
}

gpu::Timings Voxelizer::timings(std::uint64_t frame) const {
    gpu::Timings out = skin_profiler_.read_frame(frame);
    for (const auto& pass : profiler_.read_frame(frame))
        out.push_back(pass);
    return out;
}

Result<VoxelizeStats> Voxelizer::collect(const void* readback) {
    Readback r;
    std::memcpy(&r, readback, sizeof(r));
    VoxelizeStats stats(ctx_.memory());
    stats.method = method_;
    if (Status s = take_counters(r.counters, r.capacity, r.large_capacity, stats); !s) return s;
    return stats;
}

Status Voxelizer::take_counters(const VoxelizeCounters& counters, std::uint64_t capacity,
                                std::uint64_t large_capacity, VoxelizeStats& stats) {
    stats.rejected = counters.rejected;
    stats.fragments = counters.fragments;
    if (counters.wrapped)
        return Status::failure("the fragment list would pass 2^32 entries (too many "
                               "voxels per triangle at this resolution); "
                               "lower the resolution or split the scene");
    stats.truncated = counters.fragments > capacity || counters.large_items > large_capacity;
    // Grow with headroom so that a scene growing slowly does not redo every frame.
    if (counters.fragments > capacity_) {
        const std::uint64_t needed = counters.fragments;
        if (Status s = ensure_capacity(std::max(needed, std::min(needed + needed / 4, fragment_limit()))); !s)
            return s;
    }
    if (counters.large_items > large_capacity_)
        if (Status s = ensure_large_list(std::uint64_t(counters.large_items) + counters.large_items / 4); !s)
            return s;
    fragment_count_ = std::min<std::uint64_t>(counters.fragments, capacity);
    stats.capacity = capacity_;
    return {};
}

Status Voxelizer::ensure_pass(std::span<const GpuInstance> instances, const GridDesc& grid) {
    // A first guess from the triangles' sizes so that a pass rarely overflows (a redone pass costs as
    // much as the first); one that does still grows the list and is redone.
    VoxelizeWork work;
    for (const GpuInstance& inst : instances)
        work += voxelize_work(inst.mesh->sizes_, inst.model, grid);
    const double limit = double(fragment_limit());
    const double guess = std::min(limit, kFragmentHeadroom * work.fragments + double(kFragmentSlack));
    if (Status s = ensure_capacity(std::uint64_t(guess)); !s) return s;
    if (inv_dt_ > 0.0f)
        if (Status s = ensure_velocity_capacity(); !s) return s;
    return ensure_instances(instances.size());
}

Result<VoxelizeStats> Voxelizer::run(std::span<const GpuInstance> instances,
                                     std::span<const VoxelizeMethod> methods, const GridDesc& grid) {
    VoxelizeStats stats(ctx_.memory());
    stats.triangles = triangles_of(instances);
    for (;;) {
        if (Status s = ensure_pass(instances, grid); !s) return s;
        if (Status s = submit_pass(instances, methods, grid, nullptr, stats); !s) return s;
        if (!stats.truncated) break;
        stats.truncated = false;
        ++stats.retries;
    }
    return stats;
}

Status Voxelizer::submit_pass(std::span<const GpuInstance> instances, std::span<const VoxelizeMethod> methods,
                              const GridDesc& grid, const glm::ivec3* slabs, VoxelizeStats& stats) {
    const std::uint64_t capacity = capacity_, large_capacity = large_capacity_;
    bool skinned = false;
    for (const GpuInstance& inst : instances)
        skinned = skinned || !inst.mesh->staged_palette_.empty();
    Status recorded = ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
        record_skinning(cmd, instances);
        record_pass(cmd, instances, methods, grid, slabs);
    });
    if (!recorded) return recorded;
    VoxelizeCounters counters{};
    if (Status s = gpu::download(ctx_, counters_, &counters, sizeof(counters)); !s) return s;
    stats.ms = skinned ? skin_profiler_.read() : gpu::Timings(ctx_.memory());
    for (const auto& pass : profiler_.read())
        stats.ms.push_back(pass);
    return take_counters(counters, capacity, large_capacity, stats);
}

void Voxelizer::record_pass(VkCommandBuffer cmd, std::span<const GpuInstance> instances,
                            std::span<const VoxelizeMethod> methods, const GridDesc& grid,
                            const glm::ivec3* slabs) {
    const glm::mat4 to_grid = world_to_grid(grid);
    const auto& vk = ctx_.vk();
    std::pmr::vector<VoxelizeInstance> records(instances.size(), ctx_.memory());
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const GpuInstance& inst = instances[i];
        const GpuMesh& mesh = *inst.mesh;
        VoxelizeInstance& r = records[i];
        r.to_grid = to_grid * inst.model;
        r.model = inst.model;
        r.positions = mesh.positions_ ? mesh.positions_.address() : 0;
        r.prev_positions = mesh.prev_positions_ ? mesh.prev_positions_.address() : r.positions;
        r.prev_model = inst.prev_model.value_or(inst.model);
        if (inst.prev_model && r.prev_positions == r.positions)
            r.prev_model = screw_prev_model(inst.model, *inst.prev_model);
        r.indices = mesh.indices_ ? mesh.indices_.address() : 0;
        r.triangle_count = mesh.triangles_;
        r.inv_dt = inst.teleport ? 0.0f : inv_dt_;
    }
    const std::size_t with_velocity = inv_dt_ > 0.0f ? 1 : 0;
    VoxelizePush push{};
    push.velocities = with_velocity ? velocities_.address() : 0;
    push.fragments = fragments_.address();
    push.counters = counters_.address();
    push.large_list = large_list_.address();
    push.large_capacity = std::uint32_t(large_capacity_);
    push.res = grid.res;
    for (int a = 0; a < 3; ++a)
        push.keep[a] = grid.keep[a] == 0 ? grid.res : std::min(grid.keep[a], grid.res);
    push.capacity = std::uint32_t(capacity_);
    if (slabs) {
        push.slabs = 1;
        push.slab_shift = *slabs;
    }

    profiler_.reset(cmd);
    for (const GpuInstance& inst : instances) {
        const GpuMesh& mesh = *inst.mesh;
        if (!mesh.staged_.empty()) {
            gpu::update(ctx_, cmd, mesh.positions_, mesh.staged_.data(),
                        mesh.staged_.size() * sizeof(glm::vec3));
        } else if (mesh.staged_source_) {
            const VkBufferCopy region{mesh.staged_offset_, 0, mesh.positions_.size()};
            vk.vkCmdCopyBuffer(cmd, mesh.staged_source_, mesh.positions_.handle(), 1, &region);
        }
        mesh.staged_.clear();
        mesh.staged_source_ = VK_NULL_HANDLE;
    }
    if (!records.empty())
        gpu::update(ctx_, cmd, instances_, records.data(), records.size() * sizeof(VoxelizeInstance));
    if (slabs) {
        // The last pass's count, before the counters are zeroed for this one.
        gpu::barrier(ctx_, cmd);
        const VkBufferCopy region{0, 0, sizeof(std::uint32_t)};
        vk.vkCmdCopyBuffer(cmd, counters_.handle(), source_count_.handle(), 1, &region);
        gpu::barrier(ctx_, cmd);
    }
    vk.vkCmdFillBuffer(cmd, counters_.handle(), 0, VK_WHOLE_SIZE, 0);
    gpu::barrier(ctx_, cmd);
    if (slabs) {
        profiler_.begin(cmd, "shift");
        ShiftPush shift{};
        shift.source = spare_.address();
        shift.source_count = source_count_.address();
        shift.fragments = fragments_.address();
        shift.counters = counters_.address();
        shift.source_capacity = std::uint32_t(spare_capacity_);
        shift.capacity = std::uint32_t(capacity_);
        shift.shift = *slabs;
        shift.keep = push.keep;
        // Workgroups for the source's count as last read back (it is still fragment_count_), at most
        // kShiftMaxGroups: the shader strides over whatever the count is on the GPU.
        const std::uint64_t block = kShiftGroupSize * kShiftPerThread;
        const std::uint64_t groups = (fragment_count_ + block - 1) / block;
        shift_.bind(cmd, &shift, sizeof(shift));
        shift_.dispatch(cmd, std::uint32_t(std::clamp<std::uint64_t>(groups, 1, kShiftMaxGroups)));
        gpu::barrier(ctx_, cmd);
        profiler_.end(cmd);
    }
    const bool any_raster =
        std::find(methods.begin(), methods.end(), VoxelizeMethod::Raster) != methods.end();
    if (any_raster) {
        profiler_.begin(cmd, "raster");
        VkRenderPassBeginInfo rendering{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
        rendering.renderPass = ctx_.attachmentless_pass();
        rendering.framebuffer = ctx_.attachmentless_framebuffer();
        rendering.renderArea = {{0, 0}, {grid.res, grid.res}};
        vk.vkCmdBeginRenderPass(cmd, &rendering, VK_SUBPASS_CONTENTS_INLINE);
        const VkViewport viewport{0.0f, 0.0f, float(grid.res), float(grid.res), 0.0f, 1.0f};
        const VkRect2D scissor{{0, 0}, {grid.res, grid.res}};
        vk.vkCmdSetViewport(cmd, 0, 1, &viewport);
        vk.vkCmdSetScissor(cmd, 0, 1, &scissor);
        for (std::size_t i = 0; i < instances.size(); ++i) {
            const GpuMesh& mesh = *instances[i].mesh;
            if (methods[i] != VoxelizeMethod::Raster || mesh.triangles_ == 0) continue;
            push.instance = instances_.address() + i * sizeof(VoxelizeInstance);
            push.triangle_count = mesh.triangles_;
            raster_[with_velocity].bind(cmd, &push, sizeof(push));
            raster_[with_velocity].draw(cmd, 3 * mesh.triangles_);
        }
        vk.vkCmdEndRenderPass(cmd);
        profiler_.end(cmd);
    }
    // The compute path in two stages whatever the instance count: every compute instance's small triangles
    // back to back with no barrier between them (they only append, to the fragments and to one queue of
    // large items that carry their instance), the last workgroup of all sizing the large pass; then one
    // large pass over every instance's items. (One instance after another had cost three stages each.)
    const std::uint32_t per_dispatch = kMaxGroupsX * kVoxelizeGroupSize;
    auto groups_for = [](std::uint32_t triangles) {
        return (triangles + kVoxelizeGroupSize - 1) / kVoxelizeGroupSize;
    };
    push.groups_total = 0;
    for (std::size_t i = 0; i < instances.size(); ++i)
        if (methods[i] == VoxelizeMethod::Compute)
            for (std::uint32_t first = 0; first < instances[i].mesh->triangles_; first += per_dispatch)
                push.groups_total +=
                    groups_for(std::min(per_dispatch, instances[i].mesh->triangles_ - first));
    if (push.groups_total == 0) return;
    profiler_.begin(cmd, "compute");
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const GpuMesh& mesh = *instances[i].mesh;
        if (methods[i] != VoxelizeMethod::Compute) continue;
        push.instance = instances_.address() + i * sizeof(VoxelizeInstance);
        push.instance_index = std::uint32_t(i);
        for (std::uint32_t first = 0; first < mesh.triangles_; first += per_dispatch) {
            push.first_triangle = first;
            push.triangle_count = std::min(per_dispatch, mesh.triangles_ - first);
            compute_small_[with_velocity].bind(cmd, &push, sizeof(push));
            compute_small_[with_velocity].dispatch(cmd, groups_for(push.triangle_count), 1, 1);
        }
    }
    gpu::barrier(ctx_, cmd);
    push.instance = instances_.address();
    compute_large_[with_velocity].bind(cmd, &push, sizeof(push));
    compute_large_[with_velocity].dispatch_indirect(cmd, counters_.handle(),
                                                    offsetof(VoxelizeCounters, large_dispatch));
    gpu::barrier(ctx_, cmd);
    profiler_.end(cmd);
}

Result<std::vector<std::uint32_t>> Voxelizer::read_fragments() const {
    std::vector<std::uint32_t> out(fragment_count_);
    if (Status s = gpu::download(ctx_, fragments_, out.data(), out.size() * sizeof(std::uint32_t)); !s)
        return s;
    return out;
}

Result<std::vector<glm::vec3>> Voxelizer::read_velocities() const {
    if (inv_dt_ <= 0.0f)
        return Result<std::vector<glm::vec3>>::failure("the last call was made without a frame time");
    std::vector<glm::uvec2> packed(fragment_count_);
    if (Status s = gpu::download(ctx_, velocities_, packed.data(), packed.size() * sizeof(glm::uvec2)); !s)
        return s;
    std::vector<glm::vec3> out(packed.size());
    for (std::size_t i = 0; i < packed.size(); ++i) {
        const glm::vec2 xy = glm::unpackHalf2x16(packed[i].x);
        out[i] = glm::vec3(xy, glm::unpackHalf2x16(packed[i].y).x);
    }
    return out;
}

} // namespace gust
