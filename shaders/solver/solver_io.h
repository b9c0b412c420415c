// Layouts shared by the wind-solver shaders and solver/ (docs/design.md "Wind solver"): constants, pass
// modes, push constants, the bindings and the state, with their sizes checked on the C++ side. The pure
// functions are in solver_math.h (grid indexing, emitters, the solve's scalars) and solver_cells.h (a
// cell's voxel sets). The grid is a MAC grid of dims.x x dims.y x dims.z cells of size h: pressure at cell
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
/// Red-black sweeps of the coarsest level in the coarse solve.
GUST_CONST uint kCoarseSweeps = 32;
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
/// Cascades a nest holds at most, and the cells over which a cascade's answer blends into the next coarser
/// one's towards its border (docs/solver.md "Cascades"): kCascadeBlendCells where the coarser cascade is
/// open there, 1 where its cells around the point hold kCascadeSolidShare of solid or more.
GUST_CONST uint kMaxCascades = 8;
GUST_CONST float kCascadeBlendCells = 3.0f;
GUST_CONST float kCascadeSolidShare = 0.3f;
/// The share of the finer cascade's wind a coarser cascade takes each step on the faces the finer one covers
/// (docs/solver.md "Cascades", "Fine to coarse"): relaxed towards it, not overwritten by it.
GUST_CONST float kCascadeFeedback = 0.25f;
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
    float warm_qq;                    ///< q·q of the warm start, from start.comp's kStartQ
    uint pad;
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
GUST_CONST uint kCellCrossed = 256u;  ///< << k: part k is air from beyond a moving wall (part_crossed)

/// Whether the air of a cell with these flags crossed a moving wall since the last step (part_crossed):
/// its faces still hold the other side's velocities.
GUST_INLINE bool air_crossed(uint flags) {
    uint air = (flags & kCellSecondPart) != 0u ? 1u : 0u;
    return (flags & kCellNoAir) == 0u && (flags & (kCellCrossed << air)) != 0u;
}

/// Union-find node of part k of cell `cell`; node 0 stands for the air beyond the open domain sides.
GUST_CONST uint kOutsideNode = 0u;
GUST_INLINE uint part_node(uint cell, uint k) {
    return 1u + kCellParts * cell + k;
}

/// Union-find node of cell `cell` (of `cells`) in the pressure equation's own connectivity
/// (solid_faces.comp's link_fluid), after the part nodes; it shares node 0 with them.
GUST_INLINE uint fluid_node(uint cell, uint cells) {
    return 1u + kCellParts * cells + cell;
}

GUST_CONST uint kFieldVelocity = 0u; ///< face fields for load_face(): the velocity (SolverPush::swap)
GUST_CONST uint kFieldTmp = 1u;      ///< the other velocity buffer: a pass writes the next field here
GUST_CONST uint kFieldScratch = 2u;  ///< MacCormack's forward pass; the viscosity's iterations
GUST_CONST uint kFieldSolid = 3u;
GUST_CONST uint kFieldLow = 4u;  ///< MacCormack's forward pass: the least value each face blended
GUST_CONST uint kFieldHigh = 5u; ///< and the largest (both after kFieldScratch in velocity_back)
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
    GUST_ADDRESS velocity;        ///< float[faces]: one of the two velocity buffers (SolverPush::swap), m/s
    GUST_ADDRESS velocity_tmp;    ///< float[faces]: the other
    GUST_ADDRESS velocity_back;   ///< float[faces]: kFieldScratch (then kFieldLow, kFieldHigh)
    GUST_ADDRESS weights;         ///< float[]: weights of levels 1 on, from index level0_faces
    GUST_ADDRESS solid_velocity;  ///< float[faces]: solid's normal velocity per face, m/s
    GUST_ADDRESS pressure;        ///< float[]: kCellPressure, all levels
    GUST_ADDRESS pressure_up;     ///< float[]: kCellPressureUp, all levels
    GUST_ADDRESS rhs;             ///< float[]: right-hand side per cell, all levels (1/s)
    GUST_ADDRESS scratch;         ///< float[cells]: kCellScratch
    GUST_ADDRESS cell_solid;      ///< float[cells]: share of the cell's voxels that are not its air
    GUST_ADDRESS cell_parts;      ///< uint[cells * kCellParts * cell_words]: cut cells' parts (cell_parts)
    GUST_ADDRESS cell_static;     ///< uint[cells * cell_words]: kCellStatic cells' static solid voxels
    GUST_ADDRESS cell_flags;      ///< uint[cells]: kCell* flags
    GUST_ADDRESS cell_motion;     ///< ivec4[cells]: fixed-point fragment velocity sums and count
    GUST_ADDRESS labels;          ///< uint[1 + kCellParts * cells]: union-find parents (part_node ids)
    GUST_ADDRESS region_motion;   ///< ivec4[2 (1 + kCellParts * cells)]: per sealed region's root node r,
                                  ///< [2r] the fixed-point velocities of the moving solid its parts touch,
                                  ///< weighted in quarters, and the weights; [2r + 1].x 4 per part that
                                  ///< touches solid (enclosing_motion)
    GUST_ADDRESS vorticity;       ///< vec4[cells]: curl (1/s) and its length
    GUST_ADDRESS confinement;     ///< vec4[cells]: the step's confinement force (m/s^2) and speed (m/s)
    GUST_ADDRESS emitters;        ///< GpuEmitter[emitter_count]
    GUST_ADDRESS state;           ///< SolverState
    GUST_ADDRESS dispatch;        ///< LevelDispatch[2 * kDispatchSlots]: live, then full
    GUST_ADDRESS tree_nodes;      ///< the sparse tree's node pool (uvec2 per node), 0 without solids
    GUST_ADDRESS tree_masks;      ///< the sparse tree's leaf masks
    GUST_ADDRESS fragments;       ///< packed voxel keys of moving surfaces, 0 without
    GUST_ADDRESS fragment_count;  ///< uint
    GUST_ADDRESS fragment_motion; ///< uvec2 half-float velocities per fragment
    GUST_ADDRESS cg_cells;        ///< float[4 * cells]: conjugate gradients' x, p, b, old r
    GUST_ADDRESS partials;        ///< vec2[partial_count]: per-workgroup sums of a dot product
    GUST_ADDRESS points;          ///< vec3[point_count]: world positions to sample (sample.comp)
    GUST_ADDRESS samples;         ///< vec3[point_count]: their velocities, m/s
    GUST_ADDRESS texels;          ///< uvec2[cells]: half-float velocity xyz and open fraction per cell
    GUST_ADDRESS open_counts;     ///< uint[]: level 0's open voxel pairs, a byte per face
    /// Cascades (docs/solver.md "Cascades"). `current`: the velocity buffer that holds the field the last
    /// step (or scroll) left, which the neighbouring cascades read. `outer`: the SolverBindings of the next
    /// coarser cascade (0: none, and the ambient wind lies beyond the grid). `inner`: those of the next finer
    /// (0: none). `previous`: a copy of the field as it stood before the last step, which the finer cascade
    /// blends with `current` by `time_blend` (a solver with an inner only; 0: none).
    GUST_ADDRESS current;
    GUST_ADDRESS outer;
    GUST_ADDRESS inner;
    GUST_ADDRESS previous;
    ivec3 dims;           ///< wind cells per axis
    float h;              ///< cell size, m
    vec3 origin;          ///< world position of the grid's min corner, m
    uint voxels_per_cell; ///< tree voxels per cell per axis (1..8)
    vec3 ambient;         ///< m/s, world
    uint emitter_count;
    ivec3 voxel_offset; ///< tree voxel of the grid's min corner
    uint fragment_capacity;
    uint tree_levels; ///< 0 without a tree
    uint tree_log2_branching;
    uint open_sides;          ///< bit s (−x,+x,−y,+y,−z,+z) set: the side is open (φ = 0)
    uint levels;              ///< multigrid levels in use
    uint coarse_level;        ///< the first level coarse_solve.comp takes (0: the whole V-cycle)
    uint mask_words;          ///< words of a leaf layer in the tree's mask blocks
    uint mask_stride;         ///< words per tree mask block
    uint cell_words;          ///< words per part in cell_parts
    float tolerance;          ///< relative residual the solve stops at
    float vorticity_strength; ///< ε of vorticity confinement
    uint partial_count;       ///< workgroups over the level-0 cells (entries in partials)
    uint point_count;         ///< entries in points
    uint level0_faces;        ///< faces of level 0 (in open_counts); weights holds the levels after
    float pair_share;         ///< pair_share(voxels_per_cell)
    float voxel_share;        ///< voxel_share(voxels_per_cell)
    float max_solid_speed;    ///< m/s: fragment velocities are clamped to this length
    uint smoothing;           ///< red-black sweeps per V-cycle level and leg (SolverDesc::smoothing)
    uint cycles_recorded;     ///< V-cycles (Jacobi: blocks) this step records, for the stats
    uint omni_count;          ///< the first emitters are the omni ones (set_emitters puts them first)
    /// Where the finer cascade's time lies between `previous` (0) and `current` (1): the nest's steps run
    /// ahead of the finest, and the finer cascades read the wind in between (docs/solver.md "Cascades").
    float time_blend;
    // From here on vectors and levels start at multiples of 16 bytes: under Vulkan 1.2's relaxed block
    // layout, which a device without scalarBlockLayout (Godot 4's) holds shaders to, no vector straddles 16
    // bytes and an array of GridLevel is 16-aligned.
    vec3 previous_origin; ///< world position of `previous`'s min corner, m (before the last step's scroll)
    uint pad0;
    /// m/s: how much the ambient wind changed since the last step (WindSolver::set_ambient), added to every
    /// open face before the step's advection (scroll.comp kScrollAmbientChange).
    vec3 ambient_change;
    uint pad1;
    GridLevel level[kMaxGridLevels];
    uint face_mask[6 * kCellWords]; ///< voxel sets of a cell's six faces (−x,+x,−y,+y,−z,+z)
};

/// Push constants of every solver pass.
struct SolverPush {
    GUST_ADDRESS bindings; ///< SolverBindings
    float dt;              ///< seconds
    uint level;            ///< multigrid level the pass works on
    uint mode;             ///< the pass's job (the k<Pass>* modes below; diffuse.comp: the field it reads)
    uint iterations;       ///< smooth.comp: the iteration k; coarse_solve.comp: sweeps on the coarsest level
    float param;           ///< pass-specific value
    /// Bit 0: kFieldVelocity is velocity_tmp and kFieldTmp velocity; bit 1: the conjugate-gradient
    /// iteration's parity (x and p read from their B buffers).
    uint swap;
    ivec3 shift; ///< scroll: cells the field moves by
    /// Cascades: kNestOuter when SolverBindings::outer is set, kNestInner when inner is (read from here, so
    /// a solver on its own loads neither address).
    uint nest;
};

GUST_CONST uint kNestOuter = 1u;
GUST_CONST uint kNestInner = 2u;

// ---- Pass modes (SolverPush::mode) ------------------------------------------------------------------
// advect.comp and smooth.comp also take the mode as specialization constant 0 and get one pipeline per
// mode (their k*Modes): a compiler then keeps only that mode's code, where a CPU device would execute every
// mode's.

/// advect.comp: the velocity's next field into kFieldTmp.
GUST_CONST uint kAdvectSemiLagrangian = 0u; ///< semi-Lagrangian advection, then the forces (forced_face)
GUST_CONST uint kAdvectForward = 1u;        ///< MacCormack's forward pass into kFieldScratch, and its range
GUST_CONST uint kAdvectCorrect = 2u;        ///< MacCormack's backward pass and clamped correction, the forces
GUST_CONST uint kAdvectForces = 3u;         ///< no advection: the forces alone
/// kAdvectCorrect that also sums the warm start's b·q over the faces it writes and makes the scale
/// (PassLayout::FewerStages, after start.comp's kStartQ).
GUST_CONST uint kAdvectCorrectScale = 4u;
GUST_CONST uint kAdvectModes = 5u;

/// smooth.comp: one level's smoothing in shared-memory tiles.
GUST_CONST uint kSmoothFirst = 0u;      ///< level 0, a conjugate-gradient iteration's first pass: x_k and r
GUST_CONST uint kSmoothDown = 1u;       ///< a level between, downward: from zero against its right-hand side
GUST_CONST uint kSmoothUp = 2u;         ///< upward: the downward values plus the coarser level's correction
GUST_CONST uint kSmoothUpBeta = 3u;     ///< level 0 upward, conjugate gradients: kSmoothUp, then β's sums
GUST_CONST uint kSmoothFirstPlain = 4u; ///< kSmoothFirst of plain multigrid (α = 1, p the last z)
/// The solve's first pass (k = 0, either method): kSmoothFirst that also makes the right-hand side b, the
/// divergence (kCellTarget), with its maximum and the fluid cells, which the start used to.
GUST_CONST uint kSmoothStart = 5u;
GUST_CONST uint kSmoothModes = 6u;

/// coarse_solve.comp: the levels from SolverPush::level down in one workgroup.
GUST_CONST uint kCoarseCorrection = 0u; ///< the finer level's correction (level 0: plain multigrid's V-cycle)
GUST_CONST uint kCoarseBeta = 1u;       ///< level 0, conjugate gradients: the whole V-cycle, then β's sums

/// solid_cells.comp: which cells gather their voxels again.
GUST_CONST uint kSolidChanged = 0u; ///< those a moving surface reaches now or reached at the last step
GUST_CONST uint kSolidAll = 1u;     ///< every cell (the static solids or the grid changed)

/// start.comp: the pressure solve's start (docs/solver.md, "The solve's start").
GUST_CONST uint kStartRhs = 0u;   ///< the Jacobi baseline's b (kCellTarget, kCellRhs), its maximum, fluid cells
GUST_CONST uint kStartScale = 1u; ///< the warm start's q = Lφ and its scale (warm_scale), in a stage of its own
/// q and q·q only (SolverState::warm_qq), beside the advection's first pass; its last pass
/// (kAdvectCorrectScale) sums b·q by faces and makes the scale.
GUST_CONST uint kStartQ = 2u;

/// jacobi.comp: the Jacobi baseline.
GUST_CONST uint kJacobiSweep = 0u; ///< one damped sweep
GUST_CONST uint kJacobiCheck = 1u; ///< the residual's maximum and the convergence check

/// sample.comp: reading the field for engines.
GUST_CONST uint kSamplePoints = 0u; ///< per query point, the velocity there
GUST_CONST uint kSampleTexels = 1u; ///< per cell, its texel of the wind texture (finish.comp's, when bound)
GUST_CONST uint kSampleCells = 2u;  ///< per cell, the velocity at its centre
GUST_CONST uint kSampleWind = 3u;   ///< per query point, the wind as engines read it (the cascades' texels)

// scroll.comp's modes.
GUST_CONST uint kScrollMove = 0u; ///< the field moved by SolverPush::shift cells
/// SolverBindings::ambient_change added to every open face, of the field and of `previous` (when set).
GUST_CONST uint kScrollAmbientChange = 1u;

/// diffuse.comp reads face field SolverPush::mode (kFieldVelocity, then each iteration's target) and
/// writes this one: the iterations alternate between kFieldTmp and kFieldScratch.
GUST_INLINE uint diffuse_target(uint from) {
    return from == kFieldTmp ? kFieldScratch : kFieldTmp;
}

GUST_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(gust::shaderio::GpuEmitter) == 48);
static_assert(sizeof(gust::shaderio::GridLevel) == 48);
static_assert(offsetof(gust::shaderio::SolverBindings, previous_origin) % 16 == 0);
static_assert(offsetof(gust::shaderio::SolverBindings, ambient_change) % 16 == 0);
static_assert(offsetof(gust::shaderio::SolverBindings, level) % 16 == 0);
static_assert(sizeof(gust::shaderio::SolverPush) == 48);
static_assert(sizeof(gust::shaderio::SolverState) == 112);
#endif

#endif
