#version 460
#extension GL_GOOGLE_include_directive : require
// Sizes the moving-fragment pass from the voxelizer's counter.
#include "solver_common.glsl"

layout(local_size_x = 1) in;

void main() {
    uint count = sb().b.fragments == 0ul ? 0u : min(WordsRef(sb().b.fragment_count).v[0], sb().b.fragment_capacity);
    uint groups = (count + kSolverGroupSize - 1u) / kSolverGroupSize;
    state().s.fragments_dispatch = LevelDispatch(min(groups, 65535u), (groups + 65534u) / 65535u, 1u);
    state().s.fragments = count;
}
