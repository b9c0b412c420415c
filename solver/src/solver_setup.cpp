#include "solver_setup.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace gust {

using shaderio::GridLevel;
using shaderio::kCellWords;

namespace detail {

// The coarsest level is at most 4 cells per axis (grids are at most 256 per axis, so the level cap is
// never what stops the halving), and coarse_solve.comp holds it in one workgroup, a thread per cell.
static_assert(4 * 4 * 4 <= shaderio::kSolverGroupSize, "coarse_solve.comp needs a thread per coarsest cell");
static_assert(256 >> (shaderio::kMaxGridLevels - 1) <= 4, "the level cap must not stop the halving early");

std::uint32_t cycles_to_record(const WindStats& last, std::uint32_t max_cycles) {
    const std::uint32_t wanted =
        last.converged ? last.cycles + std::max(8u, last.cycles / 2) : 2 * std::max(last.cycles_recorded, 1u);
    return std::min(wanted, max_cycles);
}

std::pmr::vector<GridLevel> build_levels(glm::uvec3 cells, float cell_size,
                                         std::pmr::memory_resource* memory) {
    std::pmr::vector<GridLevel> levels(memory);
    glm::ivec3 dims(cells);
    glm::vec3 h(cell_size);
    std::uint32_t cell_offset = 0, face_offset = 0;
    for (;;) {
        GridLevel level{};
        level.dims = dims;
        level.cells = cell_offset;
        level.faces = face_offset;
        level.inv_h2 = 1.0f / (h * h);
        level.factor = glm::ivec3(1);
        cell_offset += std::uint32_t(dims.x * dims.y * dims.z);
        face_offset += std::uint32_t(shaderio::faces_total(dims));
        const bool last =
            std::max({dims.x, dims.y, dims.z}) <= 4 || levels.size() + 1 == shaderio::kMaxGridLevels;
        if (!last) {
            for (int a = 0; a < 3; ++a)
                if (dims[a] > 1) {
                    level.factor[a] = 2;
                    dims[a] = (dims[a] + 1) / 2;
                    h[a] *= 2.0f;
                }
        }
        levels.push_back(level);
        if (last) break;
    }
    return levels;
}

void face_masks(std::uint32_t v, std::uint32_t* out) {
    for (std::uint32_t s = 0; s < 6; ++s) {
        const shaderio::CellBits layer = shaderio::bits_layer(s / 2, (s & 1) == 0 ? 0 : v - 1, v);
        std::copy(layer.w, layer.w + kCellWords, out + s * kCellWords);
    }
}

std::uint32_t cell_words(std::uint32_t v) {
    return (v * v * v + 31) / 32;
}

std::uint32_t omni_first(std::span<const Emitter> emitters, std::span<shaderio::GpuEmitter> out) {
    std::uint32_t omni = 0;
    for (const Emitter& e : emitters)
        if (e.type == EmitterType::Omni) out[omni++] = to_gpu(e);
    std::uint32_t next = omni;
    for (const Emitter& e : emitters)
        if (e.type != EmitterType::Omni) out[next++] = to_gpu(e);
    return omni;
}

shaderio::GpuEmitter to_gpu(const Emitter& e) {
    shaderio::GpuEmitter g{};
    g.position = e.position;
    g.direction = e.direction;
    g.radius = e.radius;
    g.strength = e.strength;
    g.falloff = e.falloff;
    g.extent = e.length;
    switch (e.type) {
    case EmitterType::Directional:
        g.type = shaderio::kEmitterDirectional;
        break;
    case EmitterType::Omni:
        g.type = shaderio::kEmitterOmni;
        break;
    case EmitterType::Vortex:
        g.type = shaderio::kEmitterVortex;
        break;
    case EmitterType::CapsuleMotor:
        g.type = shaderio::kEmitterCapsule;
        break;
    case EmitterType::ConeMotor:
        g.type = shaderio::kEmitterCone;
        break;
    }
    return g;
}

float emitter_rate(float dt, float response) {
    return 1.0f - std::exp(-dt / response);
}

Status validate_dt(float dt) {
    if (!std::isfinite(dt) || !(dt > 0.0f) || dt > kMaxStep)
        return Status::failure("dt must be a finite number of seconds in (0, " + std::to_string(kMaxStep) +
                               "], got " + std::to_string(dt));
    return Status{};
}

Status validate_ambient(glm::vec3 velocity) {
    if (!std::isfinite(velocity.x) || !std::isfinite(velocity.y) || !std::isfinite(velocity.z))
        return Status::failure("ambient wind must be finite");
    if (glm::length(velocity) > kMaxAmbientSpeed)
        return Status::failure("ambient wind must be below 10000 m/s");
    return Status{};
}

std::pmr::vector<float> uniform_faces(glm::ivec3 cells, glm::vec3 velocity,
                                      std::pmr::memory_resource* memory) {
    std::pmr::vector<float> out(std::size_t(shaderio::faces_total(cells)), memory);
    for (int i = 0; i < int(out.size()); ++i) {
        std::uint32_t axis;
        shaderio::face_from_index(cells, i, axis);
        out[std::size_t(i)] = velocity[int(axis)];
    }
    return out;
}

} // namespace detail

namespace {
bool finite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
} // namespace

Result<GridDesc> voxel_grid(const SolverDesc& desc, std::uint32_t branching) {
    if (branching != 2 && branching != 4 && branching != 8)
        return Result<GridDesc>::failure("branching must be 2, 4 or 8, got " + std::to_string(branching));
    const std::uint32_t longest = std::max({desc.cells.x, desc.cells.y, desc.cells.z}) * desc.voxels_per_cell;
    std::uint32_t res = 1;
    while (res < longest || res < kMinRes) {
        res *= branching;
        if (res > kMaxRes)
            return Result<GridDesc>::failure("the domain needs " + std::to_string(longest) +
                                             " voxels along its longest axis; with branching " +
                                             std::to_string(branching) + " the tree would exceed " +
                                             std::to_string(kMaxRes) + " per axis");
    }
    GridDesc grid;
    grid.res = res;
    grid.voxel_size = desc.cell_size / float(desc.voxels_per_cell);
    grid.origin = desc.origin;
    // Only what the wind reads: the domain's voxels, not the rest of the power-of-b grid.
    grid.keep = desc.cells * desc.voxels_per_cell;
    return grid;
}

SolidSource solid_source(const VoxelWorld& world) {
    SolidSource s;
    s.tree = &world.tree();
    s.static_generation = world.static_generation();
    const Voxelizer& moving = world.dynamic_voxelizer();
    if (moving.velocity_buffer()) {
        s.fragments = moving.fragment_buffer().address();
        s.fragment_count = moving.fragment_count_address();
        s.fragment_velocities = moving.velocity_buffer().address();
        s.fragment_capacity = moving.fragment_capacity();
    }
    return s;
}

Status validate(const SolverDesc& desc) {
    for (int a = 0; a < 3; ++a)
        if (desc.cells[a] < 8 || desc.cells[a] > 256)
            return Status::failure("wind cells per axis must be in 8..256, got " +
                                   std::to_string(desc.cells.x) + " x " + std::to_string(desc.cells.y) +
                                   " x " + std::to_string(desc.cells.z));
    if (!std::isfinite(desc.cell_size) || !(desc.cell_size > 0.0f))
        return Status::failure("cell_size must be a positive number of metres");
    if (!finite(desc.origin)) return Status::failure("origin must be finite");
    if (desc.voxels_per_cell < 1 || desc.voxels_per_cell > shaderio::kMaxVoxelsPerCell)
        return Status::failure("voxels_per_cell must be in 1..8, got " +
                               std::to_string(desc.voxels_per_cell));
    if (!std::isfinite(desc.tolerance) || !(desc.tolerance > 0.0f) || desc.tolerance >= 1.0f)
        return Status::failure("tolerance must be in (0, 1)");
    if (desc.max_cycles < 1 || desc.max_cycles > 1000)
        return Status::failure("max_cycles must be in 1..1000");
    if (desc.cycles_per_step > 1000) return Status::failure("cycles_per_step must be in 0..1000");
    if (desc.max_iterations < 1 || desc.max_iterations > 1000000)
        return Status::failure("max_iterations must be in 1..1000000");
    if (desc.smoothing < 1 || desc.smoothing > 16) return Status::failure("smoothing must be in 1..16");
    if (!std::isfinite(desc.vorticity) || desc.vorticity < 0.0f || desc.vorticity > 10.0f)
        return Status::failure("vorticity must be in [0, 10]");
    if (!std::isfinite(desc.viscosity) || desc.viscosity < 0.0f)
        return Status::failure("viscosity must be a non-negative number of m^2/s");
    if (!std::isfinite(desc.emitter_response) || !(desc.emitter_response > 0.0f))
        return Status::failure("emitter_response must be a positive number of seconds");
    if (!std::isfinite(desc.max_solid_speed) || !(desc.max_solid_speed > 0.0f) ||
        desc.max_solid_speed > shaderio::kMaxFragmentSpeed)
        return Status::failure("max_solid_speed must be in (0, 256] m/s");
    return Status{};
}

Status validate(std::span<const Emitter> emitters) {
    static_assert(kMaxEmitterCount == shaderio::kMaxEmitters);
    if (emitters.size() > kMaxEmitterCount)
        return Status::failure("at most " + std::to_string(kMaxEmitterCount) + " emitters, got " +
                               std::to_string(emitters.size()));
    for (std::size_t i = 0; i < emitters.size(); ++i) {
        const Emitter& e = emitters[i];
        const std::string at = "emitter " + std::to_string(i) + ": ";
        if (!finite(e.position)) return Status::failure(at + "position must be finite");
        if (!finite(e.direction) || std::abs(glm::length(e.direction) - 1.0f) > 1e-3f)
            return Status::failure(at + "direction must be a finite unit vector");
        if (!std::isfinite(e.radius) || !(e.radius > 0.0f))
            return Status::failure(at + "radius must be finite and > 0");
        if (!std::isfinite(e.strength) || std::abs(e.strength) > kMaxEmitterStrength)
            return Status::failure(at + "strength must be finite, within ±" +
                                   std::to_string(int(kMaxEmitterStrength)) + " m/s");
        if (!std::isfinite(e.falloff) || e.falloff < 0.0f || e.falloff > kMaxEmitterFalloff)
            return Status::failure(at + "falloff must be finite, in [0, " +
                                   std::to_string(int(kMaxEmitterFalloff)) + "]");
        if (!std::isfinite(e.length) || e.length < 0.0f)
            return Status::failure(at + "length must be finite and >= 0");
        const bool motor = e.type == EmitterType::CapsuleMotor || e.type == EmitterType::ConeMotor;
        if (e.type == EmitterType::ConeMotor && !(e.length > 0.0f))
            return Status::failure(at + "a cone motor needs a length > 0");
        if (!motor && e.length != 0.0f) return Status::failure(at + "only motors have a length");
    }
    return Status{};
}

} // namespace gust
