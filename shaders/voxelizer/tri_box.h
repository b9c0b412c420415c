// Exact triangle / axis-aligned box overlap by the separating axis theorem (Akenine-Möller 2001):
// the box's 3 axes, the triangle's normal and the 9 cross products of edges with box axes. Closed sets:
// touching counts as overlap, which is what conservative voxelization asks for. Compiles as GLSL and C++.
#ifndef GUST_TRI_BOX_H
#define GUST_TRI_BOX_H

#include "../common.h"

GUST_NAMESPACE_BEGIN

/// True when the projections of v0,v1,v2 (box-centred) and of the box on `axis` are disjoint.
GUST_INLINE bool separated_on(vec3 axis, vec3 v0, vec3 v1, vec3 v2, vec3 half_size) {
    float p0 = dot(axis, v0);
    float p1 = dot(axis, v1);
    float p2 = dot(axis, v2);
    float r = dot(half_size, abs(axis));
    return min(p0, min(p1, p2)) > r || max(p0, max(p1, p2)) < -r;
}

/// True when the closed triangle (a,b,c) meets the closed box centre +- half_size.
GUST_INLINE bool tri_box_overlap(vec3 center, vec3 half_size, vec3 a, vec3 b, vec3 c) {
    vec3 v0 = a - center;
    vec3 v1 = b - center;
    vec3 v2 = c - center;
    vec3 lo = min(v0, min(v1, v2));
    vec3 hi = max(v0, max(v1, v2));
    if (lo.x > half_size.x || lo.y > half_size.y || lo.z > half_size.z) return false;
    if (hi.x < -half_size.x || hi.y < -half_size.y || hi.z < -half_size.z) return false;
    vec3 e0 = v1 - v0;
    vec3 e1 = v2 - v1;
    vec3 e2 = v0 - v2;
    if (separated_on(cross(e0, e1), v0, v1, v2, half_size)) return false;
    // Edge x axis: cross(e, X) = (0, e.z, -e.y), and likewise for Y and Z.
    if (separated_on(vec3(0.0f, e0.z, -e0.y), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(0.0f, e1.z, -e1.y), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(0.0f, e2.z, -e2.y), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(-e0.z, 0.0f, e0.x), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(-e1.z, 0.0f, e1.x), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(-e2.z, 0.0f, e2.x), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(e0.y, -e0.x, 0.0f), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(e1.y, -e1.x, 0.0f), v0, v1, v2, half_size)) return false;
    if (separated_on(vec3(e2.y, -e2.x, 0.0f), v0, v1, v2, half_size)) return false;
    return true;
}

/// Dominant axis of a normal: 0 (x), 1 (y) or 2 (z); ties go to the later axis.
GUST_INLINE uint dominant_axis(vec3 n) {
    vec3 a = abs(n);
    if (a.x > a.y && a.x > a.z) return 0u;
    if (a.y > a.z) return 1u;
    return 2u;
}

/// Grid coordinates -> projection space (u, v, w) with w along the dominant axis.
GUST_INLINE vec3 swizzle_to_projection(vec3 p, uint axis) {
    if (axis == 0u) return vec3(p.y, p.z, p.x);
    if (axis == 1u) return vec3(p.z, p.x, p.y);
    return p;
}

/// Projection space -> grid coordinates (inverse of swizzle_to_projection).
GUST_INLINE vec3 swizzle_from_projection(vec3 q, uint axis) {
    if (axis == 0u) return vec3(q.z, q.x, q.y);
    if (axis == 1u) return vec3(q.y, q.z, q.x);
    return q;
}

/// The voxel layers k (along w) whose slab [k, k+1] the triangle's plane can meet above the column
/// [x, x+1] x [y, y+1]: the plane's w over the column's corners, clamped to the triangle's own w range.
/// Dominant-axis projection bounds the plane's slope by 1, so this is at most four layers. Returns
/// (first, last) with first > last when empty; `n` and `a` are in projection space, n.z != 0.
GUST_INLINE ivec2 column_layers(vec3 n, vec3 a, float w_min, float w_max, float x, float y) {
    // Plane: n . (p - a) = 0  =>  w = a.z - (n.x (u - a.x) + n.y (v - a.y)) / n.z.
    float sx = -n.x / n.z;
    float sy = -n.y / n.z;
    float w00 = a.z + sx * (x - a.x) + sy * (y - a.y);
    float lo = w00 + min(sx, 0.0f) + min(sy, 0.0f);
    float hi = w00 + max(sx, 0.0f) + max(sy, 0.0f);
    // Clamped so the integer conversion below stays defined for triangles far outside the grid.
    lo = clamp(max(lo, w_min), -4.0f, 4100.0f);
    hi = clamp(min(hi, w_max), -4.0f, 4100.0f);
    // Slab k meets [lo, hi] when k <= hi and k + 1 >= lo. A small margin covers rounding of the plane
    // evaluation; the exact test decides.
    const float margin = 1e-3f;
    return ivec2(int(ceil(lo - margin)) - 1, int(floor(hi + margin)));
}

GUST_NAMESPACE_END

#endif
