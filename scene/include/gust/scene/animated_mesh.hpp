// glTF animation playback on the CPU: node hierarchy, rigid node animation and linear-blend skinning.
#pragma once

#include "gust/gpu/result.hpp"
#include "gust/scene/mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace gust {

/// A glTF mesh (static or skinned) whose posed vertices can be evaluated at any time of any of its
/// animation clips (CPU linear-blend skinning). Immutable once loaded: copies share the data, and every
/// const member may be called from several threads at once.
class AnimatedMesh {
  public:
    /// Loads a .gltf or .glb file with everything load_mesh checks, plus skins (joint indices in range,
    /// weights finite and non-negative) and animation clips (key times, value types and counts). On
    /// failure the message is "<path>: <reason>"; it never throws.
    static Result<AnimatedMesh> load(const std::filesystem::path& gltf_or_glb);

    /// The triangles exactly as load_mesh returns them, in the file's scene space and units, as a glTF
    /// viewer shows the file without animation: skinned meshes in their rest pose (joints placed by the
    /// nodes' own transforms). pose() writes positions for the same vertices in the same order.
    const Mesh& rest_pose() const;

    /// The names of the file's animation clips in file order; unnamed clips are "clip<index>".
    std::vector<std::string> clip_names() const;

    /// The index of the first clip called `name` (as clip_names() gives it), if any.
    std::optional<std::size_t> find_clip(const std::string& name) const;

    /// The clip's length in seconds: its last key time (clips start at time 0). 0 for a clip index out
    /// of range.
    double clip_duration(std::size_t clip) const;

    /// Whether any vertex follows joints of a skin (otherwise only rigid node animation moves it).
    bool skinned() const;

    /// Posed positions at time `t` (seconds) of `clip`, in the space of rest_pose(), written into `out`
    /// (resized to rest_pose().positions.size()). With `loop`, t wraps into [0, duration); otherwise the
    /// clip holds its first and last keys outside its range. A clip index out of range gives
    /// rest_pose()'s positions exactly. Non-finite t is taken as 0.
    void pose(std::size_t clip, double t, bool loop, std::vector<glm::vec3>& out) const;

    /// The most matrices a bone palette holds (16-bit joint indices, as gust::MeshSkin takes them).
    static constexpr std::size_t kMaxBones = 65536;
    /// The mesh as a GPU skinner takes it: bind positions, four joints and weights a vertex, and the palette
    /// size. The palette (bone_palette) holds every skin's joint matrices, one matrix per rigidly placed node
    /// block and the identity, so that every vertex of the file follows it; bind posed by a palette is
    /// pose() at the same time, up to float rounding (pose() blends in double).
    struct BoneSkin {
        std::vector<glm::vec3> bind;       ///< one per rest_pose() vertex, in the same order
        std::vector<std::uint16_t> joints; ///< 4 per vertex, each < joint_count
        std::vector<float> weights;        ///< 4 per vertex, summing to 1
        std::uint32_t joint_count = 0;
    };
    /// The skin for bone_palette; fails when a vertex follows more than four joints (a file with JOINTS_1)
    /// or the palette would pass kMaxBones.
    Result<BoneSkin> bone_skin() const;
    /// The palette at time `t` of `clip` (as pose() takes them), resized to bone_skin().joint_count: joint
    /// world matrix times inverse bind, bind space to the space of rest_pose().
    void bone_palette(std::size_t clip, double t, bool loop, std::vector<glm::mat4>& out) const;

  private:
    /// Every node's local transform at time `t` of `clip` (the rest transforms for a clip out of range).
    std::vector<glm::dmat4> locals_at(std::size_t clip, double t, bool loop) const;
    struct Data; ///< skeleton, skins, clips and per-vertex influences
    explicit AnimatedMesh(std::shared_ptr<const Data> data) : data_(std::move(data)) {}
    std::shared_ptr<const Data> data_;
};

} // namespace gust
