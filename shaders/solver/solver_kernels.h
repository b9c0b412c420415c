// Per-face and per-cell kernels of the wind solver, written once for the shaders and for the CPU
// version (solver/src/cpu_wind.cpp). Not a standalone header: the includer first defines the
// accessors below, as GLSL functions over device buffers or as C++ members over host arrays (the C++
// side includes this inside a struct).
//
//   ivec3 grid_dims();  float grid_h();  vec3 grid_origin();  uint grid_open_sides();
//   float load_face(uint field, int index);    kField* arrays, level-0 face indices
//   float load_weight(int index);              weight array (level offsets included)
//   float load_cell(uint field, int index);    kCell* arrays (level offsets included)
//   vec4 load_vorticity(int index);            level-0 cells
//   vec4 load_confinement(int index);          level-0 cells: cell_confinement, made earlier in the step
//   float load_phi(int index);                 level-0 cells: the step's pressure solution φ
//   GridLevel load_level(uint level);
//   uint emitter_count();  GpuEmitter load_emitter(uint i);  uint omni_count();  (omni emitters first)
//   float beyond_component(uint axis, vec3 x);  component `axis` of the wind beyond the grid at world
//                                               point x: the coarser cascades' (cascades), else the ambient
//   float border_relaxation(uint axis, ivec3 f); share of the wind beyond the grid face f takes each step
//                                               (cascades: 1 at the border, 0 from kCascadeBlendCells in)
//   bool inner_face(uint axis, ivec3 f, GUST_OUT(float) u);  whether a finer cascade covers face f, and
//                                               its wind averaged over the face (cascades; else false)

// ---- Sampling the staggered grid ------------------------------------------------------------------

/// Centre of face f normal to `axis`, in cell units from the grid's min corner.
GUST_INLINE vec3 face_position(uint axis, ivec3 f) {
    return vec3(f) + vec3(0.5f) - 0.5f * vec3(axis_unit(axis));
}

/// The lattice cell of component `axis` holding p (cell units): corners i0..i1 and weights t.
GUST_INLINE void component_lattice(uint axis, vec3 p, GUST_OUT(ivec3) i0, GUST_OUT(ivec3) i1,
                                   GUST_OUT(vec3) t) {
    ivec3 m = grid_dims() + axis_unit(axis);
    vec3 q = p - vec3(0.5f) + 0.5f * vec3(axis_unit(axis));
    q = clamp(q, vec3(0.0f), vec3(m - ivec3(1)));
    i0 = min(ivec3(floor(q)), max(m - ivec3(2), ivec3(0)));
    i1 = min(i0 + ivec3(1), m - ivec3(1));
    t = q - vec3(i0);
}

GUST_INLINE bool inside_grid(vec3 p) {
    vec3 n = vec3(grid_dims());
    return p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.x <= n.x && p.y <= n.y && p.z <= n.z;
}

/// Whether face g of the lattice of component `axis` exists.
GUST_INLINE bool face_in_lattice(uint axis, ivec3 g) {
    ivec3 m = grid_dims() + axis_unit(axis);
    return g.x >= 0 && g.y >= 0 && g.z >= 0 && g.x < m.x && g.y < m.y && g.z < m.z;
}

/// Whether face g normal to `axis` exists and has open voxel pairs: air crosses it.
GUST_INLINE bool face_open(uint axis, ivec3 g) {
    return face_in_lattice(axis, g) && load_weight(face_index(grid_dims(), axis, g)) > 0.0f;
}

/// Whether air crosses from cell c to its neighbour c + s e_b (s = ±1).
GUST_INLINE bool passage(ivec3 c, uint b, int s) {
    return face_open(b, s > 0 ? c + axis_unit(b) : c);
}

/// The lattice point of component `axis` that `corner` of a trilinear stencil around a point in cell c
/// reads: the corner itself when its cell (the corner's position across the two other axes, b and d) is
/// reached from c through open faces (`reach`: the neighbour along b, along d, the diagonal one), else c's
/// own face at that place along `axis`, so that the air on c's side stands in for whatever lies beyond a
/// closed face.
GUST_INLINE ivec3 visible_corner(ivec3 corner, ivec3 c, uint b, uint d, bvec3 reach) {
    bool across_b = corner[b] != c[b], across_d = corner[d] != c[d];
    bool seen = across_b ? (across_d ? reach.z : reach.x) : (across_d ? reach.y : true);
    if (seen) return corner;
    ivec3 own = corner;
    own[b] = c[b];
    own[d] = c[d];
    return own;
}

/// Component `axis` of face field `field` at p, trilinear, and the smallest and largest of the eight
/// lattice values it blends (MacCormack's clamp); the wind beyond the grid outside it. The stencil spans p's
/// cell c and up to three neighbours across the two other axes; a neighbour that no open face joins to c
/// (a wall between them, thin or thick) is read as c's own value, so no sample mixes the air beyond a
/// closed face into this side's (issue 31). Along `axis` the stencil reads c's own two faces: where one is
/// closed it holds the wall's velocity or this side's extension (project_extend_face).
GUST_INLINE float sample_component_range(uint field, uint axis, vec3 p, GUST_OUT(vec2) range) {
    if (!inside_grid(p)) {
        float beyond = beyond_component(axis, grid_origin() + p * grid_h());
        range = vec2(beyond);
        return beyond;
    }
    ivec3 i0, i1;
    vec3 t;
    component_lattice(axis, p, i0, i1, t);
    ivec3 n = grid_dims();
    ivec3 c = clamp(ivec3(floor(p)), ivec3(0), n - ivec3(1));
    uint b = (axis + 1u) % 3u, d = (axis + 2u) % 3u;
    int sb = i0[b] == c[b] ? 1 : -1, sd = i0[d] == c[d] ? 1 : -1;
    bool open_b = passage(c, b, sb), open_d = passage(c, d, sd);
    bool diagonal = (open_b && passage(c + sb * axis_unit(b), d, sd)) ||
                    (open_d && passage(c + sd * axis_unit(d), b, sb));
    bvec3 reach = bvec3(open_b, open_d, diagonal);
    float c000 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i0.x, i0.y, i0.z), c, b, d, reach)));
    float c100 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i1.x, i0.y, i0.z), c, b, d, reach)));
    float c010 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i0.x, i1.y, i0.z), c, b, d, reach)));
    float c110 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i1.x, i1.y, i0.z), c, b, d, reach)));
    float c001 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i0.x, i0.y, i1.z), c, b, d, reach)));
    float c101 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i1.x, i0.y, i1.z), c, b, d, reach)));
    float c011 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i0.x, i1.y, i1.z), c, b, d, reach)));
    float c111 =
        load_face(field, face_index(n, axis, visible_corner(ivec3(i1.x, i1.y, i1.z), c, b, d, reach)));
    range = vec2(min(min(min(c000, c100), min(c010, c110)), min(min(c001, c101), min(c011, c111))),
                 max(max(max(c000, c100), max(c010, c110)), max(max(c001, c101), max(c011, c111))));
    float c00 = mix(c000, c100, t.x), c10 = mix(c010, c110, t.x);
    float c01 = mix(c001, c101, t.x), c11 = mix(c011, c111, t.x);
    return mix(mix(c00, c10, t.y), mix(c01, c11, t.y), t.z);
}

/// Component `axis` of face field `field` at p, trilinear (the compilers drop the unused range).
GUST_INLINE float sample_component(uint field, uint axis, vec3 p) {
    vec2 unused;
    return sample_component_range(field, axis, p, unused);
}

GUST_INLINE vec3 sample_velocity(uint field, vec3 p) {
    return vec3(sample_component(field, 0u, p), sample_component(field, 1u, p),
                sample_component(field, 2u, p));
}

// ---- Advection (Stam 1999; MacCormack after Selle et al. 2008) ---------------------------------------

/// The velocity of `field` at face f's centre: the face's own component and, for the two others, the
/// mean of the four faces around the centre (the two cells beside f, clamped to the grid). This is what
/// sample_velocity gives there, from 9 loads instead of 24.
GUST_INLINE vec3 face_velocity(uint field, uint axis, ivec3 f) {
    ivec3 n = grid_dims();
    ivec3 lo = f, hi = f;
    lo[axis] = max(f[axis] - 1, 0);
    hi[axis] = min(f[axis], n[axis] - 1);
    vec3 v = vec3(0.0f);
    for (uint b = 0u; b < 3u; ++b) {
        ivec3 e = axis_unit(b);
        v[b] = b == axis ? load_face(field, face_index(n, axis, f))
                         : 0.25f * (load_face(field, face_index(n, b, lo)) +
                                    load_face(field, face_index(n, b, lo + e)) +
                                    load_face(field, face_index(n, b, hi)) +
                                    load_face(field, face_index(n, b, hi + e)));
    }
    return v;
}

/// The omni emitters' radial wind at p (cell units), m/s. A radial wind is all divergence, so it is not
/// part of the solved field, whose projection removed it (an 8 m/s emitter left 0.08 m/s), nor can it
/// be: kept as a divergence source, advection of that divergent field fed a rotational part no
/// projection removes (1.3 m/s beyond the radius after 500 steps, still growing). It is added to the
/// field where the air is carried and where the wind is reported, as a potential flow is superposed:
/// the sum of the omni emitters' profiles.
GUST_INLINE vec3 omni_velocity(vec3 p) {
    vec3 x = grid_origin() + p * grid_h();
    vec3 u = vec3(0.0f);
    for (uint e = 0u; e < omni_count(); ++e)
        u += emitter_velocity(load_emitter(e), x);
    return u;
}

/// The way from `from` to `to` (cell units, starting in cell `at`) up to its first closed face: `to` when
/// it crosses none (or leaves the grid, whose outside is the ambient wind), else the point where it meets the
/// face, pulled just inside the cell before it. Cells are walked in the order the way enters them (Amanatides
/// and Woo 1987); after 8 crossings, more than any trace at a CFL number below two makes, the way stops in
/// the cell it reached.
GUST_INLINE vec3 clip_to_air(vec3 from, vec3 to, ivec3 at) {
    ivec3 n = grid_dims();
    vec3 dir = to - from;
    ivec3 heading = ivec3(sign(dir));
    const float inset = 1e-3f;
    for (int k = 0; k < 8; ++k) {
        vec3 reach = vec3(2.0f);
        for (uint a = 0u; a < 3u; ++a)
            if (heading[a] != 0) reach[a] = (float(at[a] + max(heading[a], 0)) - from[a]) / dir[a];
        uint b = reach.x <= reach.y && reach.x <= reach.z ? 0u : (reach.y <= reach.z ? 1u : 2u);
        if (reach[b] >= 1.0f) return to;
        ivec3 next = at + heading[b] * axis_unit(b);
        if (!inside_cells(n, next)) return to;
        if (!passage(at, b, heading[b]))
            return clamp(from + reach[b] * dir, vec3(at) + vec3(inset), vec3(at + ivec3(1)) - vec3(inset));
        at = next;
    }
    return clamp(to, vec3(at) + vec3(inset), vec3(at + ivec3(1)) - vec3(inset));
}

/// Where the air at face f's centre was dt seconds ago (dt < 0: where it will be), in cell units,
/// midpoint rule, carried by the field and the omni emitters' wind. Both legs stop at the first closed face
/// they meet (clip_to_air), so air is never fetched from beyond a wall; the trace starts in the cell beside f
/// it heads into.
GUST_INLINE vec3 trace(uint axis, ivec3 f, float dt) {
    vec3 x = face_position(axis, f);
    float s = dt / grid_h();
    vec3 mid = x - 0.5f * s * (face_velocity(kFieldVelocity, axis, f) + omni_velocity(x));
    ivec3 start = f;
    if (mid[axis] < x[axis]) start[axis] -= 1;
    start = clamp(start, ivec3(0), grid_dims() - ivec3(1));
    mid = clip_to_air(x, mid, start);
    vec3 p = x - s * (sample_velocity(kFieldVelocity, mid) + omni_velocity(mid));
    start = f;
    if (p[axis] < x[axis]) start[axis] -= 1;
    start = clamp(start, ivec3(0), grid_dims() - ivec3(1));
    return clip_to_air(x, p, start);
}

/// Semi-Lagrangian: face f of `field` carried by the velocity field over dt. A closed face keeps its value:
/// the projection sets it from the solid (project_extend_face), and no air arrives there.
GUST_INLINE float advect_face(uint field, uint axis, ivec3 f, float dt) {
    if (!face_open(axis, f)) return load_face(field, face_index(grid_dims(), axis, f));
    return sample_component(field, axis, trace(axis, f, dt));
}

/// MacCormack's forward pass: face f of the velocity carried over dt, and in `range` the smallest and
/// largest of the values it blended (kFieldLow, kFieldHigh for the correction's clamp).
GUST_INLINE float advect_face_range(uint axis, ivec3 f, float dt, GUST_OUT(vec2) range) {
    if (!face_open(axis, f)) {
        float u = load_face(kFieldVelocity, face_index(grid_dims(), axis, f));
        range = vec2(u);
        return u;
    }
    return sample_component_range(kFieldVelocity, axis, trace(axis, f, dt), range);
}

/// MacCormack's backward pass and correction of face f: the forward result (kFieldScratch) carried back
/// over dt, and the forward result corrected by half the error that finds, clamped to the values the forward
/// pass blended (stays bounded). The backward pass needs no field of its own: each face's backward value
/// is used only by its own correction.
GUST_INLINE float maccormack_face(uint axis, ivec3 f, float dt) {
    int i = face_index(grid_dims(), axis, f);
    float backward = advect_face(kFieldScratch, axis, f, -dt);
    float corrected = load_face(kFieldScratch, i) + 0.5f * (load_face(kFieldVelocity, i) - backward);
    return clamp(corrected, load_face(kFieldLow, i), load_face(kFieldHigh, i));
}

// ---- Forces -----------------------------------------------------------------------------------------------

GUST_INLINE vec3 cell_velocity(uint field, ivec3 c) {
    ivec3 n = grid_dims();
    vec3 v = vec3(0.0f);
    for (uint a = 0u; a < 3u; ++a)
        v[a] = 0.5f *
               (load_face(field, face_index(n, a, c)) + load_face(field, face_index(n, a, c + axis_unit(a))));
    return v;
}

/// The air's velocity at cell c's centre: per axis the mean of its two faces, or the open one's alone where
/// the other is closed (a wall on that face holds the solid's velocity or the extension, not the air here).
GUST_INLINE vec3 cell_air_velocity(uint field, ivec3 c) {
    ivec3 n = grid_dims();
    vec3 v = vec3(0.0f);
    for (uint a = 0u; a < 3u; ++a) {
        ivec3 hi = c + axis_unit(a);
        float low = load_face(field, face_index(n, a, c)), high = load_face(field, face_index(n, a, hi));
        bool open_low = face_open(a, c), open_high = face_open(a, hi);
        v[a] = open_low == open_high ? 0.5f * (low + high) : (open_low ? low : high);
    }
    return v;
}

/// The neighbours of cell c along `axis` that a difference may use: c ± e_axis where air crosses to it,
/// else c itself (one-sided at walls and the domain's faces; none through a closed face, issue 31).
GUST_INLINE void difference_span(ivec3 c, uint axis, GUST_OUT(ivec3) lo, GUST_OUT(ivec3) hi) {
    ivec3 n = grid_dims();
    ivec3 e = axis_unit(axis);
    hi = c[axis] + 1 < n[axis] && passage(c, axis, 1) ? c + e : c;
    lo = c[axis] > 0 && passage(c, axis, -1) ? c - e : c;
}

/// Curl of the air's cell-centred velocity (cell_air_velocity) by central differences, one-sided where a
/// closed face or the domain's face is on one side, none across one closed on both; and its length.
GUST_INLINE vec4 cell_vorticity(ivec3 c) {
    vec3 d[3]; // d[a] = ∂v/∂x_a
    for (uint a = 0u; a < 3u; ++a) {
        ivec3 lo, hi;
        difference_span(c, a, lo, hi);
        float span = float(hi[a] - lo[a]) * grid_h();
        d[a] = span > 0.0f
                   ? (cell_air_velocity(kFieldVelocity, hi) - cell_air_velocity(kFieldVelocity, lo)) / span
                   : vec3(0.0f);
    }
    vec3 w = vec3(d[1].z - d[2].y, d[2].x - d[0].z, d[0].y - d[1].x);
    return vec4(w, length(w));
}

/// Vorticity confinement (Fedkiw et al. 2001) force at cell c, per unit mass: ε h (N × ω), N the unit
/// gradient of |ω|, whose differences take no cell beyond a closed face (difference_span).
GUST_INLINE vec3 confinement_force(ivec3 c, float epsilon) {
    ivec3 n = grid_dims();
    vec3 g = vec3(0.0f);
    for (uint a = 0u; a < 3u; ++a) {
        ivec3 lo, hi;
        difference_span(c, a, lo, hi);
        float span = float(hi[a] - lo[a]) * grid_h();
        g[a] = span > 0.0f
                   ? (load_vorticity(cell_index(n, hi)).w - load_vorticity(cell_index(n, lo)).w) / span
                   : 0.0f;
    }
    float len = length(g);
    if (!(len > 1e-12f)) return vec3(0.0f);
    return epsilon * grid_h() * cross(g / len, vec3(load_vorticity(cell_index(n, c))));
}

/// Cell c's confinement force (xyz, confinement_force) and the speed of its velocity (w), made once per cell
/// early in the step (solid_cells.comp) for confinement_change, which would otherwise redo both for the two
/// cells of every face.
GUST_INLINE vec4 cell_confinement(ivec3 c, float epsilon) {
    return vec4(confinement_force(c, epsilon), length(cell_velocity(kFieldVelocity, c)));
}

/// Vorticity confinement's change of face f over dt, from the vorticity the last step ended with
/// (load_vorticity, through load_confinement): fusing the force into advection's pass costs that one step
/// of lag, where computing this step's curl first would cost a pass. The step is limited to the local CFL
/// time (h / speed, the speed of kFieldVelocity's two cells), so a large dt cannot make the force
/// overshoot; none on the domain's faces.
GUST_INLINE float confinement_change(uint axis, ivec3 f, float dt, float epsilon) {
    ivec3 n = grid_dims();
    if (epsilon == 0.0f || boundary_side(n, axis, f) != 6u) return 0.0f;
    vec4 a = load_confinement(cell_index(n, f - axis_unit(axis))), b = load_confinement(cell_index(n, f));
    float speed = max(a.w, b.w);
    float step = speed > 0.0f ? min(dt, grid_h() / speed) : dt;
    return step * 0.5f * (a[axis] + b[axis]);
}

/// Face f of the next field from advection's value `u` there: the wind beyond the grid on the domain's
/// faces (the ambient wind, or the next coarser cascade's); else the emitters (`rate` of the gap each), then
/// vorticity confinement (confinement_change), then, where a finer cascade covers f, drawn by
/// kCascadeFeedback towards its wind, and near the border of a cascade inside a coarser one, drawn towards
/// the coarser wind (border_relaxation).
GUST_INLINE float forced_face(float u, uint axis, ivec3 f, float rate, float dt, float epsilon) {
    vec3 x = grid_origin() + face_position(axis, f) * grid_h();
    if (boundary_side(grid_dims(), axis, f) != 6u) return beyond_component(axis, x);
    // The omni emitters, first in the list, are added where the field is read, not driven into it
    // (omni_velocity).
    for (uint e = omni_count(); e < emitter_count(); ++e)
        u = emitter_drive(u, emitter_velocity(load_emitter(e), x)[axis], rate);
    u += confinement_change(axis, f, dt, epsilon);
    float finer;
    if (inner_face(axis, f, finer)) u = mix(u, finer, kCascadeFeedback);
    float relax = border_relaxation(axis, f);
    return relax > 0.0f ? mix(u, beyond_component(axis, x), relax) : u;
}

/// One Jacobi iteration of implicit viscosity (u − α∇²u·h² = u0 with α = ν dt / h^2): face f from the
/// iterate in `field`; u0 is kFieldVelocity, the wind beyond the grid outside it.
GUST_INLINE float diffuse_face(uint field, uint axis, ivec3 f, float alpha) {
    ivec3 n = grid_dims();
    ivec3 m = n + axis_unit(axis);
    float sum = 0.0f;
    for (uint a = 0u; a < 3u; ++a)
        for (int s = -1; s <= 1; s += 2) {
            ivec3 g = f + s * axis_unit(a);
            bool inside = g.x >= 0 && g.y >= 0 && g.z >= 0 && g.x < m.x && g.y < m.y && g.z < m.z;
            sum += inside ? load_face(field, face_index(n, axis, g))
                          : beyond_component(axis, grid_origin() + face_position(axis, g) * grid_h());
        }
    // (u0 + α·sum) / (1 + 6α) as u0·(1 − 6w) + sum·w with w = 1 / (6 + 1/α), finite for every α: a huge
    // viscosity (α·sum past a float) gives the neighbours' mean, not inf / inf.
    float w = 1.0f / (6.0f + 1.0f / clamp(alpha, 1e-30f, 1e30f));
    return load_face(kFieldVelocity, face_index(n, axis, f)) * (1.0f - 6.0f * w) + sum * w;
}

// ---- Projection with face weights (Batty, Bertails and Bridson 2007) -------------------------------------

/// Volume flux per unit area through face i when the air there moves at u: the open part carries the air,
/// the closed part moves with the solid (free slip: only normal velocities meet).
GUST_INLINE float face_flux_of(int i, float u) {
    float open = load_weight(i);
    return open * u + (1.0f - open) * load_face(kFieldSolid, i);
}

/// face_flux_of the velocity field's value at face f.
GUST_INLINE float face_flux(uint axis, ivec3 f) {
    int i = face_index(grid_dims(), axis, f);
    return face_flux_of(i, load_face(kFieldVelocity, i));
}

/// The solver's divergence of cell c (1/s): net outward flux over the cell's volume.
GUST_INLINE float cell_divergence(ivec3 c) {
    float net = 0.0f;
    for (uint a = 0u; a < 3u; ++a)
        net += face_flux(a, c + axis_unit(a)) - face_flux(a, c);
    return net / grid_h();
}

/// Face 2a + s of cell c of `level` (s = 0: the low side) in the Laplacian: its weight over h², 0 when
/// the face is closed or an inflow side, and in `neighbour` the cell across it (index within the level),
/// or -1 beyond an open domain side, where φ = 0.
GUST_INLINE float face_coupling(GridLevel level, uint open, ivec3 c, uint a, uint s,
                                GUST_OUT(int) neighbour) {
    ivec3 f = s == 0u ? c : c + axis_unit(a);
    ivec3 nb = s == 0u ? c - axis_unit(a) : c + axis_unit(a);
    neighbour = -1;
    float w = load_weight(int(level.faces) + face_index(level.dims, a, f)) * level.inv_h2[a];
    if (w == 0.0f) return 0.0f;
    if (inside_cells(level.dims, nb)) {
        neighbour = cell_index(level.dims, nb);
        return w;
    }
    if ((open >> (2u * a + s) & 1u) == 0u) return 0.0f;
    // Level 0 holds φ = 0 in a ghost cell one cell out, i.e. h_0/2 beyond the side. A coarser level
    // (cells h_l along this axis) keeps φ = 0 at that same place, (h_l + h_0)/2 from its cell centre
    // rather than h_l, or its correction would treat the boundary as farther out than level 0 does.
    float h_level = inversesqrt(level.inv_h2[a]);
    return h_level > 1.5f * grid_h() ? w * (2.0f * h_level / (h_level + grid_h())) : w;
}

/// The weighted Laplacian at cell c of `level`: diag = Σ w over the open faces, off = Σ w·(φ_nb − centre)
/// (φ = 0 beyond open domain sides; inflow sides add nothing), so (Lφ)_c = off − diag·(φ_c − centre).
/// With centre = φ_c, off is (Lφ)_c itself, summed from differences: off − diag·φ_c would cancel the
/// digits that matter once φ is large beside its gradient (float keeps ~7), and stall the solve above
/// its tolerance. Relaxation likewise adds a small correction to φ_c rather than recomputing it.
GUST_INLINE void cell_operator(GridLevel level, ivec3 c, uint field, float centre, GUST_OUT(float) diag,
                               GUST_OUT(float) off) {
    uint open = grid_open_sides();
    diag = 0.0f;
    off = 0.0f;
    for (uint a = 0u; a < 3u; ++a)
        for (uint s = 0u; s < 2u; ++s) {
            int nb;
            float w = face_coupling(level, open, c, a, s, nb);
            if (w == 0.0f) continue;
            diag += w;
            if (nb >= 0)
                off += w * (load_cell(field, int(level.cells) + nb) - centre);
            else
                off -= w * centre;
        }
}

/// (Lφ)_c at cell c of `level` for φ in `field`; 0 where no face is open.
GUST_INLINE float laplacian_cell(GridLevel level, ivec3 c, uint field) {
    float diag, lap;
    cell_operator(level, c, field, load_cell(field, int(level.cells) + cell_index(level.dims, c)), diag, lap);
    return diag > 0.0f ? lap : 0.0f;
}

/// Gauss–Seidel / Jacobi update of φ at cell c of `level` from the values in `field`.
GUST_INLINE float relax_cell(GridLevel level, ivec3 c, uint field) {
    int i = int(level.cells) + cell_index(level.dims, c);
    float phi = load_cell(field, i);
    float diag, lap;
    cell_operator(level, c, field, phi, diag, lap);
    if (!(diag > 0.0f)) return 0.0f;
    return phi + (lap - load_cell(kCellRhs, i)) / diag;
}

/// Damped Jacobi update of φ at level-0 cell c (`level0`) from the values in `field`.
GUST_INLINE float jacobi_cell(GridLevel level0, ivec3 c, uint field) {
    float old = load_cell(field, cell_index(grid_dims(), c));
    return mix(old, relax_cell(level0, c, field), kJacobiWeight);
}

/// Residual b − Lφ at cell c of `level` (φ in kCellPressure); 0 where no face is open.
GUST_INLINE float residual_cell(GridLevel level, ivec3 c) {
    int i = int(level.cells) + cell_index(level.dims, c);
    float diag, lap;
    cell_operator(level, c, kCellPressure, load_cell(kCellPressure, i), diag, lap);
    return diag > 0.0f ? load_cell(kCellRhs, i) - lap : 0.0f;
}

/// Right-hand side of coarse cell C of the level after `fine`: the mean residual of its children, computed
/// here from the finer level's φ, so no residual pass (and no residual array) lies between smoothing and
/// restriction.
GUST_INLINE float restrict_cell(GridLevel fine, ivec3 C) {
    ivec3 k = fine.factor;
    float sum = 0.0f;
    for (int z = 0; z < k.z; ++z)
        for (int y = 0; y < k.y; ++y)
            for (int x = 0; x < k.x; ++x) {
                ivec3 c = C * k + ivec3(x, y, z);
                if (inside_cells(fine.dims, c)) sum += residual_cell(fine, c);
            }
    return sum / float(k.x * k.y * k.z);
}

/// Weight of face F (normal to `axis`) of coarse level l: the mean open fraction of the level-0 faces it
/// covers (the mean of the means level by level, so every coarse level comes straight from level 0 in one
/// pass); level-0 faces past the grid count as closed.
GUST_INLINE float coarse_weight(uint l, uint axis, ivec3 F) {
    ivec3 k = ivec3(1);
    for (uint m = 0u; m < l; ++m)
        k *= load_level(m).factor;
    ivec3 span = k;
    span[axis] = 1;
    ivec3 n0 = grid_dims();
    ivec3 m = n0 + axis_unit(axis);
    float sum = 0.0f;
    for (int z = 0; z < span.z; ++z)
        for (int y = 0; y < span.y; ++y)
            for (int x = 0; x < span.x; ++x) {
                ivec3 f = F * k + ivec3(x, y, z);
                f[axis] = min(F[axis] * k[axis], n0[axis]);
                if (f.x < m.x && f.y < m.y && f.z < m.z) sum += load_weight(face_index(n0, axis, f));
            }
    return sum / float(span.x * span.y * span.z);
}

/// Correction for fine cell c of level `fine` from the next level, `coarse` (its values in `coarse_field`):
/// cell-centred trilinear interpolation (3/4 of the parent, 1/4 of its neighbour along each halved axis)
/// through the coarse face between them, in proportion to its open fraction θ; the closed part acts as a wall
/// (zero gradient: the parent's value). Past a domain side the neighbour is the boundary: a closed side is a
/// wall, an open side's φ = 0 (half a level-0 cell out, as face_coupling puts it) is interpolated toward
/// through the side's open part.
GUST_INLINE float prolong_cell(GridLevel fine, GridLevel coarse, ivec3 c, uint coarse_field) {
    ivec3 k = fine.factor;
    ivec3 parent = c / k;
    ivec3 toward = ivec3(0);
    vec3 own = vec3(1.0f), across = vec3(0.0f);
    for (uint a = 0u; a < 3u; ++a) {
        if (k[a] != 2) continue;
        toward[a] = (c[a] & 1) != 0 ? 1 : -1;
        ivec3 f = toward[a] > 0 ? parent + axis_unit(a) : parent;
        float theta = load_weight(int(coarse.faces) + face_index(coarse.dims, a, f));
        int q = parent[a] + toward[a];
        if (q >= 0 && q < coarse.dims[a]) {
            across[a] = 0.25f * theta;
            own[a] = 1.0f - across[a];
        } else if ((grid_open_sides() >> (2u * a + (toward[a] > 0 ? 1u : 0u)) & 1u) != 0u) {
            float h_coarse = inversesqrt(coarse.inv_h2[a]);
            own[a] = 1.0f - theta * 0.5f * h_coarse / (h_coarse + grid_h());
        }
    }
    float sum = 0.0f;
    for (int corner = 0; corner < 8; ++corner) {
        ivec3 pick = ivec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        float w = 1.0f;
        for (uint a = 0u; a < 3u; ++a)
            w *= pick[a] == 0 ? own[a] : across[a];
        if (w == 0.0f) continue;
        sum +=
            w * load_cell(coarse_field, int(coarse.cells) + cell_index(coarse.dims, parent + pick * toward));
    }
    return sum;
}

/// Face f after the pressure gradient (`gradient` false: a diverged solve, solve_diverged, projects
/// nothing): closed faces move with the solid; inflow sides keep the ambient wind; φ is 0 beyond open sides.
GUST_INLINE float project_face(uint axis, ivec3 f, bool gradient) {
    ivec3 n = grid_dims();
    int i = face_index(n, axis, f);
    float open = load_weight(i);
    if (open == 0.0f) return load_face(kFieldSolid, i);
    float u = load_face(kFieldVelocity, i);
    uint side = boundary_side(n, axis, f);
    if (!gradient || (side != 6u && (grid_open_sides() >> side & 1u) == 0u)) return u;
    ivec3 lo = f - axis_unit(axis);
    float p_lo = inside_cells(n, lo) ? load_phi(cell_index(n, lo)) : 0.0f;
    float p_hi = inside_cells(n, f) ? load_phi(cell_index(n, f)) : 0.0f;
    return u - (p_hi - p_lo) / grid_h();
}

// ---- The air's velocity extended into closed faces -----------------------------------------------------

/// Whether face g holds the air's velocity after `layer` extension passes: open (0), or closed next to an
/// open face of its lattice (1).
GUST_INLINE bool face_has_air(uint axis, ivec3 g, uint layer) {
    ivec3 n = grid_dims();
    if (load_weight(face_index(n, axis, g)) > 0.0f) return true;
    if (layer == 0u) return false;
    for (uint b = 0u; b < 3u; ++b)
        for (int s = -1; s <= 1; s += 2) {
            ivec3 nb = g + s * axis_unit(b);
            if (face_in_lattice(axis, nb) && load_weight(face_index(n, axis, nb)) > 0.0f) return true;
        }
    return false;
}

/// Which lattice neighbours of closed face f (normal to `axis`) lend it their velocity in the first extension
/// pass, as bits 2b + (s > 0) for the neighbour f + s e_b; the air's own side only. With air in one of f's
/// two cells, the open neighbours that air reaches: its cell's other face along `axis`, and those beside f
/// whose cell air crosses into from it. With air in both (a wall on f, as thin walls are), none: f keeps the
/// wall's velocity, which both sides see, rather than a mean of the two sides' winds that carried the air
/// through the wall (issue 31). With air in neither, every open neighbour, as a face inside a solid is read
/// by nothing that takes air's velocity.
GUST_INLINE uint extension_sources(uint axis, ivec3 f) {
    ivec3 n = grid_dims();
    ivec3 e = axis_unit(axis);
    ivec3 lo = f - e;
    bool in_lo = inside_cells(n, lo), in_hi = inside_cells(n, f);
    uint lo_sources = 0u, hi_sources = 0u, any = 0u;
    bool air_lo = in_lo && face_open(axis, lo), air_hi = in_hi && face_open(axis, f + e);
    if (air_lo) lo_sources |= 1u << (2u * axis);
    if (air_hi) hi_sources |= 1u << (2u * axis + 1u);
    any = lo_sources | hi_sources;
    for (uint b = 0u; b < 3u; ++b) {
        if (b == axis) continue;
        for (int s = -1; s <= 1; s += 2) {
            uint bit = 1u << (2u * b + (s > 0 ? 1u : 0u));
            bool from_lo = in_lo && passage(lo, b, s), from_hi = in_hi && passage(f, b, s);
            air_lo = air_lo || from_lo;
            air_hi = air_hi || from_hi;
            if (!face_open(axis, f + s * axis_unit(b))) continue;
            any |= bit;
            if (from_lo) lo_sources |= bit;
            if (from_hi) hi_sources |= bit;
        }
    }
    if (air_lo && air_hi) return 0u;
    return air_lo ? lo_sources : (air_hi ? hi_sources : any);
}

/// Face f after the projection and the first extension pass at once (project.comp): an open face its
/// projected velocity, a closed one the mean of the projected velocities of the open lattice neighbours on
/// its air's side (extension_sources), any other the solid's (extend_face's layer 1 over project_face's
/// values, each computed where it is read).
GUST_INLINE float project_extend_face(uint axis, ivec3 f, bool gradient) {
    ivec3 n = grid_dims();
    if (face_has_air(axis, f, 0u)) return project_face(axis, f, gradient);
    uint sources = extension_sources(axis, f);
    float sum = 0.0f, count = 0.0f;
    for (uint b = 0u; b < 3u; ++b)
        for (int s = -1; s <= 1; s += 2) {
            if ((sources >> (2u * b + (s > 0 ? 1u : 0u)) & 1u) == 0u) continue;
            sum += project_face(axis, f + s * axis_unit(b), gradient);
            count += 1.0f;
        }
    return count > 0.0f ? sum / count : load_face(kFieldSolid, face_index(n, axis, f));
}

/// Face f after the projection and both extension passes at once (project.comp): a face that holds the air's
/// velocity after the first pass keeps its value there (project_extend_face); any other takes the mean of
/// the first pass's values of its lattice neighbours that hold the air's velocity after it, each computed
/// where it is read: extend_face's layer 2 over project_extend_face's values, so the second layer costs no
/// pass of its own, and only faces two deep in a solid compute their neighbours'.
GUST_INLINE float project_extended_face(uint axis, ivec3 f, bool gradient) {
    float u = project_extend_face(axis, f, gradient);
    if (face_has_air(axis, f, 1u)) return u;
    float sum = 0.0f, count = 0.0f;
    for (uint b = 0u; b < 3u; ++b)
        for (int s = -1; s <= 1; s += 2) {
            ivec3 nb = f + s * axis_unit(b);
            if (!face_in_lattice(axis, nb) || !face_has_air(axis, nb, 1u)) continue;
            sum += project_extend_face(axis, nb, gradient);
            count += 1.0f;
        }
    return count > 0.0f ? sum / count : u;
}

/// Face f of `field` after extension pass `layer` (1, then 2): a face that holds the air's velocity after
/// layer − 1 passes keeps it; a closed face takes the mean of its lattice neighbours on its air's side in the
/// first pass (extension_sources), of those that hold the air's velocity after it in the second; any other
/// keeps its value (the solid's velocity, from the projection). Two passes reach two faces into a solid,
/// so advection, vorticity, texels and queries next to a wall read the air's velocity, never the solid's
/// zeros: without it free-slip air beside a wall slowed a little every step (Bridson, Fluid Simulation
/// for Computer Graphics, 2015, extrapolates velocity into the solid for the same reason). Closed faces
/// carry no flux (face_flux), so the projection does not see these values. The second pass fills only closed
/// faces with no open lattice neighbour, deeper in a solid than the first reaches.
GUST_INLINE float extend_face(uint field, uint axis, ivec3 f, uint layer) {
    ivec3 n = grid_dims();
    float u = load_face(field, face_index(n, axis, f));
    if (face_has_air(axis, f, layer - 1u)) return u;
    uint sources = layer == 1u ? extension_sources(axis, f) : 63u;
    float sum = 0.0f, count = 0.0f;
    for (uint b = 0u; b < 3u; ++b)
        for (int s = -1; s <= 1; s += 2) {
            ivec3 nb = f + s * axis_unit(b);
            if ((sources >> (2u * b + (s > 0 ? 1u : 0u)) & 1u) == 0u) continue;
            if (layer != 1u && (!face_in_lattice(axis, nb) || !face_has_air(axis, nb, 1u))) continue;
            sum += load_face(field, face_index(n, axis, nb));
            count += 1.0f;
        }
    return count > 0.0f ? sum / count : u;
}
