#version 460
#extension GL_GOOGLE_include_directive : require
// Per four faces (one word of open_counts): the open voxel pairs between the air of the cells on both
// sides (beyond the domain: all open), and the solid's normal velocity from the moving fragments of
// both cells (or the sealed region a cell without air lies in), over the share of the face's closed pairs
// that touch no static solid (moving_share); where one cell has no air, only the solid in the other's layer
// next to the face (layer_motion). The faces of a cell whose air crossed a moving wall (air_crossed) take
// that velocity as the air's too. When the fill found a cell with two parts of outside air (fill_finish.comp
// set SolverState::fluid_dispatch), also the pressure equation's own connectivity (link_fluid), which
// fluid_finish.comp then seals.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

/// The cell's kCell* flags, none beyond the domain.
uint flags_of(ivec3 c) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? flags_at(cell_index(n, c)) : 0u;
}

ivec4 motion_of(ivec3 c, uint flags) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? solid_motion_of(cell_index(n, c), flags) : ivec4(0);
}

CellBits static_at(ivec3 c, uint flags) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? static_of(cell_index(n, c), flags) : bits_none();
}

/// For a face between a cell with air and one without: the motion of the solid the air meets there. Where
/// the air reaches the face, that solid is the airless cell's layer next to it (solid_layer_motion); where it
/// does not, it is in the air's own cell (air_cell_motion). A static wall between the air and whatever moves
/// beyond it keeps the air still: a crate moving in a closed static building pushed the air outside through
/// a wall lying inside such a cell.

/// Cell i's solid in its voxel layer `layer`: its moving fragments where that holds moving voxels, else the
/// region of a sealed part in it, else none (static).
ivec4 solid_layer_motion(int i, uint flags, CellBits layer) {
    CellBits moving = bits_and_not(bits_and(solid_of(i, flags), layer), static_of(i, flags));
    if ((flags & kCellMoving) != 0u && bits_count(moving) != 0u) return IVec4Ref(hot.cell_motion).v[i];
    for (uint k = 0u; k < kCellParts; ++k)
        if (bits_count(bits_and(part_of(i, flags, k), layer)) != 0u)
            return region_of(LabelsRef(hot.labels).v[part_node(uint(i), k)]);
    return ivec4(0);
}

/// Cell i's solid as its air meets it, the face layer `layer` holding none of that air: its moving
/// fragments where its moving voxels touch its air, else the region of its sealed part in the layer, else
/// none (a static wall).
ivec4 air_cell_motion(int i, uint flags, CellBits layer, CellBits faces[6]) {
    uint air = (flags & kCellSecondPart) != 0u ? 1u : 0u;
    CellBits moving = bits_and_not(solid_of(i, flags), static_of(i, flags));
    CellBits reach = bits_dilate(part_of(i, flags, air), hot.voxels_per_cell, faces);
    if ((flags & kCellMoving) != 0u && bits_count(bits_and(reach, moving)) != 0u)
        return IVec4Ref(hot.cell_motion).v[i];
    if (bits_count(bits_and(part_of(i, flags, 1u - air), layer)) != 0u)
        return region_of(LabelsRef(hot.labels).v[part_node(uint(i), 1u - air)]);
    return ivec4(0);
}

CellBits air_at(ivec3 c, uint flags) {
    ivec3 n = hot.dims;
    return inside_cells(n, c) ? air_of(cell_index(n, c), flags) : bits_all(hot.voxels_per_cell);
}

/// The pressure equation's own connectivity across a face with open voxel pairs between lo and hi: a cell
/// with two parts of outside air stands for one of them in the pressure, so cells that reach an open side
/// only through its other part would form a pocket, a block of the equation with no open side, singular and
/// inconsistent wherever its divergence does not sum to zero. Unites the two cells' fluid nodes, or the
/// cell with the outside across an open domain side; fluid_finish.comp seals the cells left apart. (Open
/// pairs mean that no cell of the face is kCellNoAir.)
void link_fluid(ivec3 lo, ivec3 hi, uint axis) {
    ivec3 n = hot.dims;
    uint cells = uint(n.x * n.y * n.z);
    bool in_lo = inside_cells(n, lo), in_hi = inside_cells(n, hi);
    if (in_lo && in_hi)
        uf_unite(fluid_node(uint(cell_index(n, lo)), cells), fluid_node(uint(cell_index(n, hi)), cells));
    else if (in_hi && (hot.open_sides >> (2u * axis) & 1u) != 0u)
        uf_unite(fluid_node(uint(cell_index(n, hi)), cells), kOutsideNode);
    else if (in_lo && (hot.open_sides >> (2u * axis + 1u) & 1u) != 0u)
        uf_unite(fluid_node(uint(cell_index(n, lo)), cells), kOutsideNode);
}

void main() {
    load_bindings();
    int t = thread_index();
    ivec3 n = hot.dims;
    int total = faces_total(n);
    if (uint(t) >= open_count_words(uint(total))) return;
    uint v = hot.voxels_per_cell;
    bool fluid = state().s.fluid_dispatch.x != 0u;
    uint counts = 0u;
    // The face layers are loaded once, by the first face that compares voxel sets.
    CellBits faces[6];
    bool masks = false;
    for (int k = 0; k < 4 && 4 * t + k < total; ++k) {
        int i = 4 * t + k;
        uint axis;
        ivec3 f = face_from_index(n, i, axis);
        ivec3 lo = f - axis_unit(axis);
        uint flags_lo = flags_of(lo), flags_hi = flags_of(f);
        uint open = v * v;
        if (((flags_lo | flags_hi) & kCellNoAir) != 0u) {
            open = 0u;
        } else if (((flags_lo | flags_hi) & kCellCut) != 0u) {
            if (!masks) load_face_masks(faces);
            masks = true;
            open = face_open_count(air_at(lo, flags_lo), air_at(f, flags_hi), axis, v, faces);
        }
        counts |= open << (8 * k);
        if (fluid && open != 0u) link_fluid(lo, f, axis);
        // Where one cell has air and the other none, the solid that air meets is in its own cell's layer.
        bool air_lo = (flags_lo & kCellNoAir) == 0u, air_hi = (flags_hi & kCellNoAir) == 0u;
        ivec4 m;
        if (air_lo != air_hi) {
            if (!masks) load_face_masks(faces);
            masks = true;
            ivec3 ca = air_lo ? lo : f;
            int b = cell_index(n, air_lo ? f : lo);
            uint flags_a = air_lo ? flags_lo : flags_hi, flags_b = air_lo ? flags_hi : flags_lo;
            CellBits layer_a = faces[air_lo ? 2u * axis + 1u : 2u * axis];
            CellBits layer_b = faces[air_lo ? 2u * axis : 2u * axis + 1u];
            // Beyond the domain all is air, which reaches the face.
            bool reaches = !inside_cells(n, ca) ||
                           bits_count(bits_and(air_of(cell_index(n, ca), flags_a), layer_a)) != 0u;
            m = reaches ? solid_layer_motion(b, flags_b, layer_b)
                        : air_cell_motion(cell_index(n, ca), flags_a, layer_a, faces);
        } else {
            m = motion_of(lo, flags_lo) + motion_of(f, flags_hi);
        }
        float share = 1.0;
        if (m.w > 0 && ((flags_lo | flags_hi) & kCellStatic) != 0u) {
            if (!masks) load_face_masks(faces);
            masks = true;
            share = moving_share(v * v - open, face_any_count(static_at(lo, flags_lo), static_at(f, flags_hi), axis, v, faces));
        }
        float solid = m.w > 0 ? share * float(m[axis]) / (kVelocityScale * float(m.w)) : 0.0;
        FloatsRef(hot.solid_velocity).v[i] = solid;
        // A cell whose air crossed a moving wall: its faces held the other side's air, which advection
        // would carry on as this side's; they start from the wall's velocity.
        if (air_crossed(flags_lo) || air_crossed(flags_hi)) FloatsRef(face_field(kFieldVelocity)).v[i] = solid;
    }
    WordsRef(hot.open_counts).v[t] = counts;
}
