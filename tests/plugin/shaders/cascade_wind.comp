#version 460
// A host's shader reading gust's wind through gust_wind.glsl: the wind at each point from the cascades'
// textures (test_cascades.cpp).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#define GUST_CASCADES 3
#include "gust/gust_wind.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform sampler3D cascades[GUST_CASCADES];

layout(buffer_reference, scalar) readonly buffer Points { vec3 p[]; };
layout(buffer_reference, scalar) writeonly buffer Winds { vec3 w[]; };
layout(buffer_reference, scalar) readonly buffer Frame {
    mat4 world_to_texture[GUST_CASCADES];
    vec3 ambient;
};
layout(push_constant, scalar) uniform Push {
    Points points;
    Winds winds;
    Frame frame;
    uint count;
};

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    winds.w[i] = gust_wind(cascades, frame.world_to_texture, frame.ambient, points.p[i]);
}
