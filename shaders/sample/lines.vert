#version 460
#extension GL_GOOGLE_include_directive : require
#include "sample_common.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in vec4 line_colour;
layout(location = 0) out vec4 colour;

void main() {
    colour = line_colour;
    gl_Position = frame.view_proj * vec4(position, 1.0);
}
