#version 460
#extension GL_GOOGLE_include_directive : require
// A horizontal quad over the coarsest cascade at the slice height.
#include "sample_common.glsl"

layout(location = 0) out vec3 world;

void main() {
    vec2 corner = vec2(gl_VertexIndex & 1, (gl_VertexIndex >> 1) & 1);
    vec3 size = frame.wind_cells.xyz * frame.coarse_min.w;
    world = vec3(frame.coarse_min.x + corner.x * size.x, frame.slice.x, frame.coarse_min.z + corner.y * size.z);
    gl_Position = frame.view_proj * vec4(world, 1.0);
}
