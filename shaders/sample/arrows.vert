#version 460
#extension GL_GOOGLE_include_directive : require
// One arrow per wind cell column at the slice height: a shaft along the wind and two barbs.
#include "sample_common.glsl"

layout(location = 0) out vec4 colour;

void main() {
    uint columns = uint(frame.wind_cells.x);
    uint i = uint(gl_InstanceIndex) % columns, k = uint(gl_InstanceIndex) / columns;
    float cell = frame.wind_min.w;
    vec3 base = vec3(frame.wind_min.x + (float(i) + 0.5) * cell, frame.slice.x,
                     frame.wind_min.z + (float(k) + 0.5) * cell);
    vec3 w = wind_at(base);
    vec3 tip = base + w * frame.slice.y;
    vec3 back = -0.3 * (tip - base);
    vec3 side = 0.15 * cross(tip - base, vec3(0.0, 1.0, 0.0));
    vec3 points[6] = vec3[6](base, tip, tip, tip + back + side, tip, tip + back - side);
    colour = vec4(speed_colour(length(w)), 1.0);
    gl_Position = frame.view_proj * vec4(points[gl_VertexIndex], 1.0);
}
