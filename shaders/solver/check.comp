#version 460
#extension GL_GOOGLE_include_directive : require
// One thread after the solve's start and after each V-cycle (or block of Jacobi iterations): records the
// residual (and, from pc.iterations, how many the step recorded) and, once it is within tolerance of the divergence before projection, zeroes the live
// dispatches so the remaining recorded work does nothing. The reference is max |b|, not the first
// residual: a warm start begins with a small residual, and measuring against it would stop short. A solve
// whose residual grows past solve_diverged's bound stops the same way, marked diverged.
#include "solver_common.glsl"

layout(local_size_x = 1) in;

void main() {
    StateRef st = state();
    st.s.recorded = pc.iterations;
    if (st.s.done != 0u) return;
    float residual = uintBitsToFloat(st.s.residual_scratch);
    st.s.residual = st.s.residual_scratch;
    st.s.residual_scratch = 0u;
    float b_max = uintBitsToFloat(st.s.divergence_before);
    // The first check (after the start) keeps its residual as the divergence guard's reference.
    if (st.s.checks == 0u) st.s.first_residual = floatBitsToUint(residual);
    bool diverged = solve_diverged(residual, uintBitsToFloat(st.s.first_residual), b_max);
    if (residual <= sb().b.tolerance * b_max || diverged) {
        st.s.done = 1u;
        st.s.diverged = diverged ? 1u : 0u;
        DispatchRef live = DispatchRef(sb().b.dispatch);
        for (uint s = 0u; s < kDispatchSlots; ++s) live.v[s] = LevelDispatch(0u, 0u, 0u);
    } else {
        st.s.checks += 1u;
    }
}
