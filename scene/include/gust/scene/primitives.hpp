// Generated meshes for tests, samples and scene files.
#pragma once

#include "gust/scene/mesh.hpp"

#include <cstdint>
#include <glm/glm.hpp>
#include <optional>
#include <vector>

namespace gust {

/// The closed axis-aligned box [min, max] (same units as the arguments) as 8 vertices and 12 triangles,
/// wound counter-clockwise seen from outside. Named "box".
Mesh make_box_mesh(glm::vec3 min, glm::vec3 max);

/// One shaped bump of a terrain: height · exp(−(d / width)²), d the distance in x/z from the segment
/// [from, to] (a point when from == to). A scene file's "hill" is a point (width its radius), "ridge" a
/// segment, "valley" a segment with height = −depth (docs/scene-format.md, "terrain").
struct TerrainFeature {
    glm::vec2 from{0.0f}; ///< segment start [x, z], metres (mesh space)
    glm::vec2 to{0.0f};   ///< segment end [x, z], metres; == from for a hill
    float height = 0.0f;  ///< metres added at the segment (negative digs a hollow or a valley)
    float width = 1.0f;   ///< metres, > 0: distance at which the bump has fallen to height / e
};

/// Fractal value noise added to a terrain: `octaves` layers of hashed lattice values, each with half
/// the wavelength and half the weight of the one before, normalised so that |noise| <= amplitude.
struct TerrainNoise {
    float amplitude = 1.0f;    ///< metres, >= 0: the largest the noise can add or remove
    float wavelength = 50.0f;  ///< metres, > 0: lattice spacing of the first octave
    std::uint32_t octaves = 4; ///< 1..16
    std::uint32_t seed = 0;    ///< any value; each gives a different landscape
};

/// A heightfield over x/z with +y up, centred at the origin of its mesh space.
struct TerrainDesc {
    glm::vec2 size{100.0f};               ///< [sx, sz] metres, > 0
    glm::uvec2 samples{100u};             ///< [nx, nz] grid quads per axis, >= 1
    float base = 0.0f;                    ///< metres: height where no feature or noise reaches
    std::vector<TerrainFeature> features; ///< summed onto the base
    std::optional<TerrainNoise> noise;    ///< none: a smooth terrain
};

/// Height (metres, y) of the terrain at mesh-space (x, z): base + Σ features + noise. Defined everywhere
/// (beyond `size` too); deterministic: the same arguments give the same value on every call.
double terrain_height(const TerrainDesc& terrain, double x, double z);

/// The terrain as (nx+1)·(nz+1) shared vertices on a regular grid from −size/2 to +size/2 (vertex
/// (i, j) at x = −sx/2 + sx·i/nx, z = −sz/2 + sz·j/nz, index j·(nx+1) + i, y = terrain_height) and
/// 2·nx·nz triangles wound so that their normals point up (+y). An open sheet, no skirt. Named
/// "terrain". `terrain` must be valid (sizes > 0, samples >= 1, widths > 0), as load_scene checks.
Mesh make_terrain_mesh(const TerrainDesc& terrain);

} // namespace gust
