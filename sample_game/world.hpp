// The sample's scene on the CPU: what is where at time t, and what gust is told about it.
#pragma once

#include "sample/sample_io.h"
#include "stage.hpp"

#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <gust/gust.hpp>
#include <gust/scene/animated_mesh.hpp>
#include <gust/scene/mesh.hpp>
#include <gust/scene/primitives.hpp>
#include <memory>
#include <string>
#include <vector>

namespace sample {

/// How a drawn object moves and whether gust sees it as a solid.
enum class ObjectKind {
    Static,  ///< never moves; a solid voxelized once
    Rigid,   ///< moves along a path; a moving solid
    Skinned, ///< walks: posed every frame; a deforming moving solid
    Tree,    ///< sways with the wind (foliage state); not a solid
    Prop,    ///< drawn only (the fan)
};

/// One loaded mesh: its triangles and, for skinned ones, the animation.
struct WorldMesh {
    gust::Mesh mesh;                               ///< rest pose (skinned) or the only pose
    std::shared_ptr<gust::AnimatedMesh> animation; ///< skinned meshes only
    std::size_t clip = 0;                          ///< the walk clip
    gust::AnimatedMesh::BoneSkin bones;            ///< skinned meshes: gust's skin (bind pose, influences)
};

/// A placed mesh.
struct WorldObject {
    std::string name;
    std::size_t mesh = 0; ///< index into World::meshes()
    ObjectKind kind = ObjectKind::Static;
    glm::mat4 model{1.0f};          ///< this frame's placement (world, m)
    glm::vec3 color{0.7f};          ///< linear RGB
    std::uint32_t foliage_slot = 0; ///< Tree: its spring-damper in the foliage state
    float sway_height = 1.0f;       ///< Tree: model-space height from which the crown bends
    float sway_length = 1.0f;       ///< Tree: model-space height over which bending reaches full
    gust::InstanceId instance = 0;  ///< solids: gust's instance
    double lap = 0.0;               ///< Skinned: laps of its walk clip played so far
    bool wrapped = false;           ///< Skinned: the clip wrapped from its end to its start this frame
};

/// One grass blade (width > 0) or tree crown (width 0, rooted at the top of its tree) that the wind bends.
using FoliageSeed = gust::shaderio::FoliageSeed;

/// Settings the HUD and the command line change.
struct WorldSettings {
    std::uint32_t grass_blades = 20000;
    float wind_speed = 4.0f;        ///< ambient base speed, m/s
    float wind_heading_deg = 20.0f; ///< ambient direction around +y, from +x
    float gustiness = 0.5f;         ///< relative amplitude of the gusts
    bool fan_on = true;
    float fan_strength = 7.0f; ///< m/s
    bool flyer_motor_on = true;
    float walk_speed = 1.0f; ///< animation and path speed factor
};

/// The scene at time t, and the link to gust.
class World {
  public:
    /// Loads the meshes from `assets` (the repository's assets/ folder) and places everything. Throws
    /// std::runtime_error naming the file when an asset is missing or malformed.
    World(const std::filesystem::path& assets, const WorldSettings& settings);

    /// Moves the characters, the flyer and the fan to time `t` (seconds) and poses the skinned meshes.
    void update(double t);
    /// Creates gust's meshes and instances for the solids (once per System).
    void attach(gust::System& wind);
    /// Sends this frame's transforms, poses, emitters and ambient wind, and steps gust by `dt`.
    gust::Outcome step_wind(gust::System& wind, float dt, double t);

    const std::vector<WorldMesh>& meshes() const { return meshes_; }
    const std::vector<WorldObject>& objects() const { return objects_; }
    /// The posed vertices of a skinned mesh this frame (its rest pose for other meshes), for drawing.
    const std::vector<glm::vec3>& posed(std::size_t mesh) const { return posed_[mesh]; }
    /// A skinned mesh's bone palette this frame (WorldMesh::bones), which gust skins from.
    const std::vector<glm::mat4>& palette(std::size_t mesh) const { return palettes_[mesh]; }
    /// Grass blades first, then one entry per tree.
    const std::vector<FoliageSeed>& foliage() const { return foliage_; }
    std::uint32_t grass_count() const { return grass_count_; }
    /// Where the follow camera looks: above the fox's feet.
    glm::vec3 follow_target() const { return stage_.fox.position + glm::vec3(0.0f, 0.6f, 0.0f); }
    /// Where the flight (--fly) is at time t: a loop of 300 m radius around the village at 12 m/s, 2 m
    /// above the ground, crossing the ridge and the groves.
    glm::vec3 flight_at(double t) const;
    /// Where the actors are this frame (for the tour's cameras).
    const Stage& stage() const { return stage_; }
    /// The ambient wind at time t (m/s), gusts included.
    glm::vec3 ambient(double t) const;
    /// The fan's emitter at time t (for drawing its cone as well as for gust).
    gust::WindEmitter fan(double t) const;
    /// The emitter the flyer carries at time t.
    gust::WindEmitter flyer_motor() const { return flyer_motor_; }
    WorldSettings& settings() { return settings_; }

  private:
    std::size_t add_mesh(gust::Mesh mesh);
    void plant_grass();

    WorldSettings settings_;
    gust::TerrainDesc terrain_;
    std::vector<WorldMesh> meshes_;
    std::vector<std::vector<glm::vec3>> posed_;
    std::vector<std::vector<glm::mat4>> palettes_; ///< skinned meshes only
    std::vector<WorldObject> objects_;
    std::vector<gust::MeshId> gust_meshes_;
    std::vector<FoliageSeed> foliage_;
    std::uint32_t grass_count_ = 0;
    Stage stage_;
    gust::WindEmitter flyer_motor_;
};

} // namespace sample
