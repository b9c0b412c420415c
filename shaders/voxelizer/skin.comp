#version 460
#extension GL_GOOGLE_include_directive : require
// Skinning from a bone palette: one thread per vertex writes its posed position into the mesh's position
// buffer, the one set_vertices fills, so the voxelizer and its surface velocities read it unchanged.

layout(local_size_x = 64) in;

#include "skin_io.h"

layout(buffer_reference, scalar) readonly buffer Floats { float v[]; };
layout(buffer_reference, scalar) writeonly buffer Out { float v[]; };
layout(buffer_reference, scalar) readonly buffer Joints { uvec2 v[]; };
layout(buffer_reference, scalar) readonly buffer Weights { vec4 v[]; };
layout(buffer_reference, scalar) readonly buffer Palette { mat4 m[]; };

layout(push_constant, scalar) uniform Push { SkinPush pc; };

void main() {
    uint vertex = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kSkinGroupSize +
                  gl_LocalInvocationID.x;
    if (vertex >= pc.vertex_count) return;
    Floats bind = Floats(pc.bind);
    vec3 b = vec3(bind.v[3u * vertex], bind.v[3u * vertex + 1u], bind.v[3u * vertex + 2u]);
    uvec2 j = Joints(pc.joints).v[vertex];
    Palette palette = Palette(pc.palette);
    vec3 p = skin_point(palette.m[j.x & 0xffffu], palette.m[j.x >> 16], palette.m[j.y & 0xffffu],
                        palette.m[j.y >> 16], Weights(pc.weights).v[vertex], b);
    Out out_positions = Out(pc.positions);
    out_positions.v[3u * vertex] = p.x;
    out_positions.v[3u * vertex + 1u] = p.y;
    out_positions.v[3u * vertex + 2u] = p.z;
}
