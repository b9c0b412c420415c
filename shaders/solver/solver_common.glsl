// Buffers, accessors and helpers shared by the solver passes; then the shared kernels.
#extension GL_EXT_control_flow_attributes : enable
#include "solver_io.h"

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

layout(push_constant, scalar) uniform Push { SolverPush pc; };

BindingsRef sb() { return BindingsRef(pc.bindings); }
StateRef state() { return StateRef(sb().b.state); }

/// Linear thread index over a 2D grid of workgroups (rows of at most 65,535).
int thread_index() {
    return int((gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kSolverGroupSize + gl_LocalInvocationID.x);
}

ivec3 grid_dims() { return sb().b.dims; }
float grid_h() { return sb().b.h; }
vec3 grid_origin() { return sb().b.origin; }
vec3 grid_ambient() { return sb().b.ambient; }
uint grid_open_sides() { return sb().b.open_sides; }
GridLevel load_level(uint l) { return sb().b.level[l]; }
uint emitter_count() { return sb().b.emitter_count; }
GpuEmitter load_emitter(uint i) { return EmittersRef(sb().b.emitters).v[i]; }

uint64_t face_field(uint field) {
    if (field == kFieldVelocity) return sb().b.velocity;
    if (field == kFieldTmp) return sb().b.velocity_tmp;
    if (field == kFieldBack) return sb().b.velocity_back;
    return sb().b.solid_velocity;
}
uint64_t cell_field(uint field) {
    if (field == kCellPressure) return sb().b.pressure;
    if (field == kCellRhs) return sb().b.rhs;
    if (field == kCellScratch) return sb().b.scratch;
    if (field == kCellPressureTmp) return sb().b.pressure_tmp;
    ivec3 n = sb().b.dims;
    return sb().b.cg_cells + uint64_t(field - kCellSolution) * uint64_t(n.x * n.y * n.z) * 4ul;
}
float load_face(uint field, int index) { return FloatsRef(face_field(field)).v[index]; }
/// Level 0's open fraction from its byte count, coarser levels' weights from their floats.
float load_weight(int index) {
    int level0 = int(sb().b.level0_faces);
    if (index >= level0) return FloatsRef(sb().b.weights).v[index - level0];
    uint word = WordsRef(sb().b.open_counts).v[index >> 2];
    return open_fraction_of(open_count_in(word, uint(index)), sb().b.pair_share);
}
float load_cell(uint field, int index) { return FloatsRef(cell_field(field)).v[index]; }
vec4 load_vorticity(int index) { return Vec4Ref(sb().b.vorticity).v[index]; }

void store_face(uint field, int index, float value) { FloatsRef(face_field(field)).v[index] = value; }
void store_cell(uint field, int index, float value) { FloatsRef(cell_field(field)).v[index] = value; }

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

// Workgroup sums of two values, stored by thread 0 as the group's entry in partials (summed in a fixed
// order by cg_scalars, so a step's result does not depend on scheduling). Every thread must call it.
shared vec2 group_sums[kSolverGroupSize];
void group_sum_store(vec2 value) {
    uint t = gl_LocalInvocationIndex;
    group_sums[t] = value;
    barrier();
    [[unroll]] for (uint s = kSolverGroupSize / 2u; s > 0u; s >>= 1u) {
        if (t < s) group_sums[t] += group_sums[t + s];
        barrier();
    }
    if (t == 0u) Vec2Ref(sb().b.partials).v[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x] = group_sums[0];
}

/// A cell's six face layers (−x,+x,−y,+y,−z,+z), made once on the CPU.
void load_face_masks(out CellBits faces[6]) {
    for (uint s = 0u; s < 6u; ++s)
        for (uint k = 0u; k < kCellWords; ++k) faces[s].w[k] = sb().b.face_mask[s * kCellWords + k];
}

// ---- Cell parts, the outside-air fill and the solid's motion (solver_io.h, "cell_flags") -----------------

uint flags_at(int i) { return WordsRef(sb().b.cell_flags).v[i]; }

/// Part k of level-0 cell i: from cell_parts for a cut cell; a cell without solid voxels is one whole part.
CellBits part_of(int i, uint flags, uint k) {
    uint v = sb().b.voxels_per_cell;
    if ((flags & kCellCut) == 0u) return k == 0u ? bits_all(v) : bits_none();
    CellBits b = bits_none();
    uint cw = sb().b.cell_words;
    uint base = (kCellParts * uint(i) + k) * cw;
    for (uint w = 0u; w < cw; ++w) b.w[w] = WordsRef(sb().b.cell_parts).v[base + w];
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
    LabelsRef labels = LabelsRef(sb().b.labels);
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
    LabelsRef labels = LabelsRef(sb().b.labels);
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

/// Fixed-point velocity sums and their count for the solid in cell i: its moving fragments'; in a cell
/// without air, else, its sealed region's (the summed mean velocities of the region's moving cells); zero
/// for static solids.
ivec4 solid_motion_of(int i, uint flags) {
    if ((flags & kCellMoving) != 0u) return IVec4Ref(sb().b.cell_motion).v[i];
    if ((flags & kCellNoAir) == 0u) return ivec4(0);
    uint root = LabelsRef(sb().b.labels).v[part_node(uint(i), 0u)];
    if (root == kOutsideNode) return ivec4(0);
    uint part = (root - 1u) % kCellParts;
    if ((flags_at(int((root - 1u) / kCellParts)) & (kCellRegion << part)) == 0u) return ivec4(0);
    return IVec4Ref(sb().b.region_motion).v[root];
}

vec3 motion_velocity(ivec4 m) { return m.w > 0 ? vec3(m.xyz) / (kVelocityScale * float(m.w)) : vec3(0.0); }

#include "solver_kernels.h"
