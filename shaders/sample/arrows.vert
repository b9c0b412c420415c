#version 460
#extension GL_GOOGLE_include_directive : require
// One arrow per wind cell column at the slice height, along the wind: a shaft and a head as three
// triangles a few pixels wide (lines are one pixel wide on most devices, too thin to read over grass).
#include "sample_common.glsl"

layout(location = 0) out vec4 colour;

void main() {
    uint columns = uint(frame.wind_cells.x);
    uint i = uint(gl_InstanceIndex) % columns, k = uint(gl_InstanceIndex) / columns;
    float cell = frame.wind_min.w;
    vec3 base = vec3(frame.wind_min.x + (float(i) + 0.5) * cell, frame.slice.x,
                     frame.wind_min.z + (float(k) + 0.5) * cell);
    vec3 w = wind_at(base);
    vec4 from = frame.view_proj * vec4(base, 1.0);
    vec4 to = frame.view_proj * vec4(base + w * frame.slice.y, 1.0);
    colour = vec4(speed_colour(length(w)), 1.0);
    if (from.w <= 0.0 || to.w <= 0.0) {
        // Behind the eye: a degenerate triangle draws nothing.
        gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    // In pixels from the centre of the frame.
    vec2 half_px = 0.5 * frame.slice.zw;
    vec2 a = from.xy / from.w * half_px, b = to.xy / to.w * half_px;
    float len = length(b - a);
    vec2 along = len > 1e-3 ? (b - a) / len : vec2(1.0, 0.0);
    vec2 across = vec2(-along.y, along.x);
    float width = max(1.0, frame.slice.w / 540.0);
    float head = min(0.4 * len, 10.0 * width);
    vec2 neck = b - along * head;
    vec2 points[9] = vec2[9](a - across * width, a + across * width, neck + across * width,
                             a - across * width, neck + across * width, neck - across * width,
                             neck - across * 3.5 * width, neck + across * 3.5 * width, b);
    // How far along the arrow each point lies, for its depth.
    float along_arrow[9] = float[9](0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0);
    vec2 zw = mix(from.zw, to.zw, along_arrow[gl_VertexIndex]);
    gl_Position = vec4(points[gl_VertexIndex] / half_px * zw.y, zw.x, zw.y);
}
