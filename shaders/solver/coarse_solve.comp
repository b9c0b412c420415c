#version 460
#extension GL_GOOGLE_include_directive : require
// One workgroup solves every level from pc.level down to the coarsest in shared memory (coarse_levels.glsl,
// pc.iterations sweeps on the coarsest, pc.mode kCoarseCorrection or kCoarseBeta): levels of at most
// kCoarseCells cells (16^3) cost this one dispatch together, where a dispatch per sweep and level cost
// microseconds whatever its size. Recorded only where the coarse solve holds level 0 (a grid that small);
// on larger grids the smoothing before it runs it in its last workgroup (smooth.comp, GUST_THEN_COARSE).
#include "solver_io.h"
#include "coarse_shared.glsl"

// As wide as the device allows (constant 0, a power of two from 64 to 1024).
layout(local_size_x_id = 0) in;
#include "solver_common.glsl"
#include "coarse_levels.glsl"

void main() {
    load_bindings();
    coarse_solve(pc.level, pc.iterations, pc.mode);
}
