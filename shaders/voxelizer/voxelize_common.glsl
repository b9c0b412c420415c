// Buffers, triangle setup and the per-column exact test shared by the raster and compute paths.
#include "tri_box.h"
#include "voxelize_io.h"

layout(buffer_reference, scalar) readonly buffer InstanceRef { VoxelizeInstance i; };
layout(buffer_reference, scalar) readonly buffer Positions { float v[]; };
layout(buffer_reference, scalar) readonly buffer Indices { uint v[]; };
layout(buffer_reference, scalar) writeonly buffer Fragments { uint v[]; };
layout(buffer_reference, scalar) writeonly buffer Velocities { uvec2 v[]; };
layout(buffer_reference, scalar) buffer Counters { VoxelizeCounters c; };
// (instance, triangle, tile) items, 3 words each: an array of uvec3 would need scalarBlockLayout.
layout(buffer_reference, scalar) buffer LargeList { uint v[]; };

layout(push_constant, scalar) uniform Push { VoxelizePush pc; };

// Pipelines made for calls without a frame time compile every velocity step out.
layout(constant_id = 0) const bool kVelocities = false;

// The instance a pass works on: pc.instance, unless the pass set another (the large pass takes each
// item's from the queue).
uint64_t item_instance = 0ul;
InstanceRef instance() { return InstanceRef(item_instance != 0ul ? item_instance : pc.instance); }

vec3 load_position(uint64_t positions, uint index) {
    Positions p = Positions(positions);
    return vec3(p.v[3u * index], p.v[3u * index + 1u], p.v[3u * index + 2u]);
}

/// Vertex `corner` of triangle `tri` in grid space (voxel units, grid min corner at 0).
vec3 load_grid_vertex(uint tri, uint corner) {
    InstanceRef inst = instance();
    uint index = Indices(inst.i.indices).v[3u * tri + corner];
    return (inst.i.to_grid * vec4(load_position(inst.i.positions, index), 1.0)).xyz;
}

/// World-space velocity (m/s) of vertex `corner` of triangle `tri` between last frame and this one,
/// as motion vectors are made: this frame's world position minus last frame's, over the frame time.
vec3 load_vertex_velocity(uint tri, uint corner) {
    InstanceRef inst = instance();
    if (!kVelocities) return vec3(0.0);
    uint index = Indices(inst.i.indices).v[3u * tri + corner];
    vec3 now = (inst.i.model * vec4(load_position(inst.i.positions, index), 1.0)).xyz;
    vec3 before = (inst.i.prev_model * vec4(load_position(inst.i.prev_positions, index), 1.0)).xyz;
    return (now - before) * inst.i.inv_dt;
}

bool is_finite(vec3 p) { return !any(isnan(p)) && !any(isinf(p)); }

// Voxels found by this invocation and not yet appended: one atomic per batch instead of per voxel,
// since every invocation contends for the same counter.
const uint kPendingCapacity = 8u;
uint pending[kPendingCapacity];
uvec2 pending_velocity[kPendingCapacity];
uint pending_count = 0u;

/// Appends the pending voxels to the fragment list; past the capacity only the counter moves, which
/// tells the host to redo the pass with a larger list.
void flush_voxels() {
    if (pending_count == 0u) return;
    uint slot = atomicAdd(Counters(pc.counters).c.fragments, pending_count);
    if (slot > 0xffffffffu - pending_count) atomicOr(Counters(pc.counters).c.wrapped, 1u);
    for (uint i = 0u; i < pending_count; ++i) {
        if (slot + i >= pc.capacity) break;
        Fragments(pc.fragments).v[slot + i] = pending[i];
        if (kVelocities) Velocities(pc.velocities).v[slot + i] = pending_velocity[i];
    }
    pending_count = 0u;
}

/// The largest velocity component the fragment list keeps (m/s): half floats end at 65504, and a larger
/// value would become infinite there and NaN in the solver's clamp. Faster surfaces keep their direction.
const float kMaxStoredSpeed = 60000.0;

/// `velocity` as the fragment list can hold it: scaled down to kMaxStoredSpeed in its largest component,
/// 0 when not finite. The solver clamps it further (max_solid_speed).
vec3 storable_velocity(vec3 velocity) {
    float largest = max(max(abs(velocity.x), abs(velocity.y)), abs(velocity.z));
    if (!is_finite(velocity)) return vec3(0.0);
    return largest > kMaxStoredSpeed ? velocity * (kMaxStoredSpeed / largest) : velocity;
}

/// Queues one voxel and its surface velocity for the fragment list (call flush_voxels() before the
/// invocation ends).
void emit_voxel(uvec3 ijk, vec3 velocity) {
    if (any(greaterThanEqual(ijk, pc.keep))) return;
    if (pc.slabs != 0u) {
        // Voxels the old grid kept are in the list already, shifted.
        ivec3 old = ivec3(ijk) + pc.slab_shift;
        if (all(greaterThanEqual(old, ivec3(0))) && all(lessThan(old, ivec3(pc.keep)))) return;
    }
    pending[pending_count] = ijk.x | (ijk.y << 10) | (ijk.z << 20);
    if (kVelocities) {
        vec3 v = storable_velocity(velocity);
        pending_velocity[pending_count] = uvec2(packHalf2x16(v.xy), packHalf2x16(vec2(v.z, 0.0)));
    }
    if (++pending_count == kPendingCapacity) flush_voxels();
}

/// A triangle in projection space (w along its dominant axis).
struct Setup {
    vec3 a, b, c, n;
    vec3 va, vb, vc; ///< vertex velocities (m/s, world)
    float w_min, w_max;
    uint axis;
    ivec2 col_lo, col_hi; ///< inclusive range of pixel columns, clipped to the grid
};

/// Whether every voxel the grid-space box [lo, hi] touches, and one more around it, lies in the old grid's
/// kept extent of a slab pass: a triangle with those bounds adds no voxel there.
bool inside_old_grid(vec3 lo, vec3 hi) {
    vec3 old_lo = lo + vec3(pc.slab_shift), old_hi = hi + vec3(pc.slab_shift);
    return all(greaterThanEqual(old_lo, vec3(1.0))) && all(lessThanEqual(old_hi, vec3(pc.keep) - 1.0));
}

/// Projects grid-space vertices; false when the triangle has zero area, lies outside the grid or, in a
/// slab pass, inside the old grid.
bool setup_triangle(vec3 g0, vec3 g1, vec3 g2, out Setup s) {
    vec3 n = cross(g1 - g0, g2 - g0);
    if (n == vec3(0.0)) return false;
    s.axis = dominant_axis(n);
    s.a = swizzle_to_projection(g0, s.axis);
    s.b = swizzle_to_projection(g1, s.axis);
    s.c = swizzle_to_projection(g2, s.axis);
    s.n = swizzle_to_projection(n, s.axis);
    vec3 lo = min(s.a, min(s.b, s.c));
    vec3 hi = max(s.a, max(s.b, s.c));
    float res = float(pc.res);
    vec3 keep = swizzle_to_projection(vec3(pc.keep), s.axis);
    if (any(greaterThan(lo, keep)) || any(lessThan(hi, vec3(0.0)))) return false;
    s.w_min = lo.z;
    s.w_max = hi.z;
    // Column x meets [lo, hi] when x <= hi and x + 1 >= lo.
    vec2 clo = clamp(ceil(lo.xy) - 1.0, vec2(0.0), vec2(res - 1.0));
    vec2 chi = clamp(floor(hi.xy), vec2(0.0), vec2(res - 1.0));
    s.col_lo = ivec2(clo);
    s.col_hi = ivec2(chi);
    return pc.slabs == 0u || !inside_old_grid(min(g0, min(g1, g2)), max(g0, max(g1, g2)));
}

/// Fills the vertex velocities of a set-up triangle.
void setup_velocities(uint tri, inout Setup s) {
    s.va = load_vertex_velocity(tri, 0u);
    s.vb = load_vertex_velocity(tri, 1u);
    s.vc = load_vertex_velocity(tri, 2u);
}

/// Surface velocity above the centre of column (x, y): the vertex velocities weighted by the
/// barycentric coordinates of the nearest point of the projected triangle (clamped, renormalised).
vec3 column_velocity(Setup s, int x, int y) {
    vec2 e0 = s.b.xy - s.a.xy;
    vec2 e1 = s.c.xy - s.a.xy;
    vec2 d = vec2(float(x) + 0.5, float(y) + 0.5) - s.a.xy;
    float den = e0.x * e1.y - e0.y * e1.x;
    vec3 w = vec3(1.0);
    if (abs(den) > 1e-20) {
        float l1 = (d.x * e1.y - d.y * e1.x) / den;
        float l2 = (e0.x * d.y - e0.y * d.x) / den;
        w = max(vec3(1.0 - l1 - l2, l1, l2), vec3(0.0));
        if (w.x + w.y + w.z <= 0.0) w = vec3(1.0);
    }
    return (w.x * s.va + w.y * s.vb + w.z * s.vc) / (w.x + w.y + w.z);
}

/// Emits every voxel of column (x, y) that the triangle meets, each confirmed by the exact test.
void voxelize_column(Setup s, int x, int y) {
    ivec2 layers = column_layers(s.n, s.a, s.w_min, s.w_max, float(x), float(y));
    int k0 = max(layers.x, 0);
    int k1 = min(layers.y, int(pc.res) - 1);
    vec3 velocity = kVelocities ? column_velocity(s, x, y) : vec3(0.0);
    for (int k = k0; k <= k1; ++k) {
        vec3 centre = vec3(float(x) + 0.5, float(y) + 0.5, float(k) + 0.5);
        if (tri_box_overlap(centre, vec3(0.5), s.a, s.b, s.c))
            emit_voxel(uvec3(swizzle_from_projection(vec3(x, y, k), s.axis)), velocity);
    }
}
