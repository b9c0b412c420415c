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
    std::uint32_t cascades = 1;            ///< nested grids, 1..8 (DomainDesc::cascades)
    std::uint32_t ratio = 4;               ///< cell size from one cascade to the next: 2 or 4
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

/// Joints a skin may have: gust's limit for MeshSkin::joint_count.
constexpr std::uint32_t kMaxJoints = 65536;

/// A skinned mesh as an engine holds it, four influences a vertex (Godot 3's ARRAY_BONES and ARRAY_WEIGHTS,
/// glTF's JOINTS_0 and WEIGHTS_0): the bind pose, the triangles, and per vertex 4 joints (indices into the
/// skin's binds, the palette) and 4 weights.
struct SkinnedMeshData {
    std::span<const float> positions;       ///< bind pose, float3 a vertex
    std::span<const std::uint32_t> indices; ///< triangles
    std::span<const std::int32_t> joints;   ///< 4 a vertex, each < joint_count
    std::span<const float> weights;         ///< 4 a vertex
    std::uint32_t joint_count = 0;          ///< the skin's binds: the palette's size, 1..kMaxJoints
};

/// One bind of a skin: the skeleton's bone it follows and its bind pose (the inverse of the bone's rest in
/// skeleton space, glTF's inverse bind matrix).
struct SkinBind {
    std::int32_t bone = -1;
    Mat4 pose;
};

/// The skin Godot makes for a skinned mesh without a Skin resource: bind i follows bone i, its pose the
/// inverse of bone i's global rest (its rest composed with its parents'). `parents[i]` < 0 marks a root.
/// Fails (naming the bone) on a parent out of range, a cycle or a rest that cannot be inverted.
Outcome default_skin(std::span<const Mat4> rests, std::span<const std::int32_t> parents,
                     std::vector<SkinBind>& binds);
/// The palette of a skin posed by its skeleton: palette[i] = bone_poses[binds[i].bone] · binds[i].pose,
/// bind-pose mesh space to the posed mesh in skeleton space (as Godot 3's renderer skins; the skinned
/// node's own transform then places it in the world). Fails on a bind whose bone is out of range.
Outcome skin_palette(std::span<const Mat4> bone_poses, std::span<const SkinBind> binds,
                     std::vector<Mat4>& palette);
/// a · b (column-major affine or projective 4x4).
Mat4 multiply(const Mat4& a, const Mat4& b);

/// One gust System plus the bookkeeping a scene graph needs: meshes shared by key, obstacles that turn from
/// static to moving when their transform changes, obstacles that vanish when the host stops reporting them.
/// Writer calls (everything but sample and read_field) from one thread; sample and read_field from any.
class WindHost {
  public:
    /// Creates the System with the snapshot on (Submission::OwnQueue): on `host`'s device when given (the
    /// engine's own), else on a device of its own; there, with `exported_copies` > 0, on the physical device
    /// `device_uuid` names (16 bytes) with that many exported copies of each cascade's wind texture
    /// (SystemDesc::exported_copies), for an engine that imports them into its own device.
    Outcome create(const WindHostConfig& config, const Hooks& hooks, const HostDevice* host = nullptr,
                   std::uint32_t exported_copies = 0, const std::uint8_t* device_uuid = nullptr);
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
    /// Uploads a skinned mesh (MeshDesc::skin, deforming) under the host's key; its pose is the bind pose
    /// until set_bones. Names the first bad joint index or count.
    Outcome add_skinned_mesh(std::uint64_t mesh_key, const SkinnedMeshData& data);
    /// The pose of skinned mesh `mesh_key` for the next step (System::set_bones): one matrix a joint. The
    /// first after add_skinned_mesh is a jump from the bind pose, pushing no air; later ones are motion.
    Outcome set_bones(std::uint64_t mesh_key, std::span<const Mat4> palette);
    /// Reports obstacle `key` (a node) with mesh `mesh_key` at `transform` this frame. New obstacles are
    /// static; one whose transform changed since the last report becomes moving from then on, its motion
    /// since that report pushing air in the next step. A skinned mesh's instance moves with its bones and
    /// its transform from the start (gust voxelizes deforming meshes every step).
    Outcome report_obstacle(std::uint64_t key, std::uint64_t mesh_key, const Mat4& transform);
    /// Removes obstacles not reported since begin_obstacles(), and meshes no obstacle uses any more.
    void end_obstacles();
    /// Moving obstacles now (for tests and stats).
    std::size_t moving_obstacles() const;

    Outcome set_emitters(std::span<const WindEmitter> emitters);
    Outcome set_ambient(const Vec3& velocity);
    /// Moves the domain's centre to `focus` (world m) when it changed (System::set_focus).
    Outcome set_focus(const Vec3& focus);
    Outcome step(float dt);
    /// Steps taken since create().
    std::uint64_t steps() const { return steps_; }

    /// Reader call: the wind at each point from the last step's snapshot. Before the first step (or without
    /// a System) every point gets `fallback`.
    void sample(std::span<const Vec3> points, std::span<Vec3> velocities, const Vec3& fallback) const;
    /// Reader call: the last step's wind at every cell centre of cascade `cascade` (0 the finest, cells
    /// cell_size · ratio^cascade wide, centred as the finest) into `field` (its vector is reused).
    Outcome read_field(WindField& field, std::uint32_t cascade = 0) const;
    /// Milliseconds the last step() took on the calling thread, wall clock.
    double last_step_ms() const { return last_step_ms_; }
    /// System::export_wind_copy and System::copy_wind_textures (create's exported_copies).
    Outcome export_wind_copy(std::uint32_t cascade, std::uint32_t slot, ExportedImage& out);
    Outcome copy_wind_textures(std::uint32_t slot);
    /// Every cascade's wind image, the finest first (System::wind_textures); empty without a System.
    std::span<const WindTexture> wind_textures() const;
    /// The Vulkan device's name, or "" without a System.
    std::string device_name() const;

  private:
    struct Mesh {
        MeshId id = 0;
        bool skinned = false;
        bool posed = false; ///< set_bones was called since add_skinned_mesh
    };
    struct Obstacle {
        std::uint64_t mesh_key = 0;
        InstanceId instance = 0;
        Mat4 transform;
        bool moving = false;
        bool seen = false;
    };
    std::unique_ptr<System> system_;
    WindHostConfig config_;
    std::map<std::uint64_t, Mesh> meshes_;
    std::map<std::uint64_t, Obstacle> obstacles_;
    std::uint64_t steps_ = 0;
    double last_step_ms_ = 0.0;
};

} // namespace gust::integration
