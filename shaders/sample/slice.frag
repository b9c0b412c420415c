#version 460
#extension GL_GOOGLE_include_directive : require
// Wind speed on the slice, every cascade's blended; solid cells (gust's alpha channel: 1 − solid fraction) show dark.
#include "sample_common.glsl"

layout(location = 0) in vec3 world;
layout(location = 0) out vec4 colour;

void main() {
    vec4 w = wind_and_air_at(world);
    colour = vec4(speed_colour(length(w.xyz)) * mix(0.15, 1.0, w.a), 0.6);
}
