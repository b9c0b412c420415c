// The engine-facing layer of the Godot plugin, written against gust's public API only and free of any Godot
// type, so a GDExtension or another engine's binding stays a thin translation of its scene into these calls.
#pragma once

#include <cstdint>
#include <gust/gust.hpp>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace gust::integration {

/// What a host node sets; validate() names the first bad value.
struct WindHostConfig {
    std::uint32_t cells[3] = {32, 16, 32}; ///< wind cells per axis, 8..256
    float cell_size = 1.0f;                ///< m
    std::uint32_t voxels_per_cell = 4;     ///< 1..8
    Vec3 ambient{};                        ///< m/s, the prevailing wind
    std::int32_t quality = 1;              ///< 0 low, 1 medium, 2 high (quality_settings)
    Vec3 focus{};                          ///< the domain's centre, world m
};

/// An error message for the first invalid value of `config` ("cell_size -1 must be in ..."), or "" when
/// valid.
std::string validate(const WindHostConfig& config);
/// The solver settings a quality level stands for (docs/godot.md "Properties").
WindSettings quality_settings(std::int32_t quality);

/// The wind field at cell centres, as a host uploads it into a 3D texture.
struct WindField {
    std::uint32_t extent[3] = {}; ///< cells per axis (width x, height y, depth z)
    /// RGBA floats, x fastest then y then z: rgb m/s, a = 1 (the snapshot carries no solid fraction).
    std::vector<float> rgba;
    Vec3 origin{};           ///< the domain's min corner, world m
    float cell_size = 0.0f;  ///< m; texture coordinate = (world − origin) / (extent · cell_size)
    std::uint64_t frame = 0; ///< the snapshot's step (SnapshotInfo::frame)
};

/// One gust System plus the bookkeeping a scene graph needs: meshes shared by key, obstacles that turn from
/// static to moving when their transform changes, obstacles that vanish when the host stops reporting them.
/// Writer calls (everything but sample and read_field) from one thread; sample and read_field from any.
class WindHost {
  public:
    /// Creates the System on its own Vulkan device with the snapshot on (Submission::OwnQueue).
    Outcome create(const WindHostConfig& config, const Hooks& hooks);
    /// Destroys the System and forgets every mesh and obstacle.
    void destroy();
    bool alive() const { return system_ != nullptr; }

    /// Marks every obstacle unseen; end_obstacles() removes those not reported since.
    void begin_obstacles();
    /// True when the mesh `mesh_key` was uploaded (add_mesh) and is still alive.
    bool has_mesh(std::uint64_t mesh_key) const { return meshes_.count(mesh_key) != 0; }
    /// Uploads a static triangle mesh (float3 positions, 32-bit indices) under the host's key.
    Outcome add_mesh(std::uint64_t mesh_key, std::span<const float> positions,
                     std::span<const std::uint32_t> indices);
    /// Reports obstacle `key` (a node) with mesh `mesh_key` at `transform` this frame. New obstacles are
    /// static; one whose transform changed since the last report becomes moving from then on, its motion
    /// since that report pushing air in the next step.
    Outcome report_obstacle(std::uint64_t key, std::uint64_t mesh_key, const Mat4& transform);
    /// Removes obstacles not reported since begin_obstacles(), and meshes no obstacle uses any more.
    void end_obstacles();
    /// Moving obstacles now (for tests and stats).
    std::size_t moving_obstacles() const;

    Outcome set_emitters(std::span<const WindEmitter> emitters);
    Outcome set_ambient(const Vec3& velocity);
    Outcome step(float dt);
    /// Steps taken since create().
    std::uint64_t steps() const { return steps_; }

    /// Reader call: the wind at each point from the last step's snapshot. Before the first step (or without
    /// a System) every point gets `fallback`.
    void sample(std::span<const Vec3> points, std::span<Vec3> velocities, const Vec3& fallback) const;
    /// Reader call: the last step's field at every cell centre into `field` (its vector is reused).
    Outcome read_field(WindField& field) const;
    /// Milliseconds the last step() took on the calling thread, wall clock.
    double last_step_ms() const { return last_step_ms_; }
    /// The Vulkan device's name, or "" without a System.
    std::string device_name() const;

  private:
    struct Obstacle {
        std::uint64_t mesh_key = 0;
        InstanceId instance = 0;
        Mat4 transform;
        bool moving = false;
        bool seen = false;
    };
    std::unique_ptr<System> system_;
    WindHostConfig config_;
    std::map<std::uint64_t, MeshId> meshes_;
    std::map<std::uint64_t, Obstacle> obstacles_;
    std::uint64_t steps_ = 0;
    double last_step_ms_ = 0.0;
};

} // namespace gust::integration
