#version 460
#extension GL_GOOGLE_include_directive : require
// Raster path, stage 3: one invocation per pixel column; emits every voxel of the column that the
// triangle's plane crosses within the pixel footprint, each kept only if the exact test passes.
#include "voxelize_common.glsl"

layout(location = 0) flat in vec3 in_a;
layout(location = 1) flat in vec3 in_b;
layout(location = 2) flat in vec3 in_c;
layout(location = 3) flat in uint in_axis;
layout(location = 4) flat in vec4 in_clip;
layout(location = 5) flat in vec3 in_va;
layout(location = 6) flat in vec3 in_vb;
layout(location = 7) flat in vec3 in_vc;

void main() {
    vec2 centre = gl_FragCoord.xy;
    if (any(lessThan(centre, in_clip.xy)) || any(greaterThan(centre, in_clip.zw))) return;
    Setup s;
    s.a = in_a;
    s.b = in_b;
    s.c = in_c;
    s.n = cross(in_b - in_a, in_c - in_a);
    s.w_min = min(in_a.z, min(in_b.z, in_c.z));
    s.w_max = max(in_a.z, max(in_b.z, in_c.z));
    s.axis = in_axis;
    s.va = in_va;
    s.vb = in_vb;
    s.vc = in_vc;
    voxelize_column(s, int(floor(centre.x)), int(floor(centre.y)));
    flush_voxels();
}
