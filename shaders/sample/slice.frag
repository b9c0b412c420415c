#version 460
#extension GL_GOOGLE_include_directive : require
// Wind speed on the slice, every cascade's blended (slice.comp); solid cells (gust's alpha channel:
// 1 − solid fraction) show dark.
#include "sample_common.glsl"

layout(set = 0, binding = 6) uniform sampler2D slice_wind;

layout(location = 0) in vec3 world;
layout(location = 0) out vec4 colour;

void main() {
    vec2 uv = (world.xz - frame.coarse_min.xz) / (frame.wind_cells.xz * frame.coarse_min.w);
    vec4 w = textureLod(slice_wind, uv, 0.0);
    colour = vec4(speed_colour(length(w.xyz)) * mix(0.15, 1.0, w.a), 0.6);
}
