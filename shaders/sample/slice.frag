#version 460
#extension GL_GOOGLE_include_directive : require
// Wind speed on the slice; solid cells (gust's alpha channel: 1 − solid fraction) show dark.
#include "sample_common.glsl"

layout(location = 0) in vec3 world;
layout(location = 0) out vec4 colour;

void main() {
    vec4 w = texture(wind_texture, (frame.wind_world_to_texture * vec4(world, 1.0)).xyz);
    colour = vec4(speed_colour(length(w.xyz)) * mix(0.15, 1.0, w.a), 0.6);
}
