#version 460
#extension GL_GOOGLE_include_directive : require
#include "sample_common.glsl"

layout(location = 0) in vec3 world;
layout(location = 1) in vec3 albedo;
layout(location = 2) in vec3 normal;
layout(location = 0) out vec4 colour;

void main() {
    vec3 n = gl_FrontFacing ? normal : -normal;
    n.y = abs(n.y);
    colour = vec4(shade(albedo, normalize(n), world), 1.0);
}
