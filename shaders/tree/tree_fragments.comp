#version 460
#extension GL_GOOGLE_include_directive : require
// Before inserting a fragment list (one thread): sizes the per-fragment dispatches from the
// voxelizer's counter on the GPU.
#include "tree_common.glsl"

layout(local_size_x = 1) in;

void main() {
    load_bindings();
    state().s.fragments_dispatch = dispatch_for(fragment_count());
}
