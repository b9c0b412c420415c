#version 460
#extension GL_GOOGLE_include_directive : require
// Per moving fragment: adds its surface velocity, its length clamped to the solid speed limit, to its wind
// cell's fixed-point sum and marks the cell kCellMoving (later passes read the sums of marked cells only;
// solid_cells clears them next step).
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    if (uint(i) >= state().s.fragments) return;
    uint key = WordsRef(sb().b.fragments).v[i];
    ivec3 voxel = ivec3(key & 1023u, (key >> 10) & 1023u, (key >> 20) & 1023u) - sb().b.voxel_offset;
    if (any(lessThan(voxel, ivec3(0)))) return;
    ivec3 c = voxel / int(hot.voxels_per_cell);
    if (!inside_cells(hot.dims, c)) return;
    uvec2 packed = UVec2Ref(sb().b.fragment_motion).v[i];
    vec3 velocity = vec3(unpackHalf2x16(packed.x), unpackHalf2x16(packed.y).x);
    ivec3 fixed_point = ivec3(round(clamp_speed(velocity, sb().b.max_solid_speed) * kVelocityScale));
    int cell = cell_index(hot.dims, c);
    IVec4Ref motion = IVec4Ref(hot.cell_motion);
    atomicAdd(motion.v[cell].x, fixed_point.x);
    atomicAdd(motion.v[cell].y, fixed_point.y);
    atomicAdd(motion.v[cell].z, fixed_point.z);
    if (atomicAdd(motion.v[cell].w, 1) == 0) atomicOr(WordsRef(hot.cell_flags).v[cell], kCellMoving);
}
