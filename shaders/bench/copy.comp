#version 460
#extension GL_GOOGLE_include_directive : require
// The solver bench's bandwidth floor: vec4s copied from one buffer to another by a compute shader, each
// thread a grid-stride loop, loading and storing the way the solver's passes do (a vkCmdCopyBuffer can take
// another path through the driver, and ran slower than some passes).
#include "../common.h"

layout(local_size_x = 256) in;
layout(buffer_reference, scalar) readonly buffer SourceRef { vec4 v[]; };
layout(buffer_reference, scalar) writeonly buffer TargetRef { vec4 v[]; };
layout(push_constant, scalar) uniform Push {
    uint64_t source;
    uint64_t target;
    uint count; // vec4s
}
pc;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < pc.count; i += stride) TargetRef(pc.target).v[i] = SourceRef(pc.source).v[i];
}
