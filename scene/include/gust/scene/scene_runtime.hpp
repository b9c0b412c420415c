// The geometry of a loaded scene over time, for the simulate command, tests and the sample.
#pragma once

#include "gust/gpu/result.hpp"
#include "gust/scene/animated_mesh.hpp"
#include "gust/scene/mesh.hpp"
#include "gust/scene/scene_file.hpp"

#include <cstddef>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

namespace gust {

/// The loaded meshes of a scene and each object's geometry at any time. Meshes are loaded once per
/// file and shared between objects. Every `object` argument must be below object_count(). Not
/// thread-safe: positions() reuses a buffer per object.
class SceneRuntime {
  public:
    /// Loads every mesh of `scene` once (shared between objects with the same path), generates each
    /// terrain (make_terrain_mesh) and finds each animation clip. On failure the message is "<scene file>:
    /// objects[i].<key>: <reason>", the reason naming the mesh file (and listing the file's clips when a clip
    /// is missing); it never throws.
    static Result<SceneRuntime> load(const SceneDesc& scene);

    /// Number of objects, as in the scene description.
    std::size_t object_count() const;

    /// Bind-pose triangles of an object in mesh space (source units); indices are fixed for the
    /// object's lifetime. The reference lives as long as this runtime.
    const Mesh& mesh(std::size_t object) const;

    /// Whether the object has a skinned animation (its positions change over time).
    bool deforms(std::size_t object) const;

    /// Mesh-to-world matrix of the object at time t (seconds): object_matrix of its description.
    glm::mat4 model(std::size_t object, double t) const;

    /// Mesh-space positions at time t (seconds): posed at clip time offset + speed · t for animated
    /// objects, the rest pose otherwise. Same order and count as mesh(object).positions. The reference
    /// stays valid until the next call for that object.
    const std::vector<glm::vec3>& positions(std::size_t object, double t);

    /// Whether the object's change from time t0 to t1 (one frame) is a jump rather than motion: its
    /// keyframes jump (object_jumps), or its looping clip wraps from its end to its start in between. The
    /// wind takes such a frame as a teleport (no surface velocity).
    bool jumps(std::size_t object, double t0, double t1) const;

  private:
    struct Object {
        SceneObject desc;
        std::shared_ptr<const Mesh> mesh;             ///< rest pose (shared with `animated` when set)
        std::shared_ptr<const AnimatedMesh> animated; ///< set when the object plays a clip
        std::size_t clip = 0;                         ///< index into animated's clips
        std::vector<glm::vec3> posed;                 ///< positions() buffer
    };
    std::vector<Object> objects_;
};

} // namespace gust
