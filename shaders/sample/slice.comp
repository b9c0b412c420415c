#version 460
#extension GL_GOOGLE_include_directive : require
// The wind slice's wind and air once per texel, every cascade blended (wind_and_air_at), for the slice's
// fragments to read with one filtered fetch each. The texels tile the coarsest cascade at the slice
// height (renderer.cpp sizes them: the finest cell, or a power of two of them).
#include "sample_common.glsl"

layout(local_size_x = kSliceGroupSize, local_size_y = kSliceGroupSize) in;
layout(set = 0, binding = 5, rgba16f) uniform writeonly image2D slice_out;

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy), size = imageSize(slice_out);
    if (any(greaterThanEqual(texel, size))) return;
    vec2 extent = frame.wind_cells.xz * frame.coarse_min.w;
    vec2 xz = frame.coarse_min.xz + (vec2(texel) + 0.5) / vec2(size) * extent;
    imageStore(slice_out, texel, wind_and_air_at(vec3(xz.x, frame.slice.x, xz.y)));
}
