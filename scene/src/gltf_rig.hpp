// What places and animates every vertex of a glTF scene, as read from the file (gltf_rig.cpp) for
// AnimatedMesh to evaluate (animated_mesh.cpp).
#pragma once

#include "gltf_detail.hpp"

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <tiny_gltf.h>
#include <vector>

namespace gust {

// Named (not anonymous) so that AnimatedMesh::Data, which has external linkage, may hold these types.
namespace detail::anim {

enum class Path : std::uint8_t { translation, rotation, scale };
enum class Interpolation : std::uint8_t { step, linear, cubic };

struct Channel {
    std::size_t slot = 0; ///< index into the clip's animated nodes
    Path path = Path::translation;
    Interpolation interpolation = Interpolation::linear;
    std::vector<double> times;      ///< non-decreasing, seconds
    std::vector<glm::dvec4> values; ///< xyz, or quaternion xyzw; cubic: in-tangent, value, out-tangent
};

struct Clip {
    std::string name;
    double duration = 0.0;            ///< last key time, seconds
    std::vector<std::size_t> targets; ///< the nodes its channels move, one slot each
    std::vector<Channel> channels;
};

struct Node {
    glm::dmat4 rest{1.0}; ///< local transform as the file gives it
    bool has_matrix = false;
    glm::dvec3 translation{0.0};
    glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
    glm::dvec3 scale{1.0};
};

struct Skin {
    std::vector<std::size_t> joints;      ///< node indices
    std::vector<glm::dmat4> inverse_bind; ///< one per joint
};

/// How a run of vertices is placed.
enum class Placement : std::uint8_t {
    walk, ///< by the world transform of its node along the scene walk (rigid)
    skin, ///< by the joints of a skin
    fixed ///< not at all: a skinned node whose primitive has no joints keeps its raw positions
};

struct Block {
    std::uint32_t first = 0;
    std::uint32_t count = 0;
    std::size_t node = 0;
    Placement placement = Placement::walk;
    std::size_t skin = 0;
};

/// The joints and weights of every vertex, packed: vertex v's are [begin[v], begin[v + 1]).
struct Influences {
    std::vector<std::uint32_t> begin{0};
    std::vector<std::uint32_t> joint; ///< index into the vertex block's skin's joints
    std::vector<double> weight;       ///< non-zero, normalised to sum 1 per vertex
};

/// What places every vertex of a glTF scene: the node hierarchy and how each vertex follows it.
struct Rig {
    std::vector<glm::vec3> raw; ///< POSITION data of every vertex, before any transform
    std::vector<Node> nodes;
    std::vector<int> parent;                  ///< file hierarchy, -1 for roots
    std::vector<std::size_t> hierarchy_order; ///< every node after its parent
    std::vector<int> walk_order;              ///< as GltfGeometry
    std::vector<int> walk_parent;             ///< as GltfGeometry
    std::vector<Skin> skins;
    std::vector<Block> blocks;
    Influences influences; ///< empty ranges for vertices that no skin moves
    bool skinned = false;  ///< whether any block follows a skin
};

/// The rig of `model` (file of `file_size` bytes), whose scene build_gltf built into `geometry`; takes
/// the hierarchy and walk out of `geometry`. Checks the skins and their influences.
Result<Rig> read_rig(const tinygltf::Model& model, std::size_t file_size, GltfGeometry& geometry);

/// The animations of `model`, each channel checked against `nodes` (the rig's) and its accessors.
Result<std::vector<Clip>> read_clips(const tinygltf::Model& model, std::size_t file_size,
                                     const std::vector<Node>& nodes);

} // namespace detail::anim

} // namespace gust
