#version 460
#extension GL_GOOGLE_include_directive : require
// Raster path, stage 1: pull the vertex by index and move it to grid space.
#include "voxelize_common.glsl"

layout(location = 0) out vec3 out_grid;

void main() {
    out_grid = load_grid_vertex(uint(gl_VertexIndex) / 3u, uint(gl_VertexIndex) % 3u);
    gl_Position = vec4(0.0, 0.0, 0.5, 1.0);
}
