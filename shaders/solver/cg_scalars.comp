#version 460
#extension GL_GOOGLE_include_directive : require
// One workgroup: sums the per-group partials of cg.comp (or divergence.comp's warm start) in a fixed
// order, then pc.parity 0 sets β (and keeps r·z for the next iteration), 1 sets α, 2 the warm start's
// scale.
#include "solver_common.glsl"

// The workgroup is as wide as the device allows (constant 0, a power of two from 64 to 1024): at 128^3
// there are 32,768 partials, and a narrow group would add them one slow load after another.
layout(local_size_x_id = 0) in;

shared vec2 sums[gl_WorkGroupSize.x];

void main() {
    uint t = gl_LocalInvocationIndex;
    Vec2Ref partials = Vec2Ref(sb().b.partials);
    vec2 sum = vec2(0.0);
    for (uint g = t; g < sb().b.partial_count; g += gl_WorkGroupSize.x) sum += partials.v[g];
    sums[t] = sum;
    barrier();
    for (uint s = gl_WorkGroupSize.x / 2u; s > 0u; s >>= 1u) {
        if (t < s) sums[t] += sums[t + s];
        barrier();
    }
    if (t != 0u) return;
    StateRef st = state();
    vec2 total = sums[0];
    if (pc.parity == 0u) {
        st.s.cg_beta = cg_beta(total.x, total.y, st.s.cg_rz);
        st.s.cg_rz = total.x;
    } else if (pc.parity == 1u) {
        st.s.cg_alpha = cg_alpha(st.s.cg_rz, total.x);
    } else {
        st.s.warm_scale = warm_scale(total.x, total.y);
    }
}
