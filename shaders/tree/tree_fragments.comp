#version 460
#extension GL_GOOGLE_include_directive : require
// Before inserting a fragment list (one thread): sizes the per-fragment dispatches from the
// voxelizer's counter on the GPU, at least one workgroup so that tree_visit always plans its level.
#include "tree_common.glsl"

layout(local_size_x = 1) in;

void main() {
    load_bindings();
    state().s.fragments_dispatch = dispatch_at_least_one(fragment_count());
}
