#include "solver_setup.hpp"

#include <algorithm>
#include <cmath>
#include <gust/solver/cpu_wind.hpp>

namespace gust {

namespace shaderio {

/// The kernels over host arrays: the accessors solver_kernels.h asks for, then the kernels themselves.
struct HostKernels {
    glm::ivec3 dims;
    float h = 1.0f;
    glm::vec3 origin{0.0f}, ambient{0.0f};
    uint open_sides = 0;
    std::vector<GridLevel> levels;
    std::vector<GpuEmitter> emitters; ///< omni first (omni_first)
    uint omni = 0;
    std::vector<float> face[kFaceFields]; ///< kField*
    std::vector<float> weights;
    std::vector<float> cell[kCellFields]; ///< kCell*
    std::vector<vec4> vorticity;
    std::vector<vec4> confinement;

    ivec3 grid_dims() const { return dims; }
    float grid_h() const { return h; }
    vec3 grid_origin() const { return origin; }
    vec3 grid_ambient() const { return ambient; }
    uint grid_open_sides() const { return open_sides; }
    float load_face(uint field, int index) const { return face[field][std::size_t(index)]; }
    float load_weight(int index) const { return weights[std::size_t(index)]; }
    float load_cell(uint field, int index) const { return cell[field][std::size_t(index)]; }
    vec4 load_vorticity(int index) const { return vorticity[std::size_t(index)]; }
    vec4 load_confinement(int index) const { return confinement[std::size_t(index)]; }
    float load_phi(int index) const { return cell[kCellPhi][std::size_t(index)]; }
    GridLevel load_level(uint l) const { return levels[l]; }
    uint emitter_count() const { return uint(emitters.size()); }
    uint omni_count() const { return omni; }
    GpuEmitter load_emitter(uint i) const { return emitters[i]; }

#include "solver/solver_kernels.h"
};

} // namespace shaderio

using shaderio::CellBits;
using shaderio::GridLevel;
using shaderio::kCellWords;

struct CpuWind::Impl {
    SolverDesc desc;
    shaderio::HostKernels k;
    std::vector<float> solid_fraction;
    std::vector<std::uint32_t> flags;      ///< shaderio::kCell*
    std::vector<CellBits> parts;           ///< kCellParts per cell
    std::vector<CellBits> fixed;           ///< per cell, its static solid voxels
    std::vector<glm::ivec4> motion;        ///< per cell, as cell_motion
    std::vector<std::uint32_t> roots;      ///< per part node: its set's root (the smallest node id)
    std::vector<glm::ivec4> region_motion; ///< two per root node, as region_motion
    std::uint32_t face_mask[6 * kCellWords];
    float last_dt = 0.0f;
    bool has_guess = false; ///< as WindSolver's: φ may start the next solve

    std::size_t faces() const { return std::size_t(shaderio::faces_total(k.dims)); }
    std::size_t cells() const { return std::size_t(k.dims.x) * k.dims.y * k.dims.z; }

    template <typename F> void each_face(F&& f) {
        for (int i = 0; i < int(faces()); ++i) {
            std::uint32_t axis;
            const glm::ivec3 at = shaderio::face_from_index(k.dims, i, axis);
            f(i, axis, at);
        }
    }
    template <typename F> void each_cell(const GridLevel& level, F&& f) {
        const int n = level.dims.x * level.dims.y * level.dims.z;
        for (int i = 0; i < n; ++i)
            f(i, shaderio::cell_from_index(level.dims, i));
    }

    void solid_pass(const CpuSolid* solid, WindStats& stats);
    /// The outside-air fill: roots per part node, and each cell's air (flags, solid fraction).
    void fill(std::uint32_t& sealed_cells);
    /// Seals the cells whose open faces reach no open side (pockets of the pressure equation).
    void seal_pockets(std::uint32_t& sealed_cells);
    CellBits part_of(std::size_t cell, std::uint32_t part) const;
    CellBits air_of(std::size_t cell) const;
    CellBits static_of(std::size_t cell) const;
    /// As solver_common.glsl's solid_of.
    CellBits solid_of(std::size_t cell) const;
    /// As fill_finish.comp's add_contacts.
    void add_contacts(std::size_t cell, std::uint32_t part, std::uint32_t root, CellBits faces[6]);
    /// As solver_common.glsl's region_of.
    glm::ivec4 region_of(std::uint32_t root) const;
    /// As solid_faces.comp's solid_layer_motion and air_cell_motion.
    glm::ivec4 solid_layer_motion(std::size_t i, const CellBits& layer) const;
    glm::ivec4 air_cell_motion(std::size_t i, const CellBits& layer, CellBits faces[6]) const;
    glm::ivec4 solid_motion_of(std::size_t cell) const;
    void extend();
    void coarse_weights();
    void smooth(std::uint32_t l);
    void v_cycle();
    float max_residual();
    float start_solve(bool warm);
    /// check.comp's test: within the tolerance, or diverged (solve_diverged); stops the solve either way.
    struct Check {
        float goal = 0.0f, first = 0.0f, b_max = 0.0f;
        bool diverged = false;
        bool done(float residual) {
            if (residual <= goal) return true;
            diverged = shaderio::solve_diverged(residual, first, b_max);
            return diverged;
        }
    };
    float conjugate_gradients(Check& check, float residual, bool& done, std::uint32_t& checks);
};

CpuWind::~CpuWind() = default;

Result<std::unique_ptr<CpuWind>> CpuWind::create(const SolverDesc& desc) {
    if (Status s = validate(desc); !s) return s;
    std::unique_ptr<CpuWind> wind(new CpuWind());
    wind->impl_ = std::make_unique<Impl>();
    Impl& m = *wind->impl_;
    m.desc = desc;
    m.k.dims = glm::ivec3(desc.cells);
    m.k.h = desc.cell_size;
    m.k.origin = desc.origin;
    const auto levels = detail::build_levels(desc.cells, desc.cell_size);
    m.k.levels.assign(levels.begin(), levels.end());
    const GridLevel& last = m.k.levels.back();
    const std::size_t all_cells = last.cells + std::size_t(last.dims.x) * last.dims.y * last.dims.z;
    const std::size_t all_faces = last.faces + std::size_t(shaderio::faces_total(last.dims));
    for (auto& f : m.k.face)
        f.assign(m.faces(), 0.0f);
    m.k.weights.assign(all_faces, 1.0f);
    for (auto& c : m.k.cell)
        c.assign(all_cells, 0.0f);
    m.k.vorticity.assign(m.cells(), glm::vec4(0.0f));
    m.k.confinement.assign(m.cells(), glm::vec4(0.0f));
    m.solid_fraction.assign(m.cells(), 0.0f);
    m.flags.assign(m.cells(), 0);
    m.parts.assign(m.cells() * shaderio::kCellParts, shaderio::bits_none());
    m.fixed.assign(m.cells(), shaderio::bits_none());
    m.motion.assign(m.cells(), glm::ivec4(0));
    m.roots.assign(1 + shaderio::kCellParts * m.cells(), 0);
    m.region_motion.assign(2 * m.roots.size(), glm::ivec4(0));
    detail::face_masks(desc.voxels_per_cell, m.face_mask);
    return wind;
}

Status CpuWind::set_ambient(glm::vec3 velocity) {
    if (Status s = detail::validate_ambient(velocity); !s) return s;
    impl_->k.ambient = velocity;
    if (impl_->last_dt == 0.0f) {
        const auto faces = detail::uniform_faces(impl_->k.dims, velocity);
        impl_->k.face[shaderio::kFieldVelocity].assign(faces.begin(), faces.end());
    }
    return Status{};
}

Status CpuWind::set_emitters(std::span<const Emitter> emitters) {
    if (Status s = validate(emitters); !s) return s;
    impl_->k.emitters.resize(emitters.size());
    impl_->k.omni = detail::omni_first(emitters, impl_->k.emitters);
    return Status{};
}

Status CpuWind::set_velocity(std::span<const float> faces) {
    if (faces.size() != impl_->faces()) return Status::failure("wrong number of face velocities");
    impl_->k.face[shaderio::kFieldVelocity].assign(faces.begin(), faces.end());
    impl_->has_guess = false;
    return Status{};
}

Status CpuWind::scroll(glm::ivec3 cells) {
    Impl& m = *impl_;
    std::vector<float> moved(m.faces());
    m.each_face([&](int i, std::uint32_t axis, glm::ivec3 f) {
        const glm::ivec3 src = f + cells;
        const glm::ivec3 lattice = m.k.dims + shaderio::axis_unit(axis);
        const bool inside =
            glm::all(glm::greaterThanEqual(src, glm::ivec3(0))) && glm::all(glm::lessThan(src, lattice));
        moved[std::size_t(i)] =
            inside ? m.k.face[0][std::size_t(shaderio::face_index(m.k.dims, axis, src))] : m.k.ambient[axis];
    });
    m.k.face[0] = std::move(moved);
    std::vector<float>& phi = m.k.cell[shaderio::kCellPhi];
    std::vector<float> shifted(m.cells());
    m.each_cell(m.k.levels[0], [&](int i, glm::ivec3 c) {
        const glm::ivec3 src = c + cells;
        shifted[std::size_t(i)] = shaderio::inside_cells(m.k.dims, src)
                                      ? phi[std::size_t(shaderio::cell_index(m.k.dims, src))]
                                      : 0.0f;
    });
    std::copy(shifted.begin(), shifted.end(), phi.begin());
    m.k.origin += glm::vec3(cells) * m.desc.cell_size;
    return Status{};
}

const std::vector<float>& CpuWind::velocity() const {
    return impl_->k.face[shaderio::kFieldVelocity];
}
const std::vector<float>& CpuWind::solid_velocity() const {
    return impl_->k.face[shaderio::kFieldSolid];
}
const std::vector<float>& CpuWind::solid_fraction() const {
    return impl_->solid_fraction;
}
const std::vector<float>& CpuWind::open_fraction() const {
    return impl_->k.weights;
}
std::vector<float> CpuWind::pressure() const {
    const float scale = impl_->last_dt > 0.0f ? detail::kAirDensity / impl_->last_dt : 0.0f;
    std::vector<float> p(impl_->k.cell[shaderio::kCellPhi].begin(),
                         impl_->k.cell[shaderio::kCellPhi].begin() + std::ptrdiff_t(impl_->cells()));
    for (float& v : p)
        v *= scale;
    return p;
}

CellBits CpuWind::Impl::part_of(std::size_t cell, std::uint32_t part) const {
    if ((flags[cell] & shaderio::kCellCut) == 0)
        return part == 0 ? shaderio::bits_all(desc.voxels_per_cell) : shaderio::bits_none();
    return parts[shaderio::kCellParts * cell + part];
}

CellBits CpuWind::Impl::air_of(std::size_t cell) const {
    if ((flags[cell] & shaderio::kCellNoAir) != 0) return shaderio::bits_none();
    return part_of(cell, (flags[cell] & shaderio::kCellSecondPart) != 0 ? 1 : 0);
}

CellBits CpuWind::Impl::solid_of(std::size_t cell) const {
    return shaderio::bits_and_not(
        shaderio::bits_and_not(shaderio::bits_all(desc.voxels_per_cell), part_of(cell, 0)), part_of(cell, 1));
}

CellBits CpuWind::Impl::static_of(std::size_t cell) const {
    return (flags[cell] & shaderio::kCellStatic) != 0 ? fixed[cell] : shaderio::bits_none();
}

glm::ivec4 CpuWind::Impl::region_of(std::uint32_t root) const {
    if (root == shaderio::kOutsideNode) return glm::ivec4(0);
    return shaderio::enclosing_motion(region_motion[2 * root], region_motion[2 * root + 1].x);
}

glm::ivec4 CpuWind::Impl::solid_motion_of(std::size_t cell) const {
    if ((flags[cell] & shaderio::kCellMoving) != 0) return motion[cell];
    if ((flags[cell] & shaderio::kCellNoAir) == 0) return glm::ivec4(0);
    return region_of(roots[shaderio::part_node(std::uint32_t(cell), 0)]);
}

glm::ivec4 CpuWind::Impl::solid_layer_motion(std::size_t i, const CellBits& layer) const {
    using namespace shaderio;
    const CellBits moving = bits_and_not(bits_and(solid_of(i), layer), static_of(i));
    if ((flags[i] & kCellMoving) != 0 && bits_count(moving) != 0) return motion[i];
    for (std::uint32_t part = 0; part < kCellParts; ++part)
        if (bits_count(bits_and(part_of(i, part), layer)) != 0)
            return region_of(roots[part_node(std::uint32_t(i), part)]);
    return glm::ivec4(0);
}

glm::ivec4 CpuWind::Impl::air_cell_motion(std::size_t i, const CellBits& layer, CellBits faces[6]) const {
    using namespace shaderio;
    const std::uint32_t air = (flags[i] & kCellSecondPart) != 0 ? 1 : 0;
    const CellBits moving = bits_and_not(solid_of(i), static_of(i));
    const CellBits reach = bits_dilate(part_of(i, air), desc.voxels_per_cell, faces);
    if ((flags[i] & kCellMoving) != 0 && bits_count(bits_and(reach, moving)) != 0) return motion[i];
    if (bits_count(bits_and(part_of(i, 1 - air), layer)) != 0)
        return region_of(roots[part_node(std::uint32_t(i), 1 - air)]);
    return glm::ivec4(0);
}

void CpuWind::Impl::add_contacts(std::size_t cell, std::uint32_t part, std::uint32_t root,
                                 CellBits faces[6]) {
    using namespace shaderio;
    const std::uint32_t v = desc.voxels_per_cell;
    const glm::ivec3 c = cell_from_index(k.dims, int(cell));
    const CellBits p = part_of(cell, part);
    glm::uvec2 touch[7];
    glm::ivec3 mean[7];
    std::uint32_t total = 0;
    for (std::uint32_t side = 0; side < 7; ++side) {
        touch[side] = glm::uvec2(0);
        mean[side] = glm::ivec3(0);
        const glm::ivec3 at = side == 6 ? c : c + ((side & 1) != 0 ? 1 : -1) * axis_unit(side / 2);
        if (!inside_cells(k.dims, at)) continue;
        const std::size_t j = std::size_t(cell_index(k.dims, at));
        if ((flags[j] & kCellCut) == 0) continue;
        touch[side] = part_contact(p, solid_of(j), static_of(j), side, v, faces);
        total += touch[side].x;
        if ((flags[j] & kCellMoving) == 0)
            touch[side].y = touch[side].x;
        else
            mean[side] = glm::ivec3(motion[j]) / motion[j].w;
    }
    if (total == 0) return;
    glm::ivec4 sum(0);
    for (std::uint32_t side = 0; side < 7; ++side) {
        const int quarters = int((4 * (touch[side].x - touch[side].y) + total / 2) / total);
        sum += glm::ivec4(mean[side] * quarters, quarters);
    }
    region_motion[2 * root] += sum;
    region_motion[2 * root + 1].x += 4;
}

// fill_link.comp and fill_finish.comp as a flood fill from the outside: the same sets, and the same roots,
// since the GPU's union-find hooks every root under the smaller one, so a set's root is its smallest node.
void CpuWind::Impl::fill(std::uint32_t& sealed_cells) {
    using namespace shaderio;
    const std::uint32_t v = desc.voxels_per_cell;
    CellBits layers[6];
    for (std::uint32_t s = 0; s < 6; ++s)
        std::copy(face_mask + s * kCellWords, face_mask + (s + 1) * kCellWords, layers[s].w);
    const std::size_t nodes = roots.size();
    std::vector<std::vector<std::uint32_t>> links(nodes);
    auto link = [&](std::uint32_t a, std::uint32_t b) {
        links[a].push_back(b);
        links[b].push_back(a);
    };
    each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        const std::size_t cell = std::size_t(i);
        for (std::uint32_t part = 0; part < kCellParts; ++part) {
            const CellBits p = part_of(cell, part);
            if (bits_count(p) == 0) continue;
            for (std::uint32_t s = 0; s < 6; ++s) {
                const int a = int(s / 2);
                const bool at_side = (s & 1) == 0 ? c[a] == 0 : c[a] == k.dims[a] - 1;
                if (at_side && (k.open_sides >> s & 1) != 0 && bits_touch(p, layers, s))
                    link(part_node(std::uint32_t(i), part), kOutsideNode);
            }
            for (std::uint32_t a = 0; a < 3; ++a) {
                const glm::ivec3 nb = c + axis_unit(a);
                if (!inside_cells(k.dims, nb)) continue;
                const std::size_t j = std::size_t(cell_index(k.dims, nb));
                for (std::uint32_t m = 0; m < kCellParts; ++m)
                    if (face_open_count(p, part_of(j, m), a, v, layers) != 0)
                        link(part_node(std::uint32_t(i), part), part_node(std::uint32_t(j), m));
            }
        }
    });
    std::vector<std::uint32_t> set(nodes, UINT32_MAX);
    for (std::uint32_t start = 0; start < nodes; ++start) {
        if (set[start] != UINT32_MAX) continue;
        std::vector<std::uint32_t> members{start};
        set[start] = start;
        for (std::size_t at = 0; at < members.size(); ++at)
            for (std::uint32_t next : links[members[at]])
                if (set[next] == UINT32_MAX) {
                    set[next] = start;
                    members.push_back(next);
                }
        for (std::uint32_t m : members)
            roots[m] = start;
    }
    sealed_cells = 0;
    std::fill(region_motion.begin(), region_motion.end(), glm::ivec4(0));
    each_cell(k.levels[0], [&](int i, glm::ivec3) {
        const std::size_t cell = std::size_t(i);
        std::uint32_t counts[2], r[2];
        for (std::uint32_t part = 0; part < kCellParts; ++part) {
            counts[part] = bits_count(part_of(cell, part));
            r[part] = roots[part_node(std::uint32_t(i), part)];
        }
        std::uint32_t air = 0;
        if (counts[0] != 0 && r[0] == kOutsideNode) {
            air = counts[0];
        } else if (counts[1] != 0 && r[1] == kOutsideNode) {
            air = counts[1];
            flags[cell] |= kCellSecondPart;
        } else {
            flags[cell] |= kCellNoAir;
            if (counts[0] != 0) ++sealed_cells;
        }
        solid_fraction[cell] = 1.0f - float(air) / float(v * v * v);
    });
    // After every cell's flags are set, as the GPU's atomics make no difference to the sums' order.
    each_cell(k.levels[0], [&](int i, glm::ivec3) {
        for (std::uint32_t part = 0; part < kCellParts; ++part) {
            const std::uint32_t root = roots[part_node(std::uint32_t(i), part)];
            if (bits_count(part_of(std::size_t(i), part)) != 0 && root != kOutsideNode)
                add_contacts(std::size_t(i), part, root, layers);
        }
    });
}

void CpuWind::Impl::solid_pass(const CpuSolid* solid, WindStats& stats) {
    using namespace shaderio;
    const std::uint32_t v = desc.voxels_per_cell;
    const glm::ivec3 voxels = k.dims * int(v);
    CellBits faces_layers[6];
    for (std::uint32_t s = 0; s < 6; ++s)
        std::copy(face_mask + s * kCellWords, face_mask + (s + 1) * kCellWords, faces_layers[s].w);
    std::fill(motion.begin(), motion.end(), glm::ivec4(0));
    stats.cut_cells = 0;
    each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        const std::size_t cell = std::size_t(i);
        flags[cell] = 0;
        if (!solid || solid->occupied.empty()) return;
        CellBits occupied = bits_none();
        fixed[cell] = bits_none();
        for (std::uint32_t z = 0; z < v; ++z)
            for (std::uint32_t y = 0; y < v; ++y)
                for (std::uint32_t x = 0; x < v; ++x) {
                    const glm::ivec3 p = c * int(v) + glm::ivec3(x, y, z);
                    const std::uint8_t here =
                        solid->occupied[std::size_t(p.x) +
                                        std::size_t(voxels.x) *
                                            (std::size_t(p.y) + std::size_t(voxels.y) * p.z)];
                    if (here == 0) continue;
                    const std::uint32_t j = x + v * (y + v * z);
                    occupied.w[j / 32] |= 1u << (j % 32);
                    if (here == CpuSolid::kStatic) fixed[cell].w[j / 32] |= 1u << (j % 32);
                }
        if (bits_count(occupied) == 0) return;
        cell_parts(occupied, v, faces_layers, parts[kCellParts * cell], parts[kCellParts * cell + 1]);
        flags[cell] = kCellCut | (bits_count(fixed[cell]) != 0 ? kCellStatic : 0u);
        ++stats.cut_cells;
    });
    if (solid)
        for (const auto& [voxel, velocity] : solid->fragments) {
            if (glm::any(glm::lessThan(voxel, glm::ivec3(0)))) continue;
            const glm::ivec3 c = voxel / int(v);
            if (!inside_cells(k.dims, c)) continue;
            const glm::ivec3 fixed_point(
                glm::round(clamp_speed(velocity, desc.max_solid_speed) * kVelocityScale));
            const std::size_t cell = std::size_t(cell_index(k.dims, c));
            motion[cell] += glm::ivec4(fixed_point, 1);
            flags[cell] |= kCellMoving;
        }
    fill(stats.sealed_cells);
    auto air_at = [&](glm::ivec3 c) {
        return inside_cells(k.dims, c) ? air_of(std::size_t(cell_index(k.dims, c))) : bits_all(v);
    };
    auto flags_at = [&](glm::ivec3 c) {
        return inside_cells(k.dims, c) ? flags[std::size_t(cell_index(k.dims, c))] : 0u;
    };
    auto motion_at = [&](glm::ivec3 c) {
        return inside_cells(k.dims, c) ? solid_motion_of(std::size_t(cell_index(k.dims, c))) : glm::ivec4(0);
    };
    auto static_at = [&](glm::ivec3 c) {
        return inside_cells(k.dims, c) ? static_of(std::size_t(cell_index(k.dims, c))) : bits_none();
    };
    each_face([&](int i, std::uint32_t axis, glm::ivec3 f) {
        const glm::ivec3 lo = f - axis_unit(axis);
        float open = 1.0f;
        if (((flags_at(lo) | flags_at(f)) & (kCellCut | kCellNoAir)) != 0)
            open = face_open_fraction(air_at(lo), air_at(f), axis, v, faces_layers);
        k.weights[std::size_t(i)] = open;
        const bool air_lo = (flags_at(lo) & kCellNoAir) == 0, air_hi = (flags_at(f) & kCellNoAir) == 0;
        glm::ivec4 m = motion_at(lo) + motion_at(f);
        if (air_lo != air_hi) {
            const glm::ivec3 ca = air_lo ? lo : f;
            const std::size_t b = std::size_t(cell_index(k.dims, air_lo ? f : lo));
            const CellBits& layer_a = faces_layers[air_lo ? 2 * axis + 1 : 2 * axis];
            const CellBits& layer_b = faces_layers[air_lo ? 2 * axis : 2 * axis + 1];
            const bool reaches = !inside_cells(k.dims, ca) || bits_count(bits_and(air_at(ca), layer_a)) != 0;
            m = reaches ? solid_layer_motion(b, layer_b)
                        : air_cell_motion(std::size_t(cell_index(k.dims, ca)), layer_a, faces_layers);
        }
        float share = 1.0f;
        if (m.w > 0 && ((flags_at(lo) | flags_at(f)) & kCellStatic) != 0) {
            const std::uint32_t closed =
                v * v - face_open_count(air_at(lo), air_at(f), axis, v, faces_layers);
            share = moving_share(closed, face_any_count(static_at(lo), static_at(f), axis, v, faces_layers));
        }
        k.face[kFieldSolid][std::size_t(i)] =
            m.w > 0 ? share * float(m[int(axis)]) / (kVelocityScale * float(m.w)) : 0.0f;
    });
    seal_pockets(stats.sealed_cells);
}

// fluid_link.comp and fluid_finish.comp as a flood fill from the open sides over open faces. The GPU runs
// them only when a cell has two parts of outside air, the only case that leaves such pockets, so running
// it always finds the same cells.
void CpuWind::Impl::seal_pockets(std::uint32_t& sealed_cells) {
    using namespace shaderio;
    const glm::ivec3 n = k.dims;
    auto open = [&](std::uint32_t axis, glm::ivec3 f) {
        return k.weights[std::size_t(face_index(n, axis, f))] > 0.0f;
    };
    auto has_air = [&](int i) { return (flags[std::size_t(i)] & kCellNoAir) == 0; };
    std::vector<std::uint8_t> reached(flags.size(), 0);
    std::vector<int> queue;
    each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        if (!has_air(i)) return;
        for (std::uint32_t a = 0; a < 3; ++a) {
            const glm::ivec3 high = c + axis_unit(a);
            if ((c[int(a)] == 0 && (k.open_sides >> (2 * a) & 1) != 0 && open(a, c)) ||
                (high[int(a)] == n[int(a)] && (k.open_sides >> (2 * a + 1) & 1) != 0 && open(a, high))) {
                reached[std::size_t(i)] = 1;
                queue.push_back(i);
                return;
            }
        }
    });
    for (std::size_t at = 0; at < queue.size(); ++at) {
        const glm::ivec3 c = cell_from_index(n, queue[at]);
        for (std::uint32_t a = 0; a < 3; ++a)
            for (int side = 0; side < 2; ++side) {
                const glm::ivec3 nb = c + (2 * side - 1) * axis_unit(a);
                if (!inside_cells(n, nb) || !open(a, side == 0 ? c : nb)) continue;
                const int j = cell_index(n, nb);
                if (reached[std::size_t(j)] || !has_air(j)) continue;
                reached[std::size_t(j)] = 1;
                queue.push_back(j);
            }
    }
    each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        if (!has_air(i) || reached[std::size_t(i)]) return;
        flags[std::size_t(i)] |= kCellNoAir;
        solid_fraction[std::size_t(i)] = 1.0f;
        for (std::uint32_t a = 0; a < 3; ++a)
            for (int side = 0; side < 2; ++side)
                k.weights[std::size_t(face_index(n, a, c + side * axis_unit(a)))] = 0.0f;
        ++sealed_cells;
    });
}

// extend.comp's two passes: velocity -> tmp (layer 1) -> velocity (layer 2).
void CpuWind::Impl::extend() {
    std::vector<float>& u = k.face[shaderio::kFieldVelocity];
    std::vector<float>& tmp = k.face[shaderio::kFieldTmp];
    each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        tmp[std::size_t(i)] = k.extend_face(shaderio::kFieldVelocity, a, f, 1);
    });
    each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        u[std::size_t(i)] = k.extend_face(shaderio::kFieldTmp, a, f, 2);
    });
}

void CpuWind::Impl::coarse_weights() {
    for (std::uint32_t l = 1; l < k.levels.size(); ++l) {
        const GridLevel& level = k.levels[l];
        for (int i = 0; i < shaderio::faces_total(level.dims); ++i) {
            std::uint32_t axis;
            const glm::ivec3 f = shaderio::face_from_index(level.dims, i, axis);
            k.weights[level.faces + std::size_t(i)] = k.coarse_weight(l, axis, f);
        }
    }
}

void CpuWind::Impl::smooth(std::uint32_t l) {
    const GridLevel& level = k.levels[l];
    for (std::uint32_t s = 0; s < desc.smoothing; ++s)
        for (std::uint32_t colour = 0; colour < 2; ++colour)
            each_cell(level, [&](int i, glm::ivec3 c) {
                if (std::uint32_t(c.x + c.y + c.z) % 2 != colour) return;
                k.cell[shaderio::kCellPressure][level.cells + std::size_t(i)] =
                    k.relax_cell(level, c, shaderio::kCellPressure);
            });
}

void CpuWind::Impl::v_cycle() {
    std::vector<float>& phi = k.cell[shaderio::kCellPressure];
    std::vector<float>& rhs = k.cell[shaderio::kCellRhs];
    const std::uint32_t levels = std::uint32_t(k.levels.size());
    for (std::uint32_t l = 0; l + 1 < levels; ++l) {
        smooth(l);
        const GridLevel& coarse = k.levels[l + 1];
        each_cell(coarse, [&](int i, glm::ivec3 c) {
            rhs[coarse.cells + std::size_t(i)] = k.restrict_cell(k.levels[l], c);
            phi[coarse.cells + std::size_t(i)] = 0.0f;
        });
    }
    const GridLevel& coarsest = k.levels[levels - 1];
    for (std::uint32_t sweep = 0; sweep < 2 * detail::kCoarseSweeps; ++sweep)
        each_cell(coarsest, [&](int i, glm::ivec3 c) {
            if (std::uint32_t(c.x + c.y + c.z) % 2 == sweep % 2)
                phi[coarsest.cells + std::size_t(i)] = k.relax_cell(coarsest, c, shaderio::kCellPressure);
        });
    for (std::uint32_t l = levels - 1; l-- > 0;) {
        const GridLevel& level = k.levels[l];
        std::vector<float> add(std::size_t(level.dims.x) * level.dims.y * level.dims.z);
        each_cell(level, [&](int i, glm::ivec3 c) {
            add[std::size_t(i)] = k.prolong_cell(level, k.levels[l + 1], c, shaderio::kCellPressure);
        });
        for (std::size_t i = 0; i < add.size(); ++i)
            phi[level.cells + i] += add[i];
        smooth(l);
    }
}

// start.comp's warm start over b in kCellTarget and the last step's φ (kCellPhi): x0 = s·φ (s fitted by
// warm_scale, 0 when not warm) and its residual r0 = b − s·Lφ, placed as the solver takes them (conjugate
// gradients: x0 in x, r0 in rhs, the V-cycle's φ = 0; otherwise x0 in the V-cycle's φ). Returns max |r0|.
float CpuWind::Impl::start_solve(bool warm) {
    using namespace shaderio;
    std::vector<float>& phi = k.cell[kCellPressure];
    const std::vector<float>& last = k.cell[kCellPhi];
    std::vector<float>& q = k.cell[kCellScratch];
    const std::vector<float>& b = k.cell[kCellTarget];
    float s = 0.0f;
    if (warm) {
        double bq = 0.0, qq = 0.0;
        each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            const float lap = k.laplacian_cell(k.levels[0], c, kCellPhi);
            q[std::size_t(i)] = lap;
            bq += double(b[std::size_t(i)]) * lap;
            qq += double(lap) * lap;
        });
        s = warm_scale(float(bq), float(qq));
    }
    const bool pcg = desc.pressure == PressureSolver::MultigridPCG;
    float worst = 0.0f;
    for (std::size_t i = 0; i < cells(); ++i) {
        const float x0 = s != 0.0f ? s * last[i] : 0.0f;
        const float r0 = s != 0.0f ? b[i] - s * q[i] : b[i];
        if (pcg) {
            k.cell[kCellSolution][i] = x0;
            k.cell[kCellRhs][i] = r0;
            phi[i] = 0.0f;
        } else {
            phi[i] = x0;
        }
        worst = std::max(worst, std::abs(r0));
    }
    return worst;
}

// The GPU's passes in the GPU's order (wind_solver.cpp), with the dot products summed in double, from
// x, r, b as start_solve left them. The residual is recomputed from x each iteration rather than updated:
// the update drifts from b − Lx in float by more than the tolerance.
float CpuWind::Impl::conjugate_gradients(Check& check, float residual, bool& done, std::uint32_t& checks) {
    using namespace shaderio;
    std::vector<float>& z = k.cell[kCellPressure];
    std::vector<float>& r = k.cell[kCellRhs];
    std::vector<float>& x = k.cell[kCellSolution];
    std::vector<float>& p = k.cell[kCellDirection];
    std::vector<float>& b = k.cell[kCellTarget];
    std::vector<float>& old_r = k.cell[kCellOldResidual];
    const std::size_t n = cells();
    std::fill_n(p.begin(), n, 0.0f);
    std::fill_n(old_r.begin(), n, 0.0f);
    float old_rz = 0.0f;
    for (std::uint32_t it = 0; it < desc.max_cycles && !done; ++it) {
        v_cycle();
        double rz = 0.0, z_old_r = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            rz += double(r[i]) * z[i];
            z_old_r += double(old_r[i]) * z[i];
        }
        const float beta = cg_beta(float(rz), float(z_old_r), old_rz);
        old_rz = float(rz);
        for (std::size_t i = 0; i < n; ++i)
            p[i] = z[i] + beta * p[i];
        double pq = 0.0;
        each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            pq += double(p[std::size_t(i)]) * k.laplacian_cell(k.levels[0], c, kCellDirection);
        });
        const float alpha = cg_alpha(old_rz, float(pq));
        for (std::size_t i = 0; i < n; ++i) {
            x[i] += alpha * p[i];
            old_r[i] = r[i];
            z[i] = 0.0f;
        }
        residual = 0.0f;
        each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            r[std::size_t(i)] = b[std::size_t(i)] - k.laplacian_cell(k.levels[0], c, kCellSolution);
            residual = std::max(residual, std::abs(r[std::size_t(i)]));
        });
        done = check.done(residual);
        if (!done) ++checks;
    }
    std::copy_n(x.begin(), n, z.begin());
    return residual;
}

float CpuWind::Impl::max_residual() {
    float worst = 0.0f;
    each_cell(k.levels[0],
              [&](int, glm::ivec3 c) { worst = std::max(worst, std::abs(k.residual_cell(k.levels[0], c))); });
    return worst;
}

Result<WindStats> CpuWind::step(float dt, const CpuSolid* solid) {
    if (Status s = detail::validate_dt(dt); !s) return s;
    Impl& m = *impl_;
    auto& k = m.k;
    const SolverDesc& desc = m.desc;
    k.open_sides = shaderio::open_sides_for(k.ambient);
    if (solid) {
        const glm::ivec3 voxels = k.dims * int(desc.voxels_per_cell);
        if (!solid->occupied.empty() && solid->occupied.size() != std::size_t(voxels.x) * voxels.y * voxels.z)
            return Status::failure("CpuSolid::occupied must hold one byte per voxel of the grid");
    }
    WindStats stats;
    // solid_cells.comp also makes each cell's confinement force and speed from the field the step starts
    // with.
    if (desc.vorticity != 0.0f)
        m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
            k.confinement[std::size_t(i)] = k.cell_confinement(c, desc.vorticity);
        });
    m.solid_pass(solid, stats);
    if (solid) stats.moving_fragments = std::uint32_t(solid->fragments.size());
    m.coarse_weights();

    std::vector<float>& u = k.face[shaderio::kFieldVelocity];
    std::vector<float>& tmp = k.face[shaderio::kFieldTmp];
    std::vector<float>& back = k.face[shaderio::kFieldBack];
    if (desc.advection != Advection::None) {
        if (desc.advection == Advection::MacCormack) {
            std::vector<float>& low = k.face[shaderio::kFieldLow];
            std::vector<float>& high = k.face[shaderio::kFieldHigh];
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                glm::vec2 range;
                tmp[std::size_t(i)] = k.advect_face_range(a, f, dt, range);
                low[std::size_t(i)] = range.x;
                high[std::size_t(i)] = range.y;
            });
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                back[std::size_t(i)] = k.advect_face(shaderio::kFieldTmp, a, f, -dt);
            });
            std::vector<float> out(m.faces());
            m.each_face(
                [&](int i, std::uint32_t a, glm::ivec3 f) { out[std::size_t(i)] = k.maccormack_face(a, f); });
            tmp = std::move(out);
        } else {
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                tmp[std::size_t(i)] = k.advect_face(shaderio::kFieldVelocity, a, f, dt);
            });
        }
    }
    // advect.comp's one pass: the advected value (tmp; the velocity itself without advection) with the
    // emitters, the ambient wind and confinement from the vorticity the last step ended with, while the
    // velocity still holds the old field (which confinement's step limit reads).
    const std::vector<float>& advected = desc.advection != Advection::None ? tmp : u;
    const float rate = detail::emitter_rate(dt, desc.emitter_response);
    std::vector<float> forced(m.faces());
    m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        forced[std::size_t(i)] = k.forced_face(advected[std::size_t(i)], a, f, rate, dt, desc.vorticity);
    });
    u = std::move(forced);
    if (desc.viscosity > 0.0f) {
        const float alpha = desc.viscosity * dt / (desc.cell_size * desc.cell_size);
        std::uint32_t from = shaderio::kFieldVelocity;
        for (std::uint32_t it = 0; it < detail::kViscosityIterations; ++it) {
            const std::uint32_t to = shaderio::diffuse_target(from);
            m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
                k.face[to][std::size_t(i)] = k.diffuse_face(from, a, f, alpha);
            });
            from = to;
        }
        u = k.face[from];
    }

    // Projection, in the GPU's order of passes and checks. φ still holds the last step's solution.
    std::vector<float>& phi = k.cell[shaderio::kCellPressure];
    std::vector<float>& rhs = k.cell[shaderio::kCellRhs];
    float before = 0.0f;
    m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        float diag, off;
        k.cell_operator(k.levels[0], c, shaderio::kCellPressure, 0.0f, diag, off);
        const float d = diag > 0.0f ? k.cell_divergence(c) : 0.0f;
        rhs[std::size_t(i)] = d;
        k.cell[shaderio::kCellTarget][std::size_t(i)] = d;
        before = std::max(before, std::abs(d));
        if (diag > 0.0f) ++stats.fluid_cells;
    });
    // The goal is relative to b, not to the first residual: a warm start that begins near the solution
    // must still reach tolerance · max |b|.
    // The Jacobi baseline starts from zero, as jacobi.comp does.
    const bool jacobi = desc.pressure == PressureSolver::Jacobi;
    float residual = m.start_solve(desc.warm_start && m.has_guess && !jacobi);
    Impl::Check check{desc.tolerance * before, residual, before};
    std::uint32_t checks = 0;
    bool done = check.done(residual);
    if (!done) ++checks;
    if (desc.pressure == PressureSolver::Multigrid) {
        for (std::uint32_t cycle = 0; cycle < desc.max_cycles && !done; ++cycle) {
            m.v_cycle();
            residual = m.max_residual();
            done = check.done(residual);
            if (!done) ++checks;
        }
        stats.cycles = std::min(checks, desc.max_cycles);
    } else if (desc.pressure == PressureSolver::MultigridPCG) {
        residual = m.conjugate_gradients(check, residual, done, checks);
        stats.cycles = std::min(checks, desc.max_cycles);
    } else {
        std::vector<float>& other = k.cell[shaderio::kCellSolutionB];
        std::vector<float> next(m.cells());
        const std::uint32_t blocks = (desc.max_iterations + detail::kJacobiBlock - 1) / detail::kJacobiBlock;
        for (std::uint32_t block = 0; block < blocks && !done; ++block) {
            for (std::uint32_t it = 0; it < detail::kJacobiBlock; ++it) {
                const std::uint32_t from = (it & 1) ? shaderio::kCellSolutionB : shaderio::kCellPressure;
                std::vector<float>& to = (it & 1) ? phi : other;
                m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
                    next[std::size_t(i)] = k.jacobi_cell(k.levels[0], c, from);
                });
                std::copy(next.begin(), next.end(), to.begin());
            }
            residual = m.max_residual();
            done = check.done(residual);
            if (!done) ++checks;
        }
        stats.cycles = std::min(checks, blocks) * detail::kJacobiBlock;
    }
    stats.diverged = check.diverged;
    stats.divergence_before = before;
    // finish.comp's φ (kCellPhi, 0 after a diverged solve), which the projection reads.
    std::vector<float>& result = k.cell[shaderio::kCellPhi];
    for (std::size_t i = 0; i < m.cells(); ++i)
        result[i] = check.diverged ? 0.0f : phi[i];
    std::vector<float> projected(m.faces());
    m.each_face([&](int i, std::uint32_t a, glm::ivec3 f) {
        projected[std::size_t(i)] = k.project_face(a, f, !check.diverged);
    });
    u = std::move(projected);
    m.extend();
    // finish.comp: the final residual and divergence, and the vorticity the next step's confinement reads.
    float after = 0.0f, left = 0.0f;
    m.each_cell(k.levels[0], [&](int i, glm::ivec3 c) {
        float diag, lap;
        k.cell_operator(k.levels[0], c, shaderio::kCellPhi, result[std::size_t(i)], diag, lap);
        if (diag > 0.0f) {
            after = std::max(after, std::abs(k.cell_divergence(c)));
            left = std::max(left, std::abs(k.cell[shaderio::kCellTarget][std::size_t(i)] - lap));
        }
        k.vorticity[std::size_t(i)] = k.cell_vorticity(c);
    });
    stats.divergence_after = after;
    stats.residual = left;
    stats.converged = !check.diverged && left <= desc.tolerance * before;
    m.last_dt = dt;
    m.has_guess = true;
    return stats;
}

} // namespace gust
