// Layouts and pure per-cell functions shared by the wind-solver shaders and solver/ (docs/design.md
// "Wind solver"). The grid is a MAC grid of dims.x x dims.y x dims.z cells of size h: pressure at cell
// centres, velocity component a on the faces normal to axis a. All face values of one field live in
// one array: the x faces ((nx+1)·ny·nz, x fastest), then the y faces, then the z faces.
#ifndef GUST_SOLVER_IO_H
#define GUST_SOLVER_IO_H

#include "../common.h"

GUST_NAMESPACE_BEGIN

GUST_CONST uint kSolverGroupSize = 64;
/// Side of the cubic tile of cells one workgroup of the tile smoother (smooth.comp) owns.
GUST_CONST uint kTileSide = 8;
/// Levels of at most this many cells are solved together by one workgroup in shared memory
/// (coarse_solve.comp), so none of them costs a dispatch of its own.
GUST_CONST uint kCoarseCells = 4096;
/// advect.comp's and smooth.comp's modes (SolverPush::parity 0 to 4), one pipeline each.
GUST_CONST uint kAdvectModes = 5;
GUST_CONST uint kSmoothModes = 5;
/// Multigrid levels at most (the finest included).
GUST_CONST uint kMaxGridLevels = 10;
/// Words of a cell's voxel set: voxels_per_cell^3 bits, up to 8^3 (the layout of the voxel-set arrays).
GUST_CONST uint kCellWords = 16;
/// Words a CellBits holds. The shaders that work on voxel sets are also built with GUST_SMALL_CELLS
/// (shaders/CMakeLists.txt), for up to 4 voxels per cell (4^3 = 64 bits): their sets are two words, not
/// sixteen. llvmpipe executes every word of every branch, so this cut the sample's step by 29%
/// (docs/results.md); a GPU only saves registers.
#ifdef GUST_SMALL_CELLS
GUST_CONST uint kBitsWords = 2;
#else
GUST_CONST uint kBitsWords = kCellWords;
#endif
GUST_CONST uint kMaxVoxelsPerCell = 8;
GUST_CONST uint kMaxEmitters = 64;
/// Fragment velocities are summed per cell as fixed point with this many steps per m/s, clamped to
/// ±kMaxFragmentSpeed, so 32-bit integer atomics suffice (no float-atomic feature needed).
GUST_CONST float kVelocityScale = 256.0f;
GUST_CONST float kMaxFragmentSpeed = 256.0f;
/// Air components a cell keeps (its two largest; see cell_parts).
GUST_CONST uint kCellParts = 2u;
/// A pressure solve whose residual grows past this many times its reference (the larger of max |b| and
/// its first residual) has diverged: it stops, and the step projects nothing (solve_diverged).
GUST_CONST float kDivergenceGuard = 100.0f;

/// Damping of the Jacobi baseline: plain Jacobi never damps the checkerboard mode of a closed pocket
/// (its iteration matrix has eigenvalue −1 there), 6/7 does and is the best smoother for 3D Laplacians.
GUST_CONST float kJacobiWeight = 0.857f;

GUST_CONST uint kEmitterDirectional = 0u;
GUST_CONST uint kEmitterOmni = 1u;
GUST_CONST uint kEmitterVortex = 2u;
GUST_CONST uint kEmitterCapsule = 3u; ///< motor with a capsule profile
GUST_CONST uint kEmitterCone = 4u;    ///< motor with a cone profile

/// A wind source as the shaders see it (solver/wind_solver.hpp documents each type's profile).
struct GpuEmitter {
    vec3 position;  ///< metres, world (a motor's start)
    uint type;      ///< kEmitter*
    vec3 direction; ///< unit: flow (directional, motor) or axis (vortex)
    float radius;   ///< metres, > 0
    float strength; ///< target speed at the centre, m/s (negative reverses)
    float falloff;  ///< exponent p of (1 - d/radius)^p
    float extent;   ///< motors: metres along `direction`
    float pad;
};

/// One level of the pressure hierarchy (level 0 is the wind grid).
struct GridLevel {
    ivec3 dims;   ///< cells per axis
    uint cells;   ///< offset of this level in the per-cell arrays
    ivec3 factor; ///< fine cells per coarse cell per axis towards the next level (1 or 2)
    uint faces;   ///< offset of this level in the weight array
    vec3 inv_h2;  ///< 1 / h_a^2 per axis, 1/m^2
    uint pad;
};

/// Indirect dispatch arguments (VkDispatchIndirectCommand).
struct LevelDispatch {
    uint x, y, z;
};

/// Counters the passes write; the CPU reads them after the step.
struct SolverState {
    uint divergence_before;           ///< float bits of max |weighted divergence| before projection, 1/s
    uint divergence_after;            ///< float bits of the same after projection
    uint residual;                    ///< float bits of max |b − Lφ| of the step's pressure, 1/s
    uint residual_scratch;            ///< float bits of max |residual| being gathered by a check
    uint checks;                      ///< convergence checks that found the solve unfinished
    uint done;                        ///< 1 once a check found the residual within tolerance
    uint cut_cells;                   ///< cells holding solid voxels
    uint fluid_cells;                 ///< cells with at least one open face
    LevelDispatch fragments_dispatch; ///< over the moving surfaces' fragments
    uint fragments;                   ///< moving fragments read this step
    float cg_rz;                      ///< conjugate gradients: r·z of the last iteration
    float cg_alpha;                   ///< step length along the search direction
    float cg_beta;                    ///< weight of the previous search direction
    float warm_scale;                 ///< s of the warm start x0 = s·φ of the last step (0: from zero)
    uint recorded;                    ///< V-cycles (Jacobi: blocks) this step recorded
    uint first_residual;              ///< float bits of max |residual| at the solve's first check
    uint diverged;                    ///< 1 when the solve was stopped by solve_diverged (nothing projected)
    uint sealed_cells;                ///< cells with free voxels none of which reach an open side
    uint x_slot;                      ///< which of the two iterates holds x (0: kCellSolution, 1: ...B)
    uint p_slot;                      ///< which of the two search directions holds p
    uint reduce_count;                ///< workgroups done with the current reduction (last_group())
    LevelDispatch fluid_dispatch;     ///< over the cells when a cell has two parts of outside air, else none
    uint pad[2];
};

/// Slots of the dispatch buffer: per multigrid level the level's cells (restriction into it) and its
/// tiles (smooth.comp), the coarse solve, and a level-0 cell pass; then a full copy that live slots are
/// reset from (a converged solve zeroes the live ones).
GUST_CONST uint kTileSlot = kMaxGridLevels; ///< kTileSlot + level
GUST_CONST uint kCoarseSlot = 2u * kMaxGridLevels;
GUST_CONST uint kDispatchSlots = 2u * kMaxGridLevels + 1u;

// cell_flags. A cell's free voxels fall into 6-connected components; it keeps the two largest as its
// parts (cell_parts), and the part whose air reaches an open domain side is the air its pressure stands
// for (solid_faces: the fluid set). Parts that reach none are sealed: solid for the wind.
GUST_CONST uint kCellCut = 1u;        ///< holds solid voxels: its parts are in SolverBindings::cell_parts
GUST_CONST uint kCellMoving = 2u;     ///< moving fragments were summed into cell_motion
GUST_CONST uint kCellNoAir = 4u;      ///< no part reaches an open side: the whole cell is solid for the wind
GUST_CONST uint kCellSecondPart = 8u; ///< its air is part 1 (part 0 is sealed)
GUST_CONST uint kCellRegion = 16u;    ///< << k: node k of this cell roots a sealed region with motion sums
GUST_CONST uint kCellStatic = 64u;    ///< holds static solid voxels: they are in SolverBindings::cell_static
GUST_CONST uint kCellDynamic = 128u;  ///< held voxels of moving surfaces: the next step redoes its voxels

/// Union-find node of part k of cell `cell`; node 0 stands for the air beyond the open domain sides.
GUST_CONST uint kOutsideNode = 0u;
GUST_INLINE uint part_node(uint cell, uint k) {
    return 1u + kCellParts * cell + k;
}

/// Union-find node of cell `cell` (of `cells`) in the pressure equation's own connectivity
/// (fluid_link.comp), after the part nodes; it shares node 0 with them.
GUST_INLINE uint fluid_node(uint cell, uint cells) {
    return 1u + kCellParts * cells + cell;
}

GUST_CONST uint kFieldVelocity = 0u; ///< face fields for load_face(): the velocity (SolverPush::swap)
GUST_CONST uint kFieldTmp = 1u;      ///< the other velocity buffer: a pass writes the next field here
GUST_CONST uint kFieldBack = 2u;     ///< MacCormack's backward pass
GUST_CONST uint kFieldSolid = 3u;
GUST_CONST uint kFieldLow = 4u;  ///< MacCormack's forward pass: the least value each face blended
GUST_CONST uint kFieldHigh = 5u; ///< and the largest (both after kFieldBack in velocity_back)
GUST_CONST uint kFaceFields = 6u;
GUST_CONST uint kCellPressure = 0u;    ///< cell fields for load_cell(): a level's V-cycle value, downward
GUST_CONST uint kCellRhs = 1u;         ///< a level's V-cycle right-hand side (level 0: the residual r)
GUST_CONST uint kCellScratch = 2u;     ///< level 0 only: the warm start's q = Lφ
GUST_CONST uint kCellPressureUp = 3u;  ///< a level's V-cycle value after its coarse correction, upward
GUST_CONST uint kCellSolution = 4u;    ///< conjugate gradients: the iterate x (and kCellSolutionB)
GUST_CONST uint kCellDirection = 5u;   ///< the search direction p (and kCellDirectionB)
GUST_CONST uint kCellTarget = 6u;      ///< the right-hand side b
GUST_CONST uint kCellOldResidual = 7u; ///< the residual of the iteration before
GUST_CONST uint kCellSolutionB = 8u;   ///< the other iterate: iteration k reads one and writes the other
GUST_CONST uint kCellDirectionB = 9u;  ///< the other search direction
GUST_CONST uint kCellPhi = 10u;        ///< φ, the step's pressure solution (output and next warm start)
GUST_CONST uint kCellFields = 11u;

/// Addresses and parameters of one step, in a buffer of their own (push constants stay small).
struct SolverBindings {
    GUST_ADDRESS velocity;       ///< float[faces]: one of the two velocity buffers (SolverPush::swap), m/s
    GUST_ADDRESS velocity_tmp;   ///< float[faces]: the other
    GUST_ADDRESS velocity_back;  ///< float[faces]: MacCormack's backward pass (then kFieldLow, kFieldHigh)
    GUST_ADDRESS weights;        ///< float[]: weights of levels 1 on, from index level0_faces
    GUST_ADDRESS solid_velocity; ///< float[faces]: solid's normal velocity per face, m/s
    GUST_ADDRESS pressure;       ///< float[]: kCellPressure, all levels
    GUST_ADDRESS pressure_up;    ///< float[]: kCellPressureUp, all levels
    GUST_ADDRESS rhs;            ///< float[]: right-hand side per cell, all levels (1/s)
    GUST_ADDRESS scratch;        ///< float[cells]: kCellScratch
    GUST_ADDRESS cell_solid;     ///< float[cells]: share of the cell's voxels that are not its air
    GUST_ADDRESS cell_parts;     ///< uint[cells * kCellParts * cell_words]: cut cells' parts (cell_parts)
    GUST_ADDRESS cell_static;    ///< uint[cells * cell_words]: kCellStatic cells' static solid voxels
    GUST_ADDRESS cell_flags;     ///< uint[cells]: kCell* flags
    GUST_ADDRESS cell_motion;    ///< ivec4[cells]: fixed-point fragment velocity sums and count
    GUST_ADDRESS labels;         ///< uint[1 + kCellParts * cells]: union-find parents (part_node ids)
    GUST_ADDRESS region_motion;  ///< ivec4[2 (1 + kCellParts * cells)]: per sealed region's root node r,
                                 ///< [2r] the fixed-point velocities of the moving solid its parts touch,
                                 ///< weighted in quarters, and the weights; [2r + 1].x 4 per part that
                                 ///< touches solid (enclosing_motion)
    GUST_ADDRESS vorticity;      ///< vec4[cells]: curl (1/s) and its length
    GUST_ADDRESS confinement;    ///< vec4[cells]: the step's confinement force (m/s^2) and speed (m/s)
    GUST_ADDRESS emitters;       ///< GpuEmitter[emitter_count]
    GUST_ADDRESS state;          ///< SolverState
    GUST_ADDRESS dispatch;       ///< LevelDispatch[2 * kDispatchSlots]: live, then full
    GUST_ADDRESS tree_nodes;     ///< the sparse tree's node pool (uvec2 per node), 0 without solids
    GUST_ADDRESS tree_masks;     ///< the sparse tree's leaf masks
    GUST_ADDRESS fragments;      ///< packed voxel keys of moving surfaces, 0 without
    GUST_ADDRESS fragment_count; ///< uint
    GUST_ADDRESS fragment_motion; ///< uvec2 half-float velocities per fragment
    GUST_ADDRESS cg_cells;        ///< float[4 * cells]: conjugate gradients' x, p, b, old r
    GUST_ADDRESS partials;        ///< vec2[partial_count]: per-workgroup sums of a dot product
    GUST_ADDRESS points;          ///< vec3[point_count]: world positions to sample (sample.comp)
    GUST_ADDRESS samples;         ///< vec3[point_count]: their velocities, m/s
    GUST_ADDRESS texels;          ///< uvec2[cells]: half-float velocity xyz and open fraction per cell
    GUST_ADDRESS open_counts;     ///< uint[]: level 0's open voxel pairs, a byte per face
    ivec3 dims;                   ///< wind cells per axis
    float h;                      ///< cell size, m
    vec3 origin;                  ///< world position of the grid's min corner, m
    uint voxels_per_cell;         ///< tree voxels per cell per axis (1..8)
    vec3 ambient;                 ///< m/s, world
    uint emitter_count;
    ivec3 voxel_offset; ///< tree voxel of the grid's min corner
    uint fragment_capacity;
    uint tree_levels; ///< 0 without a tree
    uint tree_log2_branching;
    uint open_sides;          ///< bit s (−x,+x,−y,+y,−z,+z) set: the side is open (φ = 0)
    uint levels;              ///< multigrid levels in use
    uint mask_words;          ///< words of a leaf layer in the tree's mask blocks
    uint mask_stride;         ///< words per tree mask block
    uint cell_words;          ///< words per part in cell_parts
    float tolerance;          ///< relative residual the solve stops at
    float vorticity_strength; ///< ε of vorticity confinement
    uint partial_count;       ///< workgroups over the level-0 cells (entries in partials)
    uint point_count;         ///< entries in points
    uint level0_faces;        ///< faces of level 0 (in open_counts); weights holds the levels after
    float pair_share;         ///< pair_share(voxels_per_cell)
    float max_solid_speed;    ///< m/s: fragment velocities are clamped to this length
    uint smoothing;           ///< red-black sweeps per V-cycle level and leg (SolverDesc::smoothing)
    uint cycles_recorded;     ///< V-cycles (Jacobi: blocks) this step records, for the stats
    uint omni_count;          ///< the first emitters are the omni ones (set_emitters puts them first)
    GridLevel level[kMaxGridLevels];
    uint face_mask[6 * kCellWords]; ///< voxel sets of a cell's six faces (−x,+x,−y,+y,−z,+z)
};

/// Push constants of every solver pass.
struct SolverPush {
    GUST_ADDRESS bindings; ///< SolverBindings
    float dt;              ///< seconds
    uint level;            ///< multigrid level the pass works on
    uint parity;           ///< the pass's mode, or which field it reads
    uint iterations;       ///< sweeps, or a pass-specific count
    float param;           ///< pass-specific value
    /// Bit 0: kFieldVelocity is velocity_tmp and kFieldTmp velocity; bit 1: the conjugate-gradient
    /// iteration's parity (x and p read from their B buffers).
    uint swap;
    ivec3 shift; ///< scroll: cells the field moves by
    uint pad;
};

// ---- Grid indexing ----------------------------------------------------------------------------------

GUST_INLINE ivec3 axis_unit(uint axis) {
    return ivec3(axis == 0u ? 1 : 0, axis == 1u ? 1 : 0, axis == 2u ? 1 : 0);
}

GUST_INLINE int face_count(ivec3 n, uint axis) {
    ivec3 m = n + axis_unit(axis);
    return m.x * m.y * m.z;
}

/// Offset of the first face normal to `axis` in a face array of a grid of n cells.
GUST_INLINE int face_base(ivec3 n, uint axis) {
    int base = 0;
    if (axis > 0u) base += face_count(n, 0u);
    if (axis > 1u) base += face_count(n, 1u);
    return base;
}

GUST_INLINE int faces_total(ivec3 n) {
    return face_count(n, 0u) + face_count(n, 1u) + face_count(n, 2u);
}

/// Index of face f (the face on the low side of cell f along `axis`; f[axis] in 0..n[axis]).
GUST_INLINE int face_index(ivec3 n, uint axis, ivec3 f) {
    ivec3 m = n + axis_unit(axis);
    return face_base(n, axis) + f.x + m.x * (f.y + m.y * f.z);
}

GUST_INLINE int cell_index(ivec3 n, ivec3 c) {
    return c.x + n.x * (c.y + n.y * c.z);
}

GUST_INLINE bool inside_cells(ivec3 n, ivec3 c) {
    return c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x < n.x && c.y < n.y && c.z < n.z;
}

/// The face a linear index names (inverse of face_index); the axis through `axis`.
GUST_INLINE ivec3 face_from_index(ivec3 n, int index, GUST_OUT(uint) axis) {
    axis = 0u;
    if (index >= face_base(n, 1u)) axis = 1u;
    if (index >= face_base(n, 2u)) axis = 2u;
    int i = index - face_base(n, axis);
    ivec3 m = n + axis_unit(axis);
    return ivec3(i % m.x, (i / m.x) % m.y, i / (m.x * m.y));
}

GUST_INLINE ivec3 cell_from_index(ivec3 n, int index) {
    return ivec3(index % n.x, (index / n.x) % n.y, index / (n.x * n.y));
}

/// Side bit (−x,+x,−y,+y,−z,+z) of boundary face f, or 6 for an interior face.
GUST_INLINE uint boundary_side(ivec3 n, uint axis, ivec3 f) {
    int k = f[axis];
    if (k == 0) return 2u * axis;
    if (k == n[axis]) return 2u * axis + 1u;
    return 6u;
}

/// Sides through which the ambient wind enters are held at it (fixed velocity); the others are open
/// (φ = 0), so air leaves through them. A side parallel to the wind counts as open.
GUST_INLINE uint open_sides_for(vec3 ambient) {
    uint bits = 0u;
    for (uint a = 0u; a < 3u; ++a) {
        if (!(ambient[a] > 0.0f)) bits |= 1u << (2u * a);      // low side: inflow only when wind goes +a
        if (!(ambient[a] < 0.0f)) bits |= 1u << (2u * a + 1u); // high side: inflow only when wind goes −a
    }
    return bits;
}

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
/// the next (the earlier one wins a tie).
GUST_INLINE void keep_largest(CellBits component, uint count, GUST_OUT(CellBits) first,
                              GUST_OUT(uint) first_count, GUST_OUT(CellBits) second,
                              GUST_OUT(uint) second_count) {
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

// ---- Emitters ------------------------------------------------------------------------------------------

/// (1 - d/r)^p inside the radius, 0 outside (p = 0: uniform).
GUST_INLINE float emitter_falloff(float d, float radius, float p) {
    if (!(d < radius)) return 0.0f;
    float x = 1.0f - d / radius;
    return p == 0.0f ? 1.0f : pow(x, p);
}

/// The velocity an emitter drives the air towards at world point x, m/s (zero outside its reach).
/// Directional: `direction` inside a sphere. Omni: radial, outwards for positive strength (push) and
/// inwards for negative (pull). Vortex: around the axis through `position` along `direction`
/// (right-handed for positive strength), falloff by distance from the centre. Capsule motor: along
/// `direction` within `radius` of the segment of `length` from `position`. Cone motor: along the
/// segment, within a radius growing from 0 at `position` to `radius` at its end.
GUST_INLINE vec3 emitter_velocity(GpuEmitter e, vec3 x) {
    vec3 d = x - e.position;
    float dist = length(d);
    if (e.type == kEmitterDirectional)
        return e.direction * (e.strength * emitter_falloff(dist, e.radius, e.falloff));
    if (e.type == kEmitterOmni) {
        if (dist < 1e-6f) return vec3(0.0f);
        return d / dist * (e.strength * emitter_falloff(dist, e.radius, e.falloff));
    }
    if (e.type == kEmitterVortex) {
        vec3 around = cross(e.direction, d);
        float r = length(around);
        if (r < 1e-6f) return vec3(0.0f);
        return around / r * (e.strength * emitter_falloff(dist, e.radius, e.falloff));
    }
    float along = clamp(dot(d, e.direction), 0.0f, e.extent);
    float off = length(d - e.direction * along);
    float radius = e.radius;
    if (e.type == kEmitterCone) {
        if (dot(d, e.direction) < 0.0f) return vec3(0.0f);
        radius = e.extent > 0.0f ? e.radius * along / e.extent : e.radius;
        if (!(radius > 0.0f)) return vec3(0.0f);
    }
    return e.direction * (e.strength * emitter_falloff(off, radius, e.falloff));
}

/// Moves one face velocity component towards an emitter's: an emitter speeds air up along its
/// direction to its strength, and never slows air already going faster that way. `rate` is the
/// share of the gap closed this step, 1 - exp(−dt/τ).
GUST_INLINE float emitter_drive(float u, float target, float rate) {
    if (target > 0.0f && u < target) return u + (target - u) * rate;
    if (target < 0.0f && u > target) return u + (target - u) * rate;
    return u;
}

// ---- Conjugate gradients ---------------------------------------------------------------------------

/// Weight of the previous search direction. A V-cycle is not an exactly symmetric preconditioner, so
/// the flexible (Polak–Ribière) form β = z·(r − r_old) / (z_old·r_old) is used (Notay 2000); it equals
/// Fletcher–Reeves when the preconditioner is symmetric. 0 on the first iteration or a breakdown.
GUST_INLINE float cg_beta(float rz, float z_dot_old_r, float old_rz) {
    float beta = old_rz != 0.0f ? (rz - z_dot_old_r) / old_rz : 0.0f;
    return abs(beta) < 1e30f ? beta : 0.0f;
}

/// Step length along the search direction p: (r·z) / (p·Lp); 0 when p·Lp vanishes (p is constant over a
/// closed pocket, where L has no inverse) or the quotient is not finite.
GUST_INLINE float cg_alpha(float rz, float p_dot_lp) {
    float alpha = p_dot_lp != 0.0f ? rz / p_dot_lp : 0.0f;
    return abs(alpha) < 1e30f ? alpha : 0.0f;
}

/// Scale s of the warm start x0 = s·φ_prev, from b·q and q·q with q = Lφ_prev: the s that minimises
/// |b − s·q|², so the first residual is never larger (2-norm) than a start from zero gives. It follows a
/// change of dt (φ = p·dt/ρ) and falls to about 0 when φ_prev belongs to another problem (the first
/// step from still or uniform air, whose φ sets the flow moving, is then a poor start for the next).
/// 0 when q vanishes or the quotient is not finite.
GUST_INLINE float warm_scale(float b_dot_q, float q_dot_q) {
    float s = q_dot_q > 0.0f ? b_dot_q / q_dot_q : 0.0f;
    return abs(s) < 1e30f ? s : 0.0f;
}

/// Whether a solve has diverged: its max residual (NaN included) past kDivergenceGuard times the larger of
/// max |b| and its first residual. Conjugate gradients on a consistent system do not grow that much (their
/// max-norm residual wanders within a few times its start); a singular or inconsistent one can without
/// bound, and projecting such a φ would set the air moving at any speed.
GUST_INLINE bool solve_diverged(float residual, float first, float b_max) {
    return !(residual <= kDivergenceGuard * max(first, b_max));
}

/// A fragment velocity (m/s) with its length clamped to `limit` (m/s, > 0): no solid pushes air faster.
GUST_INLINE vec3 clamp_speed(vec3 velocity, float limit) {
    float speed = length(velocity);
    return speed > limit ? velocity * (limit / speed) : velocity;
}

GUST_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(gust::shaderio::GpuEmitter) == 48);
static_assert(sizeof(gust::shaderio::GridLevel) == 48);
static_assert(sizeof(gust::shaderio::SolverPush) == 48);
static_assert(sizeof(gust::shaderio::SolverState) == 112);
#endif

#endif
