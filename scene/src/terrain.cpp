// Generated heightfield terrain: Gaussian features along segments plus fractal value noise. The noise
// hashes integer lattice coordinates (no library random numbers, whose sequences differ between standard
// libraries), so a seed gives the same landscape everywhere.
#include "gust/scene/primitives.hpp"

#include <cassert>
#include <cmath>
#include <cstddef>

namespace gust {
namespace {

/// Distance in x/z from p to the segment [a, b] (to a when a == b).
double segment_distance(glm::dvec2 p, glm::dvec2 a, glm::dvec2 b) {
    const glm::dvec2 ab = b - a;
    const double length2 = glm::dot(ab, ab);
    const double s = length2 > 0.0 ? glm::clamp(glm::dot(p - a, ab) / length2, 0.0, 1.0) : 0.0;
    return glm::length(p - (a + s * ab));
}

/// A 32-bit integer hash of a lattice point and a seed (the "lowbias32" finaliser, Chris Wellons).
std::uint32_t hash(std::uint32_t x, std::uint32_t z, std::uint32_t seed) {
    std::uint32_t h = (x * 0x8da6b343u) ^ (z * 0xd8163841u) ^ (seed * 0xcb1ab31fu);
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

/// The lattice value at integer point (x, z), in [−1, 1). Lattice coordinates wrap at 2^32.
double lattice(std::int64_t x, std::int64_t z, std::uint32_t seed) {
    return double(hash(std::uint32_t(x), std::uint32_t(z), seed)) / 2147483648.0 - 1.0;
}

/// Value noise at (x, z) in lattice units: the four surrounding lattice values blended with the
/// smoothstep weight 3t² − 2t³. Within [−1, 1].
double value_noise(double x, double z, std::uint32_t seed) {
    const double fx = std::floor(x);
    const double fz = std::floor(z);
    const auto ix = static_cast<std::int64_t>(fx);
    const auto iz = static_cast<std::int64_t>(fz);
    const double tx = x - fx;
    const double tz = z - fz;
    const double sx = tx * tx * (3.0 - 2.0 * tx);
    const double sz = tz * tz * (3.0 - 2.0 * tz);
    const double v0 = lattice(ix, iz, seed) + sx * (lattice(ix + 1, iz, seed) - lattice(ix, iz, seed));
    const double v1 =
        lattice(ix, iz + 1, seed) + sx * (lattice(ix + 1, iz + 1, seed) - lattice(ix, iz + 1, seed));
    return v0 + sz * (v1 - v0);
}

double fractal_noise(const TerrainNoise& noise, double x, double z) {
    double sum = 0.0;
    double weights = 0.0;
    double weight = 1.0;
    double frequency = 1.0 / double(noise.wavelength);
    for (std::uint32_t octave = 0; octave < noise.octaves; ++octave) {
        sum += weight * value_noise(x * frequency, z * frequency, noise.seed + octave);
        weights += weight;
        weight *= 0.5;
        frequency *= 2.0;
    }
    return double(noise.amplitude) * sum / weights;
}

} // namespace

double terrain_height(const TerrainDesc& terrain, double x, double z) {
    double height = terrain.base;
    for (const TerrainFeature& feature : terrain.features) {
        const double d = segment_distance({x, z}, glm::dvec2(feature.from), glm::dvec2(feature.to)) /
                         double(feature.width);
        height += double(feature.height) * std::exp(-d * d);
    }
    if (terrain.noise) height += fractal_noise(*terrain.noise, x, z);
    return height;
}

Mesh make_terrain_mesh(const TerrainDesc& terrain) {
    assert(terrain.samples.x >= 1 && terrain.samples.y >= 1);
    assert(terrain.size.x > 0.0f && terrain.size.y > 0.0f);
    const std::size_t nx = terrain.samples.x;
    const std::size_t nz = terrain.samples.y;
    Mesh mesh;
    mesh.name = "terrain";
    mesh.positions.reserve((nx + 1) * (nz + 1));
    for (std::size_t j = 0; j <= nz; ++j) {
        const double z = double(terrain.size.y) * (double(j) / double(nz) - 0.5);
        for (std::size_t i = 0; i <= nx; ++i) {
            const double x = double(terrain.size.x) * (double(i) / double(nx) - 0.5);
            mesh.positions.emplace_back(float(x), float(terrain_height(terrain, x, z)), float(z));
        }
    }
    mesh.indices.reserve(6 * nx * nz);
    const auto row = static_cast<std::uint32_t>(nx + 1);
    for (std::uint32_t j = 0; j < nz; ++j) {
        for (std::uint32_t i = 0; i < nx; ++i) {
            const std::uint32_t v00 = j * row + i; // (x0, z0)
            const std::uint32_t v10 = v00 + 1;     // (x1, z0)
            const std::uint32_t v01 = v00 + row;   // (x0, z1)
            const std::uint32_t v11 = v01 + 1;     // (x1, z1)
            // (v01 − v00) × (v10 − v00) = (0, 0, dz) × (dx, 0, 0) = (0, dz·dx, 0): up.
            mesh.indices.insert(mesh.indices.end(), {v00, v01, v10, v10, v01, v11});
        }
    }
    return mesh;
}

} // namespace gust
