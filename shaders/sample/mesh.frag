#version 460
#extension GL_GOOGLE_include_directive : require
#include "sample_common.glsl"

layout(push_constant, scalar) uniform Push { DrawPush draw; };
layout(location = 0) in vec3 world;
layout(location = 0) out vec4 colour;

void main() {
    // Flat shading from screen-space derivatives: the meshes carry positions only, as gust sees them.
    vec3 n = normalize(cross(dFdx(world), dFdy(world)));
    if (dot(n, frame.camera.xyz - world) < 0.0) n = -n;
    colour = vec4(shade(draw.color.rgb, n, world), 1.0);
}
