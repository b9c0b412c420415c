// The shared memory of coarse_levels.glsl's coarse_solve(), which holds the levels it solves (included before
// solver_common.glsl, whose load_cell reads them there under GUST_COARSE_SHARED; coarse_levels.glsl after
// it).
const uint kCoarseValues = kCoarseCells + kCoarseCells / 7u + 16u;
const uint kCoarseRhs = kCoarseCells / 7u + 16u;
shared float coarse_phi[kCoarseValues];
shared float coarse_rhs[kCoarseRhs];
// The global cell index of coarse_phi[0], and coarse_rhs[0]'s offset from it: beyond every cell until
// coarse_solve() sets them, so a pass that smooths in memory before it reads memory.
uint coarse_base = 0x7fffffffu;
uint coarse_rhs_from = 0x7fffffffu;
#define GUST_COARSE_SHARED 1
