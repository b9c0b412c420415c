// CpuWind's solid boundary, as solid_cells.comp to fluid_finish.comp: each cell's parts, the outside-air
// fill, the faces' open fractions and solid velocities, and the pockets the pressure equation seals.
#include "cpu_wind_impl.hpp"

#include <algorithm>
#include <cmath>

namespace gust {

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
        solid_fraction[cell] = solid_fraction_of(air, v, voxel_share(v));
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
        const bool had_air = (flags[cell] & kCellNoAir) == 0;
        const CellBits before = had_air ? air_of(cell) : bits_none();
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
        for (std::uint32_t part = 0; had_air && part < kCellParts; ++part)
            if (part_crossed(parts[kCellParts * cell + part], before)) flags[cell] |= kCellCrossed << part;
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
        if (air_crossed(flags_at(lo)) || air_crossed(flags_at(f)))
            k.face[kFieldVelocity][std::size_t(i)] = k.face[kFieldSolid][std::size_t(i)];
    });
    seal_pockets(stats.sealed_cells);
}

// solid_faces.comp's link_fluid and fluid_finish.comp as a flood fill from the open sides over open faces.
// The GPU runs them only when a cell has two parts of outside air, the only case that leaves such pockets, so
// running it always finds the same cells.
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

} // namespace gust
