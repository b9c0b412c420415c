#version 460
#extension GL_GOOGLE_include_directive : require
// Per face of every multigrid level above level 0 at once: the mean open fraction of the level-0 faces it
// covers (coarse_weight), so the coarse levels cost one dispatch, not one each.
#include "solver_io.h"
layout(local_size_x = kSolverGroupSize) in;
#include "solver_common.glsl"

void main() {
    load_bindings();
    int i = thread_index();
    uint levels = sb().b.levels;
    uint first = uint(hot.level0_faces);
    GridLevel last = load_level(levels - 1u);
    int total = int(last.faces - first) + faces_total(last.dims);
    if (levels < 2u || i >= total) return;
    uint face = first + uint(i);
    uint l = 1u;
    while (l + 1u < levels && face >= load_level(l + 1u).faces) ++l;
    GridLevel level = load_level(l);
    uint axis;
    ivec3 f = face_from_index(level.dims, int(face - level.faces), axis);
    FloatsRef(hot.weights).v[i] = coarse_weight(l, axis, f);
}
