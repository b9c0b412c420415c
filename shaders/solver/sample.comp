#version 460
#extension GL_GOOGLE_include_directive : require
// Reading the field. pc.mode kSampleWind: per point, the wind as engines read it (texel_wind: the cascades'
// texels, trilinear and blended as gust_wind.glsl). kSamplePoints: per point, the solver's own field there
// (WindReading::Solver): inside a solid (a voxel that is not its cell's air, or a cell without air) the
// solid's own velocity, in the air trilinear on the faces (extended into the solid, so no wall's zeros mix
// in) plus the omni emitters' wind; outside the grid the wind beyond it (the ambient wind, or the coarser
// cascades', blended in over the last cells).
// kSampleTexels: per cell, a texel of the wind texture (store_texel; a step's finish.comp writes the bound
// texels, so this serves the first fill and tests). kSampleCells: per cell, the velocity at its centre
// (cell_output) as three floats into `samples`.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

// Points and samples are 3 floats each, as the host's arrays hold them: an array of vec3 (a stride of 12)
// would need scalarBlockLayout.
layout(buffer_reference, scalar) readonly buffer PointsRef { float v[]; };
layout(buffer_reference, scalar) writeonly buffer SamplesRef { float v[]; };

vec3 point(int i) {
    PointsRef points = PointsRef(sb().b.points);
    return vec3(points.v[3 * i], points.v[3 * i + 1], points.v[3 * i + 2]);
}

void store_sample(int i, vec3 u) {
    SamplesRef samples = SamplesRef(sb().b.samples);
    samples.v[3 * i] = u.x;
    samples.v[3 * i + 1] = u.y;
    samples.v[3 * i + 2] = u.z;
}

void main() {
    load_bindings();
    int i = thread_index();
    ivec3 n = grid_dims();
    if (pc.mode == kSampleWind) {
        if (i >= int(sb().b.point_count)) return;
        store_sample(i, texel_wind(point(i)));
    } else if (pc.mode == kSamplePoints) {
        if (i >= int(sb().b.point_count)) return;
        vec3 p = (point(i) - grid_origin()) / grid_h();
        vec3 x = grid_origin() + p * grid_h();
        // Towards the border of a cascade with coarser ones beyond, the answer blends into theirs.
        float own = !inside_grid(p) ? 0.0 : !nested(kNestOuter) ? 1.0 : nested_weight(p, n, sb().b.outer, x);
        vec3 u = vec3(0.0);
        if (own > 0.0) {
            int cell = cell_index(n, clamp(ivec3(floor(p)), ivec3(0), n - 1));
            uint flags = flags_at(cell);
            u = own * (in_solid(p, cell, flags) ? solid_velocity_at(p, cell, flags)
                                                : sample_velocity(kFieldVelocity, p) + omni_velocity(p));
        }
        if (own < 1.0)
            u += (1.0 - own) * vec3(beyond_component(0u, x), beyond_component(1u, x), beyond_component(2u, x));
        store_sample(i, u);
    } else {
        if (i >= n.x * n.y * n.z) return;
        if (pc.mode == kSampleCells)
            store_sample(i, cell_output(i));
        else
            store_texel(i);
    }
}
