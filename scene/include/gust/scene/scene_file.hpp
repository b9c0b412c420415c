// Scene files (JSON, docs/scene-format.md): meshes with transforms, rigid keyframes and skinned clips,
// emitters, ambient wind and the simulation domain. Loading checks every value and never throws.
#pragma once

#include "gust/gpu/result.hpp"
#include "gust/scene/primitives.hpp"

#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <optional>
#include <string>
#include <vector>

namespace gust {

/// Places a mesh in the world: translate + Rz(rz)·Ry(ry)·Rx(rx)·(scale·p), rotations in degrees about
/// the world axes, x first. Units are the scene's (metres for the wind).
struct Transform {
    glm::vec3 translate{0.0f};  ///< world units
    glm::vec3 rotate_deg{0.0f}; ///< degrees about world x, y, z, applied x first
    float scale = 1.0f;         ///< uniform, > 0
    /// The matrix mapping mesh space to world space.
    glm::mat4 matrix() const;
};

/// One key of a rigid object's motion.
struct Keyframe {
    double t = 0.0;      ///< seconds (frame · dt)
    Transform transform; ///< the object's placement at t
    /// JSON "teleport": the object holds the previous key's placement until t and jumps here then (a
    /// respawn, a cut); the wind sees the jump as a teleport (object_jumps).
    bool teleport = false;
};

/// A skinned clip to play (glTF meshes only): clip time = offset + speed · scene time.
struct AnimationDesc {
    std::string clip;    ///< clip name as AnimatedMesh::clip_names() gives it
    double speed = 1.0;  ///< playback rate (1 = as authored; negative plays backwards)
    bool loop = true;    ///< wrap at the clip's end; otherwise hold the last key
    double offset = 0.0; ///< clip time at scene time 0, seconds
};

/// One mesh instance in the scene: a mesh file or a generated terrain.
struct SceneObject {
    std::filesystem::path
        mesh;               ///< absolute (resolved relative to the scene file's folder); empty for a terrain
    bool is_static = false; ///< JSON "static": never moves, voxelized once
    Transform transform;    ///< used when there are no keyframes
    std::vector<Keyframe> keyframes;        ///< strictly increasing t; empty for a fixed transform
    std::optional<AnimationDesc> animation; ///< a skinned clip deforming the mesh, if any
    std::optional<TerrainDesc> terrain;     ///< JSON "terrain": a generated mesh instead of a file
};

/// One key of a moving emitter's path.
struct EmitterKey {
    double t = 0.0;           ///< seconds (frame · dt)
    glm::vec3 position{0.0f}; ///< metres, world
};

/// A wind source. The solver defines each type's profile; these are its parameters.
struct EmitterDesc {
    std::string type;              ///< "directional", "omni", "vortex" or "motor"
    glm::vec3 position{0.0f};      ///< world units (metres); a motor's start
    glm::vec3 direction{1, 0, 0};  ///< unit vector (normalised at load): flow or axis direction
    float radius = 1.0f;           ///< metres, > 0
    float strength = 0.0f;         ///< wind speed at the centre, m/s (negative reverses it)
    float falloff = 1.0f;          ///< exponent p of (1 − d/radius)^p inside the radius, >= 0 (0 = uniform)
    std::string shape = "capsule"; ///< motors: "capsule" or "cone"
    float length = 0.0f;           ///< motors: metres along `direction`, >= 0 (> 0 for a cone)
    std::vector<EmitterKey> path;  ///< strictly increasing t; empty: fixed at `position`
};

/// Numerics of the wind solver (all optional in the file; defaults as in gust::SolverDesc).
struct SolverSettings {
    std::string advection = "maccormack"; ///< "maccormack", "semi_lagrangian" or "none"
    std::string pressure = "mgpcg";       ///< "mgpcg", "multigrid" or "jacobi"
    float tolerance = 1e-5f;              ///< relative residual, in (0, 1)
    std::uint32_t max_cycles = 32;        ///< multigrid V-cycles per step, 1..1000
    std::uint32_t cycles_per_step = 0;    ///< V-cycles every step runs, 0..1000 (0: until the tolerance)
    std::uint32_t max_iterations = 4000;  ///< Jacobi iterations per step, 1..1000000
    float vorticity = 0.2f;               ///< confinement strength, 0..10
    float viscosity = 0.0f;               ///< m^2/s, >= 0
    float max_solid_speed = 50.0f;        ///< m/s, in (0, 256]: fastest a surface pushes air
};

/// The simulated box and its resolution.
struct DomainDesc {
    glm::vec3 center{0.0f};            ///< world units (metres); min corner = center − cells·cell_size/2
    glm::uvec3 cells{32, 16, 32};      ///< wind cells per axis, each 8..256
    float cell_size = 1.0f;            ///< metres, > 0
    std::uint32_t voxels_per_cell = 4; ///< voxels per wind cell per axis, 1..8
    std::uint32_t branching = 4;       ///< sparse tree branching per axis: 2, 4 or 8
    std::uint32_t hysteresis = 8;      ///< frames a tree node stays refined after its last fragment
    std::uint32_t cascades = 1;        ///< nested grids around the centre, 1..8 (gust::WindDomain::cascades)
    std::uint32_t ratio = 4;           ///< cell size from one cascade to the next coarser: 2 or 4
};

/// A whole scene file.
struct SceneDesc {
    std::filesystem::path file;        ///< the scene file as given to load_scene (for messages)
    double dt = 0.02;                  ///< seconds per frame, > 0
    DomainDesc domain;                 ///< the simulated box
    glm::vec3 ambient_velocity{0.0f};  ///< m/s, world space, entering at the domain's faces
    std::vector<SceneObject> objects;  ///< meshes, in file order
    std::vector<EmitterDesc> emitters; ///< wind sources, in file order
    SolverSettings solver;             ///< JSON "solver"
};

/// Reads and checks a scene file. Mesh files must exist (they are not opened here: the mesh loaders
/// report their own errors later). On failure the message is "<file>: <key path>: <reason>", e.g.
/// "scene.json: objects[1].keyframes[2].t: keyframes must be in increasing time order (2.0 after 3.0)";
/// it never throws. Safe to call from several threads at once.
Result<SceneDesc> load_scene(const std::filesystem::path& file);

/// World matrix of an object at time t (seconds): keyframes interpolate linearly in time per component
/// (translate, rotate_deg, scale), holding the end values outside their range (and a key's predecessor's
/// until a "teleport" key); without keyframes the object's transform.
glm::mat4 object_matrix(const SceneObject& object, double t);

/// Whether the object's keyframed motion jumps between times t0 and t1 (t0 < t1, one frame apart): a
/// "teleport" key falls in (t0, t1], or a keyframe segment shorter than t1 − t0 ends there (a change no
/// frame sees as motion). A frame whose motion jumps is a teleport: it moves the solid without pushing air.
bool object_jumps(const SceneObject& object, double t0, double t1);

/// Position of an emitter at time t (seconds): its path interpolated linearly, holding the end keys
/// outside their range; without a path its position.
glm::vec3 emitter_position(const EmitterDesc& emitter, double t);

} // namespace gust
