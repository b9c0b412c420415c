#version 460
#extension GL_GOOGLE_include_directive : require
// Shades the W view's voxel faces (voxels.vert) with the scene's sun, sky and haze.
#include "sample_common.glsl"

layout(location = 0) in vec3 world;
layout(location = 1) in vec3 albedo;
layout(location = 2) in vec3 normal;
layout(location = 0) out vec4 colour;

void main() {
    colour = vec4(shade(albedo, normal, world), 1.0);
}
