// The scene every table of gust_bench_solver runs: the unit box as the ground, three buildings and a sliding
// box, an omni emitter and the ambient wind, laid out as fractions of the domain (Layout), once for the wind
// solver alone (Scene) and once through the public API as a game drives it (FrameScene).
#pragma once

#include "solver_bench.hpp"

#include <algorithm>
#include <array>
#include <glm/gtc/matrix_transform.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <memory>
#include <optional>
#include <span>
#include <sstream>

namespace gust::bench::solver {

/// The unit cube [0, 1]^3 as 8 corners and 12 triangles; every box of the scene is an instance of it.
struct UnitBox {
    std::array<glm::vec3, 8> positions;
    std::array<std::uint32_t, 36> indices;

    UnitBox() {
        for (std::uint32_t i = 0; i < 8; ++i)
            positions[i] = glm::vec3(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
        const std::uint32_t quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                           {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
        std::size_t n = 0;
        for (const auto& q : quads)
            for (std::uint32_t corner : {q[0], q[1], q[2], q[0], q[2], q[3]})
                indices[n++] = corner;
    }

    gust::MeshView view() const {
        gust::MeshView v;
        v.positions = &positions[0].x;
        v.vertex_count = positions.size();
        v.position_stride = sizeof(glm::vec3);
        v.indices = indices.data();
        v.index_count = indices.size();
        return v;
    }
};

/// Model matrix of the unit box stretched to span lo..hi.
inline glm::mat4 box_model(glm::vec3 lo, glm::vec3 hi) {
    return glm::scale(glm::translate(glm::mat4(1.0f), lo), hi - lo);
}

/// A box of the scene: x and z in fractions of the domain's extent, y in metres from its floor.
struct Placed {
    glm::vec2 lo_xz, hi_xz;
    float lo_y, hi_y; ///< metres, or fractions of the height where `top_fraction` says so
    bool top_fraction;
};

/// Where the scene's solids and source lie on one grid: a ground slab whose top cuts the lowest cells,
/// three buildings standing in it, a box sliding along +z over the ground, an omni emitter among them,
/// and the ambient wind along +x. Footprints and heights are fractions of the domain, so every size holds
/// the same scene at its own resolution; the ground's top is at the same height in metres, so it cuts its
/// cells alike.
class Layout {
  public:
    explicit Layout(const gust::SolverDesc& desc)
        : origin_(desc.origin), extent_(glm::vec3(desc.cells) * desc.cell_size) {}

    /// Model matrices of the unit box for the static boxes, the ground first.
    std::vector<glm::mat4> statics() const {
        std::vector<glm::mat4> out;
        for (const Placed& p : kStatic)
            out.push_back(model(p));
        return out;
    }

    /// The sliding box's model matrix at step `index`.
    glm::mat4 moving(std::int64_t index) const {
        return glm::translate(glm::mat4(1.0f), float(index) * kDt * kBoxVelocity) * model(kMoving);
    }

    /// The omni emitter, pushing air outwards among the buildings.
    gust::Emitter emitter() const {
        gust::Emitter e;
        e.type = gust::EmitterType::Omni;
        e.position = origin_ + extent_ * kEmitterAt;
        e.radius = kEmitterRadius * std::min({extent_.x, extent_.y, extent_.z});
        e.strength = kEmitterStrength;
        return e;
    }

    glm::vec3 centre() const { return origin_ + 0.5f * extent_; }

    /// What the scene holds, for the results text.
    static std::string describe() {
        std::ostringstream out;
        const auto box = [&](const Placed& p) {
            out << "x " << p.lo_xz.x << "-" << p.hi_xz.x << ", z " << p.lo_xz.y << "-" << p.hi_xz.y
                << " of the extent, y from " << p.lo_y << " m to " << p.hi_y
                << (p.top_fraction ? " of the height" : " m");
        };
        out << "a ground slab (past every side) with its top at y = " << kStatic[0].hi_y
            << " m, inside the lowest cells; buildings at ";
        for (std::size_t i = 1; i < std::size(kStatic); ++i) {
            if (i > 1) out << (i + 1 == std::size(kStatic) ? " and " : "; ");
            box(kStatic[i]);
        }
        out << ", standing in the ground; a box at ";
        box(kMoving);
        out << ", sliding along +z at " << kBoxVelocity.z << " m/s; an omni emitter (" << kEmitterStrength
            << " m/s, radius " << kEmitterRadius << " of the shortest side, falloff 1) at (" << kEmitterAt.x
            << ", " << kEmitterAt.y << ", " << kEmitterAt.z << ") of the extent";
        return out.str();
    }

  private:
    glm::mat4 model(const Placed& p) const {
        const float hi_y = p.top_fraction ? p.hi_y * extent_.y : p.hi_y;
        const glm::vec3 lo(p.lo_xz.x * extent_.x, p.lo_y, p.lo_xz.y * extent_.z);
        const glm::vec3 hi(p.hi_xz.x * extent_.x, hi_y, p.hi_xz.y * extent_.z);
        return box_model(origin_ + lo, origin_ + hi);
    }

    /// The ground first, reaching past the sides and the floor so that it has no edges inside; the
    /// buildings reach below the floor too.
    static constexpr Placed kStatic[] = {{{-0.1f, -0.1f}, {1.1f, 1.1f}, -1.0f, 0.3f, false},
                                         {{0.2f, 0.25f}, {0.3f, 0.4f}, -1.0f, 0.5f, true},
                                         {{0.5f, 0.6f}, {0.62f, 0.72f}, -1.0f, 0.7f, true},
                                         {{0.7f, 0.2f}, {0.78f, 0.45f}, -1.0f, 0.35f, true}};
    static constexpr Placed kMoving{{0.42f, 0.12f}, {0.48f, 0.18f}, 0.5f, 0.2f, true};
    static constexpr glm::vec3 kEmitterAt{0.35f, 0.3f, 0.5f};
    static constexpr float kEmitterRadius = 0.15f;
    static constexpr float kEmitterStrength = 6.0f;

    glm::vec3 origin_;
    glm::vec3 extent_;
};

/// The scene for the wind solver alone (the time-to-tolerance table): a b = 4 VoxelWorld over the wind
/// grid with the static boxes set; the moving box is placed by advance().
class Scene {
  public:
    static gust::Result<std::unique_ptr<Scene>> create(gust::gpu::Context& ctx,
                                                       const gust::SolverDesc& desc) {
        std::unique_ptr<Scene> scene(new Scene(desc));
        auto grid = gust::voxel_grid(desc, 4);
        if (!grid) return grid.status();
        gust::WorldDesc world;
        world.grid = *grid;
        world.tree.branching = 4;
        world.method = gust::VoxelizeMethod::Compute;
        auto created = gust::VoxelWorld::create(ctx, world);
        if (!created) return created.status();
        scene->world_ = std::move(*created);
        auto box = scene->world_->upload(UnitBox().view());
        if (!box) return gust::Status::failure("box upload failed: " + box.message());
        scene->box_ = std::make_unique<gust::GpuMesh>(std::move(*box));
        std::vector<gust::GpuInstance> statics;
        for (const glm::mat4& model : scene->layout_.statics())
            statics.push_back({scene->box_.get(), model, std::nullopt});
        scene->world_->set_static(std::move(statics));
        return scene;
    }

    /// Moves the box to step `index` and voxelizes the frame (static set once, box with velocities).
    gust::Status advance(std::int64_t index) {
        const gust::GpuInstance moving{box_.get(), layout_.moving(index), layout_.moving(index - 1)};
        auto frame = world_->step(std::span(&moving, 1), kDt);
        return frame ? gust::Status{} : frame.status();
    }

    /// The solid boundary as the solver takes it: the tree and the moving box's fragments. Taken after
    /// advance(), since a step may reallocate the fragment list.
    gust::SolidSource source() const { return gust::solid_source(*world_); }

    const Layout& layout() const { return layout_; }

  private:
    explicit Scene(const gust::SolverDesc& desc) : layout_(desc) {}

    Layout layout_;
    std::unique_ptr<gust::VoxelWorld> world_;
    std::unique_ptr<gust::GpuMesh> box_;
};

/// gust's matrix type from GLM's (both column-major).
inline gust::Mat4 to_mat4(const glm::mat4& m) {
    gust::Mat4 out;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            out.m[4 * c + r] = m[c][r];
    return out;
}

/// The Status of a public API call's Outcome, its message prefixed with what was being done.
inline gust::Status checked(const gust::Outcome& outcome, const char* what) {
    return outcome ? gust::Status{} : gust::Status::failure(std::string(what) + ": " + outcome.message());
}

/// The frame tables' scene through the public API, as a game drives gust: a gust::System on its own
/// device whose wind domain is the grid of `desc`, the unit box as one mesh, the static boxes as
/// instances, the sliding box as a moving instance, the ambient wind and the emitter. advance() moves the
/// box and runs one whole frame (voxelizer, tree, wind, texture) with System::step.
class FrameScene {
  public:
    static gust::Result<std::unique_ptr<FrameScene>> create(const gust::SolverDesc& desc,
                                                            const Options& options,
                                                            std::uint32_t cycles_per_step,
                                                            bool moving = true) {
        std::unique_ptr<FrameScene> scene(new FrameScene(desc));
        gust::SystemDesc system;
        system.device = options.device.empty() ? nullptr : options.device.c_str();
        system.voxelize = gust::VoxelizePath::Compute;
        for (int a = 0; a < 3; ++a)
            system.domain.cells[a] = desc.cells[a];
        system.domain.cell_size = desc.cell_size;
        system.domain.voxels_per_cell = desc.voxels_per_cell;
        system.domain.branching = 4;
        const glm::vec3 centre = scene->layout_.centre();
        system.domain.focus = {centre.x, centre.y, centre.z};
        system.wind.tolerance = desc.tolerance;
        system.wind.max_cycles = desc.max_cycles;
        system.wind.cycles_per_step = cycles_per_step;
        system.wind.vorticity = desc.vorticity;
        system.wind.advection = desc.advection == gust::Advection::MacCormack
                                    ? gust::WindAdvection::MacCormack
                                    : gust::WindAdvection::SemiLagrangian;
        if (gust::Status s = checked(gust::System::create(system, scene->system_), "System::create"); !s)
            return s;
        gust::System& sys = *scene->system_;
        const UnitBox box;
        gust::MeshDesc mesh;
        mesh.positions = &box.positions[0].x;
        mesh.vertex_count = std::uint32_t(box.positions.size());
        mesh.indices = box.indices.data();
        mesh.index_count = std::uint32_t(box.indices.size());
        gust::MeshId mesh_id = 0;
        if (gust::Status s = checked(sys.create_mesh(mesh, mesh_id), "create_mesh"); !s) return s;
        for (const glm::mat4& model : scene->layout_.statics()) {
            gust::InstanceId id = 0;
            if (gust::Status s =
                    checked(sys.create_instance(mesh_id, to_mat4(model), false, id), "create_instance");
                !s)
                return s;
        }
        if (moving)
            if (gust::Status s =
                    checked(sys.create_moving_instance(mesh_id, to_mat4(scene->layout_.moving(0)),
                                                       to_mat4(scene->layout_.moving(-1)), scene->moving_),
                            "create_moving_instance");
                !s)
                return s;
        if (gust::Status s = checked(sys.set_ambient({kAmbient.x, kAmbient.y, kAmbient.z}), "set_ambient");
            !s)
            return s;
        const gust::Emitter e = scene->layout_.emitter();
        gust::WindEmitter emitter;
        emitter.type = gust::WindEmitterType::Omni;
        emitter.position = {e.position.x, e.position.y, e.position.z};
        emitter.radius = e.radius;
        emitter.strength = e.strength;
        emitter.falloff = e.falloff;
        if (gust::Status s = checked(sys.set_emitters(std::span(&emitter, 1)), "set_emitters"); !s) return s;
        return scene;
    }

    /// Moves the box to step `index` (created at step 0) and runs the frame; the wall time around step().
    gust::Result<double> advance(std::int64_t index) {
        if (index > 0 && moving_ != 0)
            if (gust::Status s =
                    checked(system_->set_transform(moving_, to_mat4(layout_.moving(index))), "set_transform");
                !s)
                return s;
        const auto start = Clock::now();
        const gust::Outcome stepped = system_->step(kDt);
        const double wall_ms = ms_since(start);
        if (gust::Status s = checked(stepped, "step"); !s) return s;
        return wall_ms;
    }

    const gust::FrameStats& stats() const { return system_->stats(); }

    /// System::set_dispatch_timing: the frames from the next on give one entry a dispatch in stats().ms.
    gust::Status time_dispatches(bool on) {
        return checked(system_->set_dispatch_timing(on), "set_dispatch_timing");
    }

  private:
    explicit FrameScene(const gust::SolverDesc& desc) : layout_(desc) {}

    Layout layout_;
    std::unique_ptr<gust::System> system_;
    gust::InstanceId moving_ = 0;
};

} // namespace gust::bench::solver
