// A cell's voxel sets, shared by the solver's shaders and solver/ (written in the GLSL/GLM common subset,
// shaders/common.h): set operations, a cell's parts (its air), and the voxel pairs open across a face.
#ifndef GUST_SOLVER_CELLS_H
#define GUST_SOLVER_CELLS_H

#include "solver_io.h"

GUST_NAMESPACE_BEGIN

// ---- Cell voxel sets (a cell's voxels, bit x + v·(y + v·z) for v voxels per cell) ---------------------

struct CellBits {
    uint w[kBitsWords];
};

GUST_INLINE CellBits bits_none() {
    CellBits r;
    for (uint i = 0u; i < kBitsWords; ++i)
        r.w[i] = 0u;
    return r;
}

/// Every voxel of a cell of v^3 voxels.
GUST_INLINE CellBits bits_all(uint v) {
    CellBits r = bits_none();
    uint n = v * v * v;
    for (uint i = 0u; i < kBitsWords; ++i) {
        uint lo = i * 32u;
        if (n >= lo + 32u)
            r.w[i] = 0xffffffffu;
        else if (n > lo)
            r.w[i] = (1u << (n - lo)) - 1u;
    }
    return r;
}

GUST_INLINE bool bits_get(CellBits b, uint i) {
    return (b.w[i / 32u] >> (i % 32u) & 1u) != 0u;
}

GUST_INLINE uint bits_count(CellBits b) {
    uint c = 0u;
    for (uint i = 0u; i < kBitsWords; ++i)
        c += uint(bitCount(b.w[i]));
    return c;
}

GUST_INLINE bool bits_equal(CellBits a, CellBits b) {
    bool same = true;
    for (uint i = 0u; i < kBitsWords; ++i)
        same = same && a.w[i] == b.w[i];
    return same;
}

GUST_INLINE CellBits bits_and(CellBits a, CellBits b) {
    for (uint i = 0u; i < kBitsWords; ++i)
        a.w[i] &= b.w[i];
    return a;
}

GUST_INLINE CellBits bits_and_not(CellBits a, CellBits b) {
    for (uint i = 0u; i < kBitsWords; ++i)
        a.w[i] &= ~b.w[i];
    return a;
}

GUST_INLINE CellBits bits_or(CellBits a, CellBits b) {
    for (uint i = 0u; i < kBitsWords; ++i)
        a.w[i] |= b.w[i];
    return a;
}

/// Bits moved up by s positions (towards higher indices).
GUST_INLINE CellBits bits_up(CellBits a, uint s) {
    CellBits r = bits_none();
    uint words = s / 32u, bits = s % 32u;
    for (uint i = kBitsWords; i-- > words;) {
        uint j = i - words;
        r.w[i] = a.w[j] << bits;
        if (bits != 0u && j > 0u) r.w[i] |= a.w[j - 1u] >> (32u - bits);
    }
    return r;
}

/// Bits moved down by s positions.
GUST_INLINE CellBits bits_down(CellBits a, uint s) {
    CellBits r = bits_none();
    uint words = s / 32u, bits = s % 32u;
    for (uint i = 0u; i + words < kBitsWords; ++i) {
        uint j = i + words;
        r.w[i] = a.w[j] >> bits;
        if (bits != 0u && j + 1u < kBitsWords) r.w[i] |= a.w[j + 1u] << (32u - bits);
    }
    return r;
}

/// The voxels of a cell (v per axis) whose coordinate along `axis` equals `layer`.
GUST_INLINE CellBits bits_layer(uint axis, uint layer, uint v) {
    CellBits r = bits_none();
    for (uint z = 0u; z < v; ++z)
        for (uint y = 0u; y < v; ++y)
            for (uint x = 0u; x < v; ++x) {
                uint c = axis == 0u ? x : (axis == 1u ? y : z);
                if (c != layer) continue;
                uint i = x + v * (y + v * z);
                r.w[i / 32u] |= 1u << (i % 32u);
            }
    return r;
}

/// `set` grown by one voxel across each face (6-connectivity), kept inside the cell. `faces` are
/// bits_layer(axis, 0 or v-1) for −x,+x,−y,+y,−z,+z.
GUST_INLINE CellBits bits_dilate(CellBits set, uint v, CellBits faces[6]) {
    CellBits r = set;
    uint stride = 1u;
    for (uint a = 0u; a < 3u; ++a) {
        r = bits_or(r, bits_up(bits_and_not(set, faces[2u * a + 1u]), stride));
        r = bits_or(r, bits_down(bits_and_not(set, faces[2u * a]), stride));
        stride *= v;
    }
    return r;
}

/// Keeps `component` (of `count` voxels) if it is among the two largest seen: `first` the largest, `second`
/// the next (the earlier one wins a tie). The four are read as well as written: `inout`, since a GLSL `out`
/// parameter starts undefined (C++ references hid that; an NVIDIA GPU then sealed cells at random).
GUST_INLINE void keep_largest(CellBits component, uint count, GUST_INOUT(CellBits) first,
                              GUST_INOUT(uint) first_count, GUST_INOUT(CellBits) second,
                              GUST_INOUT(uint) second_count) {
    if (count > first_count) {
        second = first;
        second_count = first_count;
        first = component;
        first_count = count;
    } else if (count > second_count) {
        second = component;
        second_count = count;
    }
}

/// cell_parts for any v: the flood fill on whole CellBits.
GUST_INLINE void cell_parts_general(CellBits occupied, uint v, CellBits faces[6], GUST_OUT(CellBits) first,
                                    GUST_OUT(CellBits) second) {
    CellBits free_voxels = bits_and_not(bits_all(v), occupied);
    CellBits remaining = free_voxels;
    first = bits_none();
    second = bits_none();
    uint first_count = 0u, second_count = 0u;
    uint n = v * v * v;
    for (uint seeds = 0u; seeds < n; ++seeds) {
        uint start = n;
        for (uint i = 0u; i < kBitsWords && start == n; ++i)
            if (remaining.w[i] != 0u) start = i * 32u + uint(findLSB(remaining.w[i]));
        if (start == n) break;
        CellBits component = bits_none();
        component.w[start / 32u] = 1u << (start % 32u);
        for (uint step = 0u; step < n; ++step) {
            CellBits grown = bits_and(bits_dilate(component, v, faces), free_voxels);
            if (bits_equal(grown, component)) break;
            component = grown;
        }
        keep_largest(component, bits_count(component), first, first_count, second, second_count);
        remaining = bits_and_not(remaining, component);
    }
}

/// A cell of at most 64 voxels (v <= 4) as two words, low bits first.
struct Bits64 {
    uint lo;
    uint hi;
};

GUST_INLINE Bits64 b64(uint lo, uint hi) {
    Bits64 r;
    r.lo = lo;
    r.hi = hi;
    return r;
}

/// Moved up by s (1..31; a cell of v <= 4 steps by 1, v and v^2) positions.
GUST_INLINE Bits64 b64_up(Bits64 a, uint s) {
    return b64(a.lo << s, (a.hi << s) | (a.lo >> (32u - s)));
}

/// Moved down by s (1..31) positions.
GUST_INLINE Bits64 b64_down(Bits64 a, uint s) {
    return b64((a.lo >> s) | (a.hi << (32u - s)), a.hi >> s);
}

/// cell_parts_general for v <= 4, with the same fill on two words: a shader keeps them in registers,
/// where the general form's 16-word arrays, indexed by run-time shifts, go to memory (on an H100 that
/// made the fill most of the solid pass).
GUST_INLINE void cell_parts_small(CellBits occupied, uint v, CellBits faces[6], GUST_OUT(CellBits) first,
                                  GUST_OUT(CellBits) second) {
    CellBits all = bits_all(v);
    Bits64 free_voxels = b64(all.w[0] & ~occupied.w[0], all.w[1] & ~occupied.w[1]);
    Bits64 remaining = free_voxels;
    Bits64 best = b64(0u, 0u), next = b64(0u, 0u);
    uint best_count = 0u, next_count = 0u;
    uint n = v * v * v;
    for (uint seeds = 0u; seeds < n; ++seeds) {
        if (remaining.lo == 0u && remaining.hi == 0u) break;
        Bits64 component = remaining.lo != 0u ? b64(remaining.lo & (0u - remaining.lo), 0u)
                                              : b64(0u, remaining.hi & (0u - remaining.hi));
        for (uint step = 0u; step < n; ++step) {
            Bits64 grown = component;
            uint stride = 1u;
            for (uint a = 0u; a < 3u; ++a) {
                Bits64 up = b64_up(
                    b64(component.lo & ~faces[2u * a + 1u].w[0], component.hi & ~faces[2u * a + 1u].w[1]),
                    stride);
                Bits64 down = b64_down(
                    b64(component.lo & ~faces[2u * a].w[0], component.hi & ~faces[2u * a].w[1]), stride);
                grown = b64(grown.lo | up.lo | down.lo, grown.hi | up.hi | down.hi);
                stride *= v;
            }
            grown = b64(grown.lo & free_voxels.lo, grown.hi & free_voxels.hi);
            if (grown.lo == component.lo && grown.hi == component.hi) break;
            component = grown;
        }
        uint count = uint(bitCount(component.lo)) + uint(bitCount(component.hi));
        if (count > best_count) {
            next = best;
            next_count = best_count;
            best = component;
            best_count = count;
        } else if (count > next_count) {
            next = component;
            next_count = count;
        }
        remaining = b64(remaining.lo & ~component.lo, remaining.hi & ~component.hi);
    }
    first = bits_none();
    first.w[0] = best.lo;
    first.w[1] = best.hi;
    second = bits_none();
    second.w[0] = next.lo;
    second.w[1] = next.hi;
}

/// The parts of a cell: the two largest 6-connected components of its free voxels (the first found on a
/// tie), largest first; empty where there are fewer. One pressure per cell cannot stand for two sides of
/// a wall, so a cell's air is one part, and faces open only into it (face_open_count): then any chain of
/// open faces is a chain of free voxels, and a watertight surface, however thin, lets no air through.
/// Which part is the air is decided by whether it reaches an open domain side (the outside-air fill,
/// docs/solver.md "Solid interiors"); a cell keeps two so that the air beside a wall can be the smaller
/// part when the larger lies inside a closed mesh.
GUST_INLINE void cell_parts(CellBits occupied, uint v, CellBits faces[6], GUST_OUT(CellBits) first,
                            GUST_OUT(CellBits) second) {
    if (v * v * v <= 64u)
        cell_parts_small(occupied, v, faces, first, second);
    else
        cell_parts_general(occupied, v, faces, first, second);
}

/// Whether a part of a cell holds air that was beyond a wall a step before: fewer than half its voxels were
/// the cell's air then (`before`). Where a moving wall crosses the middle of a cell, the cell's air (its
/// larger part) switches to the wall's other side, and the faces of the cell still hold the velocities of
/// the side it left; solid_faces.comp sets them to the wall's.
GUST_INLINE bool part_crossed(CellBits part, CellBits before) {
    uint count = bits_count(part);
    return count != 0u && 2u * bits_count(bits_and(part, before)) < count;
}

/// Whether a set holds a voxel on cell side s (−x,+x,−y,+y,−z,+z).
GUST_INLINE bool bits_touch(CellBits set, CellBits faces[6], uint s) {
    return bits_count(bits_and(set, faces[s])) != 0u;
}

/// Voxel pairs across the face between cells `low` and `high` along `axis` that are both in the given
/// sets (the two cells' air, or two parts when linking them).
GUST_INLINE uint face_open_count(CellBits low, CellBits high, uint axis, uint v, CellBits faces[6]) {
    CellBits a = bits_and(low, faces[2u * axis + 1u]);
    CellBits b = bits_and(high, faces[2u * axis]);
    uint shift = axis == 0u ? v - 1u : (axis == 1u ? (v - 1u) * v : (v - 1u) * v * v);
    return bits_count(bits_and(bits_down(a, shift), b));
}

/// Voxel pairs across the face between cells `low` and `high` along `axis` with a voxel of the given sets on
/// either side (the static solid's, where a moving surface's push does not count: moving_share).
GUST_INLINE uint face_any_count(CellBits low, CellBits high, uint axis, uint v, CellBits faces[6]) {
    CellBits a = bits_and(low, faces[2u * axis + 1u]);
    CellBits b = bits_and(high, faces[2u * axis]);
    uint shift = axis == 0u ? v - 1u : (axis == 1u ? (v - 1u) * v : (v - 1u) * v * v);
    return bits_count(bits_or(bits_down(a, shift), b));
}

/// A sealed part's contact with solid voxels, as (voxels touched, of which static): in its own cell
/// (`side` 6; `solid` and `still` are the cell's) or in the neighbour across face `side` (−x,+x,−y,+y,−z,
/// +z; the neighbour's sets, counted as voxel pairs across the face).
GUST_INLINE uvec2 part_contact(CellBits part, CellBits solid, CellBits still, uint side, uint v,
                               CellBits faces[6]) {
    if (side == 6u) {
        CellBits ring = bits_and(bits_dilate(part, v, faces), solid);
        return uvec2(bits_count(ring), bits_count(bits_and(ring, still)));
    }
    uint axis = side / 2u;
    if ((side & 1u) != 0u)
        return uvec2(face_open_count(part, solid, axis, v, faces),
                     face_open_count(part, still, axis, v, faces));
    return uvec2(face_open_count(solid, part, axis, v, faces), face_open_count(still, part, axis, v, faces));
}

/// A sealed region moves with the solid that encloses it: the mean velocity of the moving solid voxels
/// its parts touch when those are at least half of all the solid voxels they touch, else still. `motion`
/// is region_motion's first slot (velocity sums weighted in quarters, and the weights), `border` the
/// second's x (4 per part that touches solid). So the inside of a static building stays still whatever
/// moves in it or brushes its walls, and a crate's inside moves with the crate though the floor it slides
/// on holds a sixth of its border.
GUST_INLINE ivec4 enclosing_motion(ivec4 motion, int border) {
    return motion.w > 0 && 2 * motion.w >= border ? motion : ivec4(0);
}

/// The share of a face's closed voxel pairs a moving solid pushes with: those with no static solid voxel.
/// Where a moving surface touches a static one (a foot on the ground, a piston along its duct's wall) their
/// voxels overlap, and a pair against the static solid carries no motion (it slides, the wall stays put).
/// Without it the cells a moving and a static surface share pushed with their whole closed part: a piston
/// filling a duct drove the air 30% faster than itself.
GUST_INLINE float moving_share(uint closed, uint static_pairs) {
    return closed > 0u ? float(closed - min(static_pairs, closed)) / float(closed) : 1.0f;
}

/// The share of one voxel pair in a face, 1 / v^2. Computed on the host (IEEE division); the shaders
/// read it from SolverBindings::pair_share, so both sides multiply by the same float.
GUST_INLINE float pair_share(uint v) {
    return 1.0f / float(v * v);
}

/// The share of one voxel in a cell, 1 / v^3: computed on the host, read by the shaders from
/// SolverBindings::voxel_share (as pair_share).
GUST_INLINE float voxel_share(uint v) {
    return 1.0f / float(v * v * v);
}

/// Solid fraction of a cell of v^3 voxels of which `air` are its air: 1 with none, else the solid voxels
/// times voxel_share, one correctly rounded multiplication. A shader's division may be off by an ulp (an
/// NVIDIA GPU's was), and the host's is exact: both sides must give the same float.
GUST_INLINE float solid_fraction_of(uint air, uint v, float share) {
    return air == 0u ? 1.0f : float(v * v * v - air) * share;
}

/// Words of open_counts for `faces` level-0 faces, four to a word.
GUST_INLINE uint open_count_words(uint faces) {
    return (faces + 3u) / 4u;
}

/// Open voxel pairs of level-0 face `face` from its word of open_counts.
GUST_INLINE uint open_count_in(uint word, uint face) {
    return (word >> (8u * (face & 3u))) & 0xffu;
}

/// Open fraction of a face with `count` of its voxel pairs open. Level 0 stores the count, a byte per
/// face (v <= 8), and every reader turns it into the fraction here.
GUST_INLINE float open_fraction_of(uint count, float share) {
    return float(count) * share;
}

/// Host side: the open fraction of a face between the air of two cells.
GUST_INLINE float face_open_fraction(CellBits low, CellBits high, uint axis, uint v, CellBits faces[6]) {
    return open_fraction_of(face_open_count(low, high, axis, v, faces), pair_share(v));
}

GUST_NAMESPACE_END

#endif
