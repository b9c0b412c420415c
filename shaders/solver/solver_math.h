// Pure functions of the wind grid shared by the solver's shaders and solver/ (written in the GLSL/GLM
// common subset, shaders/common.h): indexing of the MAC grid (solver_io.h), the emitters' profiles and
// the pressure solve's scalar formulas.
#ifndef GUST_SOLVER_MATH_H
#define GUST_SOLVER_MATH_H

#include "solver_io.h"

GUST_NAMESPACE_BEGIN

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

/// The open sides of a cascade nested in a coarser one: every side is held at the coarser wind (so the flux
/// through each matches the coarser cascade's) but the one the ambient wind leaves through along its largest
/// component, which stays open (φ = 0) to carry the difference; without an ambient wind every side is open.
GUST_INLINE uint nested_open_sides(vec3 ambient) {
    vec3 a = abs(ambient);
    if (!(max(a.x, max(a.y, a.z)) > 0.0f)) return 63u;
    uint axis = a.x >= a.y && a.x >= a.z ? 0u : a.y >= a.z ? 1u : 2u;
    return 1u << (2u * axis + (ambient[axis] > 0.0f ? 1u : 0u));
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

#endif
