// System's scene calls: meshes, instances, emitters, the ambient wind and the focus (include/gust/gust.hpp).
#include "system_impl.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <optional>
#include <string>

namespace gust {

using namespace detail;

namespace {
bool finite(const Mat4& m) {
    for (float f : m.m)
        if (!std::isfinite(f)) return false;
    return true;
}
/// Finite and affine: the last row is (0, 0, 0, 1). A projective matrix would voxelize a distorted mesh.
Outcome check_transform(const Mat4& m, const char* name) {
    if (!finite(m)) return invalid(std::string(name) + " must be finite");
    if (m.m[3] != 0.0f || m.m[7] != 0.0f || m.m[11] != 0.0f || m.m[15] != 1.0f)
        return invalid(std::string(name) +
                       " must be affine: its last row (m[3], m[7], m[11], m[15]) must be 0, "
                       "0, 0, 1");
    return {};
}
} // namespace

Outcome System::create_mesh(const MeshDesc& desc, MeshId& id) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("create_mesh");
    id = 0;
    if (desc.vertex_count > 0 && !desc.positions) return invalid("positions is null");
    if (desc.index_count > 0 && !desc.indices) return invalid("indices is null");
    if (desc.stride < 12)
        return invalid("stride must be at least 12 bytes, got " + std::to_string(desc.stride));
    if (desc.skin && !desc.deforming) return invalid("a skin needs a deforming mesh (MeshDesc::deforming)");
    const MeshView view{desc.positions, desc.vertex_count, desc.stride, desc.indices, desc.index_count};
    for (std::uint32_t v = 0; v < desc.vertex_count; ++v) {
        const glm::vec3 p = view.position(v);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return invalid("vertex " + std::to_string(v) + " is not finite");
    }
    std::optional<SkinView> skin;
    if (desc.skin) skin = SkinView{desc.skin->joints, desc.skin->weights, desc.skin->joint_count};
    return guarded([&]() -> Outcome {
        auto mesh = impl_->world->upload(view, skin ? &*skin : nullptr);
        if (!mesh) return invalid(mesh.message());
        const MeshId next = impl_->next_id++;
        impl_->meshes.emplace(next, Impl::Mesh{std::move(*mesh), desc.deforming, 0});
        id = next;
        return {};
    });
}

Outcome System::destroy_mesh(MeshId mesh) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("destroy_mesh");
    Outcome error;
    const Impl::Mesh* m = impl_->find_mesh(mesh, error);
    if (!m) return error;
    if (m->instances > 0)
        return Outcome(ErrorCode::InvalidHandle, "mesh " + std::to_string(mesh) + " is still used by " +
                                                     std::to_string(m->instances) + " instances");
    impl_->meshes.erase(mesh);
    return {};
}

Outcome System::set_vertices(MeshId mesh, const float* positions, std::uint32_t vertex_count,
                             std::uint32_t stride, bool teleport) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_vertices");
    Outcome error;
    Impl::Mesh* m = impl_->find_deforming(mesh, vertex_count, error);
    if (!m) return error;
    if (vertex_count > 0 && !positions) return invalid("positions is null");
    if (stride < 12) return invalid("stride must be at least 12 bytes, got " + std::to_string(stride));
    return guarded([&]() -> Outcome {
        std::pmr::vector<glm::vec3> packed(vertex_count, &impl_->memory);
        for (std::uint32_t v = 0; v < vertex_count; ++v) {
            const auto* p = reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(positions) +
                                                           std::size_t(v) * stride);
            packed[v] = {p[0], p[1], p[2]};
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
                return invalid("vertex " + std::to_string(v) + " is not finite");
        }
        if (Status s = impl_->world->update_positions(m->gpu, packed); !s) return device_failure(s);
        m->teleport = m->teleport || teleport;
        return {};
    });
}

Outcome System::set_vertices(MeshId mesh, VkBuffer buffer, VkDeviceSize offset, std::uint32_t vertex_count,
                             bool teleport) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_vertices");
    Outcome error;
    Impl::Mesh* m = impl_->find_deforming(mesh, vertex_count, error);
    if (!m) return error;
    if (impl_->ctx->owns_device()) return invalid("vertex buffers need a host device (SystemDesc::host)");
    if (buffer == VK_NULL_HANDLE) return invalid("buffer is null");
    if (offset % 4 != 0) return invalid("offset must be a multiple of 4");
    return guarded([&]() -> Outcome {
        if (Status s = impl_->world->copy_positions(m->gpu, buffer, offset); !s) return device_failure(s);
        m->teleport = m->teleport || teleport;
        return {};
    });
}

Outcome System::set_bones(MeshId mesh, const Mat4* palette, std::uint32_t count, bool teleport) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_bones");
    Outcome error;
    Impl::Mesh* m = impl_->find_mesh(mesh, error);
    if (!m) return error;
    if (!m->deforming) return invalid("mesh " + std::to_string(mesh) + " was not created as deforming");
    const std::uint32_t joints = m->gpu.joint_count();
    if (joints == 0) return invalid("mesh " + std::to_string(mesh) + " has no skin (MeshDesc::skin)");
    if (count != joints)
        return invalid("got " + std::to_string(count) + " bone matrices for a skin of " +
                       std::to_string(joints) + " joints");
    if (!palette) return invalid("palette is null");
    for (std::uint32_t j = 0; j < count; ++j)
        if (Outcome o = check_transform(palette[j], "bone matrix"); !o)
            return invalid(o.message() + " (joint " + std::to_string(j) + ")");
    return guarded([&]() -> Outcome {
        std::pmr::vector<glm::mat4> bones(count, &impl_->memory);
        for (std::uint32_t j = 0; j < count; ++j)
            bones[j] = to_glm(palette[j]);
        if (Status s = impl_->world->pose_from_bones(m->gpu, bones); !s) return invalid(s.message());
        m->teleport = m->teleport || teleport;
        return {};
    });
}

Outcome System::Impl::add_instance(MeshId mesh, const Mat4& transform, const Mat4* previous, bool moving,
                                   InstanceId& id) {
    id = 0;
    Outcome error;
    Mesh* m = find_mesh(mesh, error);
    if (!m) return error;
    if (Outcome o = check_transform(transform, "transform"); !o) return o;
    if (previous)
        if (Outcome o = check_transform(*previous, "previous"); !o) return o;
    return guarded([&]() -> Outcome {
        const InstanceId next = next_id++;
        const bool dynamic = moving || m->deforming;
        std::optional<glm::mat4> prev;
        if (previous) prev = to_glm(*previous);
        instances.emplace(next, Instance{mesh, to_glm(transform), prev, dynamic});
        ++m->instances;
        if (!dynamic) static_dirty = true;
        id = next;
        return {};
    });
}

Outcome System::create_instance(MeshId mesh, const Mat4& transform, bool moving, InstanceId& id) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("create_instance");
    return impl_->add_instance(mesh, transform, nullptr, moving, id);
}

Outcome System::create_moving_instance(MeshId mesh, const Mat4& transform, const Mat4& previous,
                                       InstanceId& id) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("create_moving_instance");
    return impl_->add_instance(mesh, transform, &previous, true, id);
}

Outcome System::set_transform(InstanceId instance, const Mat4& transform, bool teleport) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_transform");
    auto it = impl_->instances.find(instance);
    if (it == impl_->instances.end())
        return Outcome(ErrorCode::InvalidHandle, "no instance " + std::to_string(instance));
    if (Outcome o = check_transform(transform, "transform"); !o) return o;
    it->second.model = to_glm(transform);
    it->second.teleport = it->second.teleport || teleport;
    if (!it->second.dynamic) impl_->static_dirty = true;
    return {};
}

Outcome System::destroy_instance(InstanceId instance) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("destroy_instance");
    auto it = impl_->instances.find(instance);
    if (it == impl_->instances.end())
        return Outcome(ErrorCode::InvalidHandle, "no instance " + std::to_string(instance));
    --impl_->meshes.at(it->second.mesh).instances;
    if (!it->second.dynamic) impl_->static_dirty = true;
    impl_->instances.erase(it);
    return {};
}

Outcome System::set_emitters(std::span<const WindEmitter> emitters) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_emitters");
    return guarded([&]() -> Outcome {
        std::pmr::vector<Emitter> out(&impl_->memory);
        for (const WindEmitter& e : emitters) {
            const int type = int(e.type);
            if (type < 0 || type > int(WindEmitterType::ConeMotor))
                return invalid("emitter " + std::to_string(out.size()) + ": unknown type " +
                               std::to_string(type));
            out.push_back(Emitter{EmitterType(type), to_glm(e.position), to_glm(e.direction), e.radius,
                                  e.strength, e.falloff, e.length});
        }
        // Every cascade blows them: a finer one's wind replaces a coarser one's where it covers it.
        if (Status s = impl_->solver->set_emitters(out); !s) return invalid(s.message());
        for (auto& coarser : impl_->coarse_solvers)
            if (Status s = coarser->set_emitters(out); !s) return device_failure(s);
        return {};
    });
}

Outcome System::set_ambient(const Vec3& velocity) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_ambient");
    if (Status s = impl_->solver->set_ambient(to_glm(velocity)); !s) return invalid(s.message());
    for (auto& coarser : impl_->coarse_solvers)
        if (Status s = coarser->set_ambient(to_glm(velocity)); !s) return device_failure(s);
    return {};
}

Outcome System::set_focus(const Vec3& position) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("set_focus");
    if (!finite(position)) return invalid("focus must be finite");
    // The next step scrolls by whole cells, counted in 32-bit integers: a move it could not make is
    // refused here, keeping the old focus, rather than failing every step after.
    const float h = impl_->solver_desc.cell_size;
    if (too_far_out(to_glm(position), h)) return invalid(std::string("focus ") + kTooFarOut);
    const glm::vec3 centre = impl_->solver->origin() + 0.5f * glm::vec3(impl_->solver_desc.cells) * h;
    if (glm::any(glm::greaterThan(glm::abs(to_glm(position) - centre) / h, glm::vec3(kMaxFocusMoveCells))))
        return invalid("focus is more than a million cells from the domain's centre; move it in smaller "
                       "steps or create the System at the new place");
    impl_->focus = to_glm(position);
    return {};
}

Outcome System::shift_origin(const Vec3& offset) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("shift_origin");
    if (!finite(offset)) return invalid("offset must be finite");
    Impl& m = *impl_;
    const glm::vec3 by = to_glm(offset);
    if (too_far_out(m.focus + by, m.solver_desc.cell_size))
        return invalid(std::string("the shifted focus ") + kTooFarOut);
    return guarded([&]() -> Outcome {
        const glm::mat4 move = glm::translate(glm::mat4(1.0f), by);
        m.focus += by;
        for (std::size_t k = 0; k <= m.coarse_solvers.size(); ++k) {
            WindSolver& solver = k == 0 ? *m.solver : *m.coarse_solvers[k - 1];
            VoxelWorld& world = k == 0 ? *m.world : *m.coarse_worlds[k - 1];
            if (Status s = solver.shift_origin(by); !s) return invalid(s.message());
            if (Status s = world.move_grid(solver.origin()); !s) return device_failure(s);
        }
        for (auto& [id, instance] : m.instances) {
            instance.model = move * instance.model;
            if (instance.prev) instance.prev = move * *instance.prev;
        }
        m.static_dirty = true;
        m.frame->origin_shifted();
        for (auto& [id, pending] : m.queries)
            if (!pending.asked)
                for (glm::vec3& p : pending.points)
                    p += by;
        return {};
    });
}

} // namespace gust
