// Buffers, accessors and helpers shared by the solver passes; then the shared kernels. A pass declares its
// workgroup size before including this file: group_sum() reads gl_WorkGroupSize, which glslang takes as
// (1, 1, 1) where it is used before the declaration.
#extension GL_EXT_control_flow_attributes : enable
#include "solver_io.h"
#include "solver_math.h"
#include "solver_cells.h"

layout(buffer_reference, scalar) readonly buffer BindingsRef { SolverBindings b; };
// Not `coherent`: no pass reads what another invocation of the same dispatch wrote (the barrier between
// dispatches makes writes visible), and coherent loads skip the first-level cache on some GPUs.
layout(buffer_reference, scalar) buffer FloatsRef { float v[]; };
layout(buffer_reference, scalar) buffer WordsRef { uint v[]; };
layout(buffer_reference, scalar) buffer Vec4Ref { vec4 v[]; };
layout(buffer_reference, scalar) buffer Vec2Ref { vec2 v[]; };
layout(buffer_reference, scalar) buffer IVec4Ref { ivec4 v[]; };
layout(buffer_reference, scalar) readonly buffer UVec2Ref { uvec2 v[]; };
layout(buffer_reference, scalar) readonly buffer NodesRef { uvec2 v[]; };
layout(buffer_reference, scalar) readonly buffer EmittersRef { GpuEmitter v[]; };
layout(buffer_reference, scalar) buffer StateRef { SolverState s; };
layout(buffer_reference, scalar) buffer DispatchRef { LevelDispatch v[]; };
// The cell fields (load_cell, store_cell). A pass whose last workgroup reads cells that the others wrote in
// the same dispatch (smooth.comp built with GUST_THEN_COARSE) defines GUST_COHERENT_CELLS.
#ifdef GUST_COHERENT_CELLS
layout(buffer_reference, scalar) coherent buffer CellsRef { float v[]; };
#else
layout(buffer_reference, scalar) buffer CellsRef { float v[]; };
#endif

layout(push_constant, scalar) uniform Push { SolverPush pc; };

BindingsRef sb() { return BindingsRef(pc.bindings); }
StateRef state() { return StateRef(sb().b.state); }

/// Linear thread index over a 2D grid of workgroups (rows of at most 65,535).
int thread_index() {
    return int((gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kSolverGroupSize + gl_LocalInvocationID.x);
}

// What the accessors below read at every call, loaded once per invocation: every pass's main() begins with
// load_bindings(). Mesa 22's llvmpipe turns each buffer-reference load into a loop over the SIMD lanes, so
// reading these through sb() at every access cost more than the data itself; a GPU keeps them in scalar
// registers either way.
struct HotBindings {
    uint64_t velocity, velocity_tmp, velocity_back, solid_velocity, weights, open_counts;
    uint64_t pressure, pressure_up, rhs, scratch, cg_cells;
    uint64_t vorticity, confinement, emitters, cell_flags, cell_parts, cell_solid, labels, cell_static, cell_motion, region_motion;
    ivec3 dims;
    float h;
    vec3 origin;
    uint open_sides;
    vec3 ambient;
    int level0_faces;
    float pair_share;
    uint voxels_per_cell;
    uint cell_words;
    uint emitter_count;
    uint omni_count;
};
HotBindings hot;
void load_bindings() {
    BindingsRef r = sb();
    hot.velocity = r.b.velocity;
    hot.velocity_tmp = r.b.velocity_tmp;
    hot.velocity_back = r.b.velocity_back;
    hot.solid_velocity = r.b.solid_velocity;
    hot.weights = r.b.weights;
    hot.open_counts = r.b.open_counts;
    hot.pressure = r.b.pressure;
    hot.pressure_up = r.b.pressure_up;
    hot.rhs = r.b.rhs;
    hot.scratch = r.b.scratch;
    hot.cg_cells = r.b.cg_cells;
    hot.vorticity = r.b.vorticity;
    hot.confinement = r.b.confinement;
    hot.emitters = r.b.emitters;
    hot.cell_flags = r.b.cell_flags;
    hot.cell_parts = r.b.cell_parts;
    hot.cell_solid = r.b.cell_solid;
    hot.labels = r.b.labels;
    hot.cell_static = r.b.cell_static;
    hot.cell_motion = r.b.cell_motion;
    hot.region_motion = r.b.region_motion;
    hot.dims = r.b.dims;
    hot.h = r.b.h;
    hot.origin = r.b.origin;
    hot.open_sides = r.b.open_sides;
    hot.ambient = r.b.ambient;
    hot.level0_faces = int(r.b.level0_faces);
    hot.pair_share = r.b.pair_share;
    hot.voxels_per_cell = r.b.voxels_per_cell;
    hot.cell_words = r.b.cell_words;
    hot.emitter_count = r.b.emitter_count;
    hot.omni_count = r.b.omni_count;
}

ivec3 grid_dims() { return hot.dims; }
float grid_h() { return hot.h; }
vec3 grid_origin() { return hot.origin; }
uint grid_open_sides() { return hot.open_sides; }
GridLevel load_level(uint l) { return sb().b.level[l]; }
uint emitter_count() { return hot.emitter_count; }
uint omni_count() { return hot.omni_count; }
GpuEmitter load_emitter(uint i) { return EmittersRef(hot.emitters).v[i]; }

// ---- Cascades (docs/solver.md "Cascades") ---------------------------------------------------------------
// A cascade reads its neighbours' fields through their bindings (SolverBindings::outer, inner): their
// `current` velocity buffer, dims, cell size and origin as of their last step or scroll. A shader that
// defines GUST_NESTED_CONSTANT declares kNested, a specialization constant false for a solver without
// neighbours; the others take SolverPush::nest alone.

/// Whether this grid reads the next coarser (kNestOuter) or finer (kNestInner) cascade.
bool nested(uint which) {
#ifdef GUST_NESTED_CONSTANT
    if (!kNested) return false;
#endif
    return (pc.nest & which) != 0u;
}

/// Trilinear at q (in lattice points) over a lattice of m points stored from `values` + `base` floats, x
/// fastest, clamped to it: a face component's lattice (face_index) or the cells' (cell_index, base 0).
float lattice_value(uint64_t values, int base, ivec3 m, vec3 q) {
    q = clamp(q, vec3(0.0), vec3(m - ivec3(1)));
    ivec3 i0 = min(ivec3(floor(q)), max(m - ivec3(2), ivec3(0)));
    ivec3 i1 = min(i0 + ivec3(1), m - ivec3(1));
    vec3 t = q - vec3(i0);
    FloatsRef v = FloatsRef(values);
    float c00 = mix(v.v[base + cell_index(m, i0)], v.v[base + cell_index(m, ivec3(i1.x, i0.y, i0.z))], t.x);
    float c10 = mix(v.v[base + cell_index(m, ivec3(i0.x, i1.y, i0.z))],
                    v.v[base + cell_index(m, ivec3(i1.x, i1.y, i0.z))], t.x);
    float c01 = mix(v.v[base + cell_index(m, ivec3(i0.x, i0.y, i1.z))],
                    v.v[base + cell_index(m, ivec3(i1.x, i0.y, i1.z))], t.x);
    float c11 = mix(v.v[base + cell_index(m, ivec3(i0.x, i1.y, i1.z))], v.v[base + cell_index(m, i1)], t.x);
    return mix(mix(c00, c10, t.y), mix(c01, c11, t.y), t.z);
}

/// Component `axis` at world point x of the face field `faces` of a grid of `dims` cells of `h` m from
/// `origin`: trilinear on the component's lattice, clamped to it (the caller keeps x inside the grid).
float cascade_component(uint64_t faces, ivec3 dims, float h, vec3 origin, uint axis, vec3 x) {
    vec3 q = (x - origin) / h - vec3(0.5) + 0.5 * vec3(axis_unit(axis));
    return lattice_value(faces, face_base(dims, axis), dims + axis_unit(axis), q);
}

/// The blend's width in cells where the next coarser cascade reads open fraction `open` there:
/// kCascadeBlendCells in open air, 1 at kCascadeSolidShare of solid or more.
float blend_cells_for(float open) {
    float share = clamp((open - (1.0 - kCascadeSolidShare)) / kCascadeSolidShare, 0.0, 1.0);
    return 1.0 + (kCascadeBlendCells - 1.0) * share;
}

/// The blend's width in cells at world point x, by how open the next coarser cascade (SolverBindings at
/// `coarser`) is there: its open fractions (1 − cell_solid) trilinear on its cell centres, as its wind
/// texture's sampler reads them. kCascadeBlendCells in open air; 1 where its cells around x hold
/// kCascadeSolidShare of solid or more, since a coarse grid resolves the solid it cuts coarsely: a floor
/// laid under the ground, or a border beside a hill, then keeps the finer cascade's air by the solid.
float cascade_blend_cells(uint64_t coarser, vec3 x) {
    BindingsRef r = BindingsRef(coarser);
    vec3 q = (x - r.b.origin) / r.b.h - vec3(0.5);
    return blend_cells_for(1.0 - lattice_value(r.b.cell_solid, 0, r.b.dims, q));
}

/// How much a cascade's own answer counts at p (cell units of its grid of `dims` cells): 0 outside it,
/// rising to 1 over its last `blend` cells, so that no seam shows where the next coarser cascade's answer
/// takes over.
float cascade_weight(vec3 p, ivec3 dims, float blend) {
    vec3 inside = min(p, vec3(dims) - p);
    return clamp(min(inside.x, min(inside.y, inside.z)) / blend, 0.0, 1.0);
}

/// cascade_weight at p (world point x) of a cascade whose next coarser one has the SolverBindings at
/// `coarser`, over cascade_blend_cells: the coarser cascade's solids are read only inside the blend.
float nested_weight(vec3 p, ivec3 dims, uint64_t coarser, vec3 x) {
    float w = cascade_weight(p, dims, kCascadeBlendCells);
    return w > 0.0 && w < 1.0 ? cascade_weight(p, dims, cascade_blend_cells(coarser, x)) : w;
}

/// Component `axis` of the wind beyond this grid at world point x: the coarser cascades' in turn, each
/// blended into the next towards its border (the coarsest wholly inside its grid), then the ambient wind.
float beyond_component(uint axis, vec3 x) {
    if (!nested(kNestOuter)) return hot.ambient[axis];
    float sum = 0.0, left = 1.0;
    uint64_t at = sb().b.outer;
    for (uint k = 0u; k < kMaxCascades && at != 0ul && left > 0.0; ++k) {
        BindingsRef r = BindingsRef(at);
        ivec3 dims = r.b.dims;
        float h = r.b.h;
        vec3 origin = r.b.origin;
        uint64_t next = r.b.outer;
        vec3 p = (x - origin) / h;
        bool inside = all(greaterThanEqual(p, vec3(0.0))) && all(lessThanEqual(p, vec3(dims)));
        float w = !inside ? 0.0 : next == 0ul ? 1.0 : nested_weight(p, dims, next, x);
        if (w > 0.0) {
            // Between two of the coarser cascade's steps, in time as well as in space.
            float u = cascade_component(r.b.current, dims, h, origin, axis, x);
            float blend = r.b.time_blend;
            if (blend < 1.0)
                u = mix(cascade_component(r.b.previous, dims, h, r.b.previous_origin, axis, x), u, blend);
            sum += left * w * u;
            left *= 1.0 - w;
        }
        at = next;
    }
    return sum + left * hot.ambient[axis];
}

/// Near the border of a cascade with a coarser one beyond, the share of the coarser wind face f takes each
/// step: 1 on the border, falling to 0 kCascadeBlendCells in (a relaxation zone, as nested weather models
/// have), so that the border agrees with the coarser cascade where the answer blends into it.
float border_relaxation(uint axis, ivec3 f) {
    if (!nested(kNestOuter)) return 0.0;
    vec3 p = vec3(f) + vec3(0.5) - 0.5 * vec3(axis_unit(axis));
    vec3 inside = min(p, vec3(grid_dims()) - p);
    return clamp(1.0 - min(inside.x, min(inside.y, inside.z)) / kCascadeBlendCells, 0.0, 1.0);
}

/// Whether the next finer cascade covers face f, at least one of this grid's cells inside its border; then
/// `u`, its wind averaged over the face (ratio^2 points on it).
bool inner_face(uint axis, ivec3 f, out float u) {
    u = 0.0;
    if (!nested(kNestInner)) return false;
    uint64_t at = sb().b.inner;
    BindingsRef r = BindingsRef(at);
    ivec3 dims = r.b.dims;
    float h = r.b.h;
    vec3 origin = r.b.origin;
    vec3 x = grid_origin() + (vec3(f) + vec3(0.5) - 0.5 * vec3(axis_unit(axis))) * grid_h();
    vec3 p = (x - origin) / h;
    float ratio = grid_h() / h;
    if (any(lessThan(p, vec3(ratio))) || any(greaterThan(p, vec3(dims) - vec3(ratio)))) return false;
    uint64_t faces = r.b.current;
    uint b = (axis + 1u) % 3u, d = (axis + 2u) % 3u;
    int n = max(int(round(ratio)), 1);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            vec3 y = x;
            y[b] += ((float(i) + 0.5) / float(n) - 0.5) * grid_h();
            y[d] += ((float(j) + 0.5) / float(n) - 0.5) * grid_h();
            u += cascade_component(faces, dims, h, origin, axis, y);
        }
    u /= float(n * n);
    return true;
}

uint64_t face_field(uint field) {
    bool swapped = (pc.swap & 1u) != 0u;
    if (field == kFieldVelocity) return swapped ? hot.velocity_tmp : hot.velocity;
    if (field == kFieldTmp) return swapped ? hot.velocity : hot.velocity_tmp;
    if (field == kFieldScratch) return hot.velocity_back;
    if (field == kFieldSolid) return hot.solid_velocity;
    return hot.velocity_back + uint64_t(field - kFieldSolid) * uint64_t(hot.level0_faces) * 4ul;
}
uint64_t cell_field(uint field) {
    if (field == kCellPressure) return hot.pressure;
    if (field == kCellRhs) return hot.rhs;
    if (field == kCellScratch) return hot.scratch;
    if (field == kCellPressureUp) return hot.pressure_up;
    ivec3 n = hot.dims;
    // The conjugate-gradient iteration's parity (swap bit 1) says which of each pair is current.
    bool odd = (pc.swap & 2u) != 0u;
    if (odd && (field == kCellSolution || field == kCellDirection)) field += 4u;
    else if (odd && (field == kCellSolutionB || field == kCellDirectionB)) field -= 4u;
    uint slot = field <= kCellOldResidual ? field - kCellSolution : field - kCellSolutionB + 4u;
    return hot.cg_cells + uint64_t(slot) * uint64_t(n.x * n.y * n.z) * 4ul;
}
float load_face(uint field, int index) { return FloatsRef(face_field(field)).v[index]; }
/// Level 0's open fraction from its byte count, coarser levels' weights from their floats.
float load_weight(int index) {
    if (index >= hot.level0_faces) return FloatsRef(hot.weights).v[index - hot.level0_faces];
    uint word = WordsRef(hot.open_counts).v[index >> 2];
    return open_fraction_of(open_count_in(word, uint(index)), hot.pair_share);
}
#ifdef GUST_COARSE_SHARED
// coarse_solve.comp keeps the levels it solves in shared memory (coarse_phi, coarse_rhs, from global cell
// index coarse_base on; the first level's right-hand side stays in memory), so the shared kernels below
// (relax_cell, restrict_cell, prolong_cell) run on them unchanged. Downward and upward values are one
// array there.
float load_cell(uint field, int index) {
    int at = index - int(coarse_base);
    if (at >= 0 && (field == kCellPressure || field == kCellPressureUp)) return coarse_phi[at];
    if (at >= int(coarse_rhs_from) && field == kCellRhs) return coarse_rhs[at - int(coarse_rhs_from)];
    return CellsRef(cell_field(field)).v[index];
}
#else
float load_cell(uint field, int index) { return CellsRef(cell_field(field)).v[index]; }
#endif
vec4 load_vorticity(int index) { return Vec4Ref(hot.vorticity).v[index]; }
vec4 load_confinement(int index) { return Vec4Ref(hot.confinement).v[index]; }
/// The step's pressure solution at level-0 cell `index` as the solve left it: x + α p (or + z for plain
/// multigrid) of the iterate and direction the state names, 0 after a diverged solve.
float load_phi(int index) {
    StateRef st = state();
    if (st.s.diverged != 0u) return 0.0;
    float x = FloatsRef(cell_field(st.s.x_slot == 0u ? kCellSolution : kCellSolutionB)).v[index];
    float alpha = st.s.cg_alpha;
    if (alpha == 0.0) return x;
    uint p = st.s.p_slot;
    uint direction = p == 0u ? kCellDirection : (p == 1u ? kCellDirectionB : kCellPressureUp);
    return x + alpha * FloatsRef(cell_field(direction)).v[index];
}

void store_face(uint field, int index, float value) { FloatsRef(face_field(field)).v[index] = value; }
void store_cell(uint field, int index, float value) { CellsRef(cell_field(field)).v[index] = value; }

// Workgroup maximum of |value|s, folded into a global counter by one thread per group (non-negative
// floats order like their bits). Every thread of the group must call begin and end.
shared uint group_max;
void group_max_begin() {
    if (gl_LocalInvocationIndex == 0u) group_max = 0u;
    barrier();
}
void group_max_add(float value) { atomicMax(group_max, floatBitsToUint(abs(value))); }
/// The group's maximum (float bits) on thread 0, after all threads added theirs.
bool group_max_end(out uint bits) {
    barrier();
    bits = group_max;
    return gl_LocalInvocationIndex == 0u;
}

// Reductions over a whole dispatch in the dispatch itself (the "last workgroup" pattern): every group stores
// its partial result, counts itself done with an atomic, and the group that counts last folds all partials
// in a fixed order, so a step gives the same result every run on a device. Partials are read only by that
// group, after the others' writes (released by a memory barrier before their count), through a coherent
// reference.
layout(buffer_reference, scalar) coherent buffer PartialsRef { vec2 v[]; };
layout(buffer_reference, scalar) coherent buffer CoherentStateRef { SolverState s; };

uint group_linear() { return gl_WorkGroupID.x + gl_NumWorkGroups.x * (gl_WorkGroupID.y + gl_NumWorkGroups.y * gl_WorkGroupID.z); }
uint group_total() { return gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z; }

shared bool group_is_last;
/// Called by every thread once thread 0 has written this group's partial: true in every thread of the group
/// that finished last (the others' partials and atomics are then visible to it).
bool last_group() {
    memoryBarrierBuffer();
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        uint seen = atomicAdd(state().s.reduce_count, 1u);
        group_is_last = seen + 1u == group_total();
        if (group_is_last) state().s.reduce_count = 0u;
    }
    barrier();
    memoryBarrierBuffer();
    return group_is_last;
}

// Workgroup sums of two values into shared memory (every thread must call them).
shared vec2 group_sums[kSolverGroupSize];
/// The workgroup's sum of `value` (valid in every thread after the call); groups up to kSolverGroupSize
/// threads wide use one slot per thread, wider ones fold in strides.
vec2 group_sum(vec2 value) {
    uint t = gl_LocalInvocationIndex;
    uint width = gl_WorkGroupSize.x * gl_WorkGroupSize.y * gl_WorkGroupSize.z;
    if (t < kSolverGroupSize) group_sums[t] = vec2(0.0);
    barrier();
    for (uint lane = 0u; lane < (width + kSolverGroupSize - 1u) / kSolverGroupSize; ++lane) {
        if (t / kSolverGroupSize == lane) group_sums[t % kSolverGroupSize] += value;
        barrier();
    }
    [[unroll]] for (uint s = kSolverGroupSize / 2u; s > 0u; s >>= 1u) {
        if (t < s) group_sums[t] += group_sums[t + s];
        barrier();
    }
    vec2 total = group_sums[0];
    barrier();
    return total;
}
/// Stores this group's sum of `value` as its partial; in the group that finished last, returns the sum of
/// all partials (in group order) in `total` and true.
bool sum_dispatch(vec2 value, out vec2 total) {
    vec2 mine = group_sum(value);
    if (gl_LocalInvocationIndex == 0u) PartialsRef(sb().b.partials).v[group_linear()] = mine;
    total = vec2(0.0);
    if (!last_group()) return false;
    uint t = gl_LocalInvocationIndex;
    uint width = gl_WorkGroupSize.x * gl_WorkGroupSize.y * gl_WorkGroupSize.z;
    vec2 sum = vec2(0.0);
    PartialsRef partials = PartialsRef(sb().b.partials);
    for (uint g = t; g < group_total(); g += width) sum += partials.v[g];
    total = group_sum(sum);
    return true;
}

/// A cell's six face layers (−x,+x,−y,+y,−z,+z), made once on the CPU; only the cell's words are loaded
/// (each buffer-reference load costs a loop over the SIMD lanes on llvmpipe), the others are empty.
void load_face_masks(out CellBits faces[6]) {
    BindingsRef r = sb();
    uint cw = hot.cell_words;
    for (uint s = 0u; s < 6u; ++s) {
        faces[s] = bits_none();
        for (uint k = 0u; k < cw; ++k) faces[s].w[k] = r.b.face_mask[s * kCellWords + k];
    }
}

// ---- Cell parts, the outside-air fill and the solid's motion (solver_io.h, "cell_flags") -----------------

uint flags_at(int i) { return WordsRef(hot.cell_flags).v[i]; }

/// Part k of level-0 cell i: from cell_parts for a cut cell; a cell without solid voxels is one whole part.
CellBits part_of(int i, uint flags, uint k) {
    uint v = hot.voxels_per_cell;
    if ((flags & kCellCut) == 0u) return k == 0u ? bits_all(v) : bits_none();
    CellBits b = bits_none();
    uint cw = hot.cell_words;
    uint base = (kCellParts * uint(i) + k) * cw;
    for (uint w = 0u; w < cw; ++w) b.w[w] = WordsRef(hot.cell_parts).v[base + w];
    return b;
}

/// The solid voxels of level-0 cell i: those in neither of its parts (none in a cell without solid).
CellBits solid_of(int i, uint flags) {
    CellBits all = bits_all(hot.voxels_per_cell);
    return bits_and_not(bits_and_not(all, part_of(i, flags, 0u)), part_of(i, flags, 1u));
}

/// The static solid voxels of level-0 cell i (none unless it is kCellStatic).
CellBits static_of(int i, uint flags) {
    if ((flags & kCellStatic) == 0u) return bits_none();
    CellBits b = bits_none();
    uint cw = hot.cell_words;
    for (uint w = 0u; w < cw; ++w) b.w[w] = WordsRef(hot.cell_static).v[uint(i) * cw + w];
    return b;
}

/// The air of cell i: the part whose air reaches an open side; none in a kCellNoAir cell.
CellBits air_of(int i, uint flags) {
    if ((flags & kCellNoAir) != 0u) return bits_none();
    return part_of(i, flags, (flags & kCellSecondPart) != 0u ? 1u : 0u);
}

// Union-find over part nodes (Jaiganesh and Burtscher 2018, ECL-CC): a root is hooked under the smaller of
// two roots by compare-and-swap, so parents only ever decrease and every chain ends; finds halve paths with
// atomicMin. Other invocations' writes may be read late: a stale read only costs a failed swap, whose
// returned value is current, so each retry moves to a smaller id.
layout(buffer_reference, scalar) buffer LabelsRef { uint v[]; };

uint uf_find(uint x) {
    LabelsRef labels = LabelsRef(hot.labels);
    uint parent = labels.v[x];
    while (parent != x) {
        uint grand = labels.v[parent];
        if (grand < parent) atomicMin(labels.v[x], grand);
        x = parent;
        parent = grand;
    }
    return x;
}

void uf_unite(uint a, uint b) {
    LabelsRef labels = LabelsRef(hot.labels);
    for (;;) {
        a = uf_find(a);
        b = uf_find(b);
        if (a == b) return;
        if (a > b) {
            uint t = a;
            a = b;
            b = t;
        }
        uint seen = atomicCompSwap(labels.v[b], b, a);
        if (seen == b) return;
        b = seen;
    }
}

/// Fixed-point velocity sums and their weight for the sealed region whose root is `root` (enclosing_motion);
/// zero for the outside air or a region that touches no solid.
ivec4 region_of(uint root) {
    if (root == kOutsideNode) return ivec4(0);
    uint part = (root - 1u) % kCellParts;
    if ((flags_at(int((root - 1u) / kCellParts)) & (kCellRegion << part)) == 0u) return ivec4(0);
    IVec4Ref regions = IVec4Ref(hot.region_motion);
    return enclosing_motion(regions.v[2u * root], regions.v[2u * root + 1u].x);
}

/// Fixed-point velocity sums and their count for the solid in cell i: its moving fragments'; in a cell
/// without air, else, its sealed region's (region_of); zero for static solids.
ivec4 solid_motion_of(int i, uint flags) {
    if ((flags & kCellMoving) != 0u) return IVec4Ref(hot.cell_motion).v[i];
    if ((flags & kCellNoAir) == 0u) return ivec4(0);
    return region_of(LabelsRef(hot.labels).v[part_node(uint(i), 0u)]);
}

vec3 motion_velocity(ivec4 m) { return m.w > 0 ? vec3(m.xyz) / (kVelocityScale * float(m.w)) : vec3(0.0); }

// ---- The pressure solve's convergence check -------------------------------------------------------------

/// Run by one thread of the workgroup that finishes a check's pass last (the residual's maximum gathered in
/// residual_scratch): records the residual and which iterate holds x, and once the residual is within
/// tolerance of max |b| (or diverged, solve_diverged) marks the solve done, makes that iterate final (α = 0)
/// and zeroes the live dispatches, so the remaining recorded work does nothing. The reference is max |b|,
/// not the first residual: a warm start begins with a small residual, and measuring against it would stop
/// short.
void convergence_check(uint x_slot) {
    StateRef st = state();
    float residual = uintBitsToFloat(st.s.residual_scratch);
    st.s.residual_scratch = 0u;
    if (st.s.done != 0u) return;
    st.s.x_slot = x_slot;
    float b_max = uintBitsToFloat(st.s.divergence_before);
    if (st.s.checks == 0u) st.s.first_residual = floatBitsToUint(residual);
    bool diverged = solve_diverged(residual, uintBitsToFloat(st.s.first_residual), b_max);
    if (residual <= sb().b.tolerance * b_max || diverged) {
        st.s.done = 1u;
        st.s.diverged = diverged ? 1u : 0u;
        st.s.cg_alpha = 0.0;
        DispatchRef live = DispatchRef(sb().b.dispatch);
        for (uint s = 0u; s < kDispatchSlots; ++s) live.v[s] = LevelDispatch(0u, 0u, 0u);
    } else {
        st.s.checks += 1u;
    }
}

#include "solver_kernels.h"

// ---- What engines read ---------------------------------------------------------------------------------

/// The voxel of cell `cell` that point p (cell units) lies in, as a bit of a CellBits.
uint voxel_bit(vec3 p, int cell) {
    ivec3 c = cell_from_index(grid_dims(), cell);
    int v = int(hot.voxels_per_cell);
    ivec3 voxel = clamp(ivec3(floor((p - vec3(c)) * float(v))), ivec3(0), ivec3(v - 1));
    return uint(voxel.x + v * (voxel.y + v * voxel.z));
}

/// Whether point p (cell units, inside the grid) lies in a solid: in a cell without air, or in a voxel of a
/// cut cell that is not the cell's air.
bool in_solid(vec3 p, int cell, uint flags) {
    if ((flags & kCellNoAir) != 0u) return true;
    if ((flags & kCellCut) == 0u) return false;
    return !bits_get(air_of(cell, flags), voxel_bit(p, cell));
}

/// The velocity of the solid at point p (cell units) in cell `cell`, where in_solid: in a sealed part, its
/// region's (region_of); in a static voxel, 0; in a moving one, the cell's fragments' mean. A point inside a
/// static building stays still beside a mover that brushes its wall (the whole cell answered the mover's).
vec3 solid_velocity_at(vec3 p, int cell, uint flags) {
    LabelsRef labels = LabelsRef(hot.labels);
    if ((flags & kCellCut) == 0u) return motion_velocity(region_of(labels.v[part_node(uint(cell), 0u)]));
    uint bit = voxel_bit(p, cell);
    for (uint k = 0u; k < kCellParts; ++k)
        if (bits_get(part_of(cell, flags, k), bit))
            return motion_velocity(region_of(labels.v[part_node(uint(cell), k)]));
    if (bits_get(static_of(cell, flags), bit)) return vec3(0.0);
    return (flags & kCellMoving) != 0u ? motion_velocity(IVec4Ref(hot.cell_motion).v[cell]) : vec3(0.0);
}

/// Whether cell i's centre touches its air: the cell has air, and one of the voxels whose closed box holds
/// the centre is in it. With an even count of voxels a side the centre is the corner of the 8 middle voxels,
/// so a surface voxel on one side of it does not make a centre in the open air solid (issue 42: cells 28 %
/// solid, their centre 0.37 m from a sphere, reported 0 m/s when the corner's +x+y+z voxel held surface).
bool centre_in_air(int i, uint flags) {
    if ((flags & kCellNoAir) != 0u) return false;
    if ((flags & kCellCut) == 0u) return true;
    int v = int(hot.voxels_per_cell);
    int lo = (v - 1) / 2, hi = v / 2;
    CellBits air = air_of(i, flags);
    for (int z = lo; z <= hi; ++z)
        for (int y = lo; y <= hi; ++y)
            for (int x = lo; x <= hi; ++x)
                if (bits_get(air, uint(x + v * (y + v * z)))) return true;
    return false;
}

/// Velocity at cell i's centre as reported: where the centre touches the cell's air (centre_in_air), the
/// air's (its faces' means, a closed face left out: cell_air_velocity; and the omni emitters' wind), else the
/// solid's own (a cell without air, or a cut cell's centre beyond its wall, which reported the other side's
/// wind).
vec3 cell_output(int i) {
    uint flags = flags_at(i);
    ivec3 c = cell_from_index(grid_dims(), i);
    vec3 centre = vec3(c) + 0.5;
    if (!centre_in_air(i, flags)) return solid_velocity_at(centre, i, flags);
    return cell_air_velocity(kFieldVelocity, c) + omni_velocity(centre);
}

layout(buffer_reference, scalar) writeonly buffer TexelsRef { uvec2 v[]; };
layout(buffer_reference, scalar) readonly buffer TexelsIn { uvec2 v[]; };

/// Texel c of the cascade whose texels are at `texels`: velocity xyz (m/s) and open fraction.
vec4 texel_at(uint64_t texels, ivec3 dims, ivec3 c) {
    uvec2 t = TexelsIn(texels).v[cell_index(dims, c)];
    return vec4(unpackHalf2x16(t.x), unpackHalf2x16(t.y));
}

/// The texels of a cascade of `dims` cells read at p (its cell units) as its wind texture's sampler reads
/// them: trilinear on the cell centres, clamped to the edge.
vec4 texels_trilinear(uint64_t texels, ivec3 dims, vec3 p) {
    vec3 q = clamp(p - vec3(0.5), vec3(0.0), vec3(dims - ivec3(1)));
    ivec3 i0 = min(ivec3(floor(q)), max(dims - ivec3(2), ivec3(0)));
    ivec3 i1 = min(i0 + ivec3(1), dims - ivec3(1));
    vec3 t = q - vec3(i0);
    vec4 c00 = mix(texel_at(texels, dims, i0), texel_at(texels, dims, ivec3(i1.x, i0.y, i0.z)), t.x);
    vec4 c10 = mix(texel_at(texels, dims, ivec3(i0.x, i1.y, i0.z)),
                   texel_at(texels, dims, ivec3(i1.x, i1.y, i0.z)), t.x);
    vec4 c01 = mix(texel_at(texels, dims, ivec3(i0.x, i0.y, i1.z)),
                   texel_at(texels, dims, ivec3(i1.x, i0.y, i1.z)), t.x);
    vec4 c11 = mix(texel_at(texels, dims, ivec3(i0.x, i1.y, i1.z)), texel_at(texels, dims, i1), t.x);
    return mix(mix(c00, c10, t.y), mix(c01, c11, t.y), t.z);
}

/// The wind at world point x as the engine's shaders read it (gust_wind.glsl's gust_wind): from this
/// cascade's texels and each coarser one's, finest first, each trilinear on its cell centres and blended into
/// the next coarser one over its last cells (kCascadeBlendCells, 1 where the coarser one's texels read
/// kCascadeSolidShare of solid or more), beyond the coarsest the ambient wind. A cascade without bound texels
/// is passed over. One definition of the wind at a point (issue 42): System::query, the texture and the
/// snapshot all answer it.
vec3 texel_wind(vec3 x) {
    vec3 sum = vec3(0.0);
    float left = 1.0;
    uint64_t at = pc.bindings;
    for (uint k = 0u; k < kMaxCascades && at != 0ul && left > 0.0; ++k) {
        BindingsRef r = BindingsRef(at);
        ivec3 dims = r.b.dims;
        uint64_t texels = r.b.texels, next = r.b.outer;
        vec3 p = (x - r.b.origin) / r.b.h;
        bool inside = all(greaterThanEqual(p, vec3(0.0))) && all(lessThanEqual(p, vec3(dims)));
        if (inside && texels != 0ul) {
            float w = 1.0;
            if (next != 0ul) {
                w = cascade_weight(p, dims, kCascadeBlendCells);
                if (w > 0.0 && w < 1.0) {
                    BindingsRef c = BindingsRef(next);
                    float open = c.b.texels == 0ul
                                     ? 1.0
                                     : texels_trilinear(c.b.texels, c.b.dims, (x - c.b.origin) / c.b.h).w;
                    w = cascade_weight(p, dims, blend_cells_for(open));
                }
            }
            if (w > 0.0) {
                sum += left * w * texels_trilinear(texels, dims, p).xyz;
                left *= 1.0 - w;
            }
        }
        at = next;
    }
    return sum + left * hot.ambient;
}
/// Cell i's texel of the wind texture: cell_output and 1 − solid fraction, as four half floats.
void store_texel(int i) {
    vec3 u = cell_output(i);
    float open = 1.0 - FloatsRef(hot.cell_solid).v[i];
    TexelsRef(sb().b.texels).v[i] = uvec2(packHalf2x16(u.xy), packHalf2x16(vec2(u.z, open)));
}
