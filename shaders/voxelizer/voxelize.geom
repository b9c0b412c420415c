#version 460
#extension GL_GOOGLE_include_directive : require
// Raster path, stage 2: project along the dominant axis onto a res x res viewport and dilate the
// triangle so that every pixel whose square meets it has its centre covered (Hasselgren et al.,
// GPU Gems 2 ch. 42). The fragment stage clips to the triangle's bounding box and tests exactly.
#include "voxelize_common.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

layout(location = 0) in vec3 in_grid[];
layout(location = 0) flat out vec3 out_a;
layout(location = 1) flat out vec3 out_b;
layout(location = 2) flat out vec3 out_c;
layout(location = 3) flat out uint out_axis;
layout(location = 4) flat out vec4 out_clip;
layout(location = 5) flat out vec3 out_va;
layout(location = 6) flat out vec3 out_vb;
layout(location = 7) flat out vec3 out_vc;

// Half a pixel plus a margin, so centres exactly on a dilated edge are never lost to the fill rule or to
// the rasterizer snapping vertices to its sub-pixel grid: Vulkan guarantees at least 4 sub-pixel bits,
// so a vertex moves by at most 1/32 pixel, and 1/16 outlasts that. Extra pixels cost only their exact
// tests, which reject them.
const float kDilation = 0.5 + 1.0 / 16.0;

// How far past the viewport (pixels) a dilated vertex may lie. Rasterizers clip and snap vertices in
// fixed point, and far beyond this lavapipe lost parts of triangles that reach 1e8 voxels out; such a
// triangle is drawn as its bounding box cut to the viewport instead, and the exact tests keep its voxels.
const float kFarPixels = 16384.0;

void emit(vec2 p, Setup s, vec4 clip) {
    out_a = s.a;
    out_b = s.b;
    out_c = s.c;
    out_axis = s.axis;
    out_clip = clip;
    out_va = s.va;
    out_vb = s.vb;
    out_vc = s.vc;
    gl_Position = vec4(p / float(pc.res) * 2.0 - 1.0, 0.5, 1.0);
    EmitVertex();
}

void main() {
    vec3 g0 = in_grid[0], g1 = in_grid[1], g2 = in_grid[2];
    if (!is_finite(g0) || !is_finite(g1) || !is_finite(g2)) {
        atomicAdd(Counters(pc.counters).c.rejected, 1u);
        return;
    }
    Setup s;
    if (!setup_triangle(g0, g1, g2, s)) return;
    setup_velocities(uint(gl_PrimitiveIDIn), s);

    vec2 p[3] = vec2[3](s.a.xy, s.b.xy, s.c.xy);
    vec2 lo = min(p[0], min(p[1], p[2]));
    vec2 hi = max(p[0], max(p[1], p[2]));
    // A pixel's square meets the bounding box exactly when its centre is within half a pixel of it.
    vec4 clip = vec4(lo - kDilation, hi + kDilation);
    float res = float(pc.res);

    float area = (p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[1].y - p[0].y) * (p[2].x - p[0].x);
    if (area < 0.0) {
        vec2 t = p[1];
        p[1] = p[2];
        p[2] = t;
    }
    // Each edge line moved outwards by the pixel's half-diagonal in the direction of its normal.
    vec3 lines[3];
    for (int i = 0; i < 3; ++i) {
        vec2 e = p[(i + 1) % 3] - p[i];
        vec2 outward = vec2(e.y, -e.x);
        lines[i] = vec3(outward, dot(outward, p[i]) + kDilation * (abs(outward.x) + abs(outward.y)));
    }
    vec2 dilated[3];
    bool ok = abs(area) > 1e-6;
    for (int i = 0; i < 3 && ok; ++i) {
        vec3 l1 = lines[(i + 2) % 3], l2 = lines[i];
        float det = l1.x * l2.y - l1.y * l2.x;
        if (abs(det) < 1e-12 * (dot(l1.xy, l1.xy) + dot(l2.xy, l2.xy))) ok = false;
        else dilated[i] = vec2(l1.z * l2.y - l1.y * l2.z, l1.x * l2.z - l1.z * l2.x) / det;
        if (ok && !is_finite(vec3(dilated[i], 0.0))) ok = false;
    }
    for (int i = 0; i < 3 && ok; ++i)
        if (any(greaterThan(abs(dilated[i] - 0.5 * res), vec2(0.5 * res + kFarPixels)))) ok = false;
    if (ok) {
        for (int i = 0; i < 3; ++i) emit(dilated[i], s, clip);
    } else {
        // Nearly degenerate in projection, or reaching far past the viewport: rasterize the clip box, cut
        // to the viewport (and a pixel around it).
        vec4 box = clamp(clip, vec4(-1.0), vec4(res + 1.0));
        emit(box.xy, s, clip);
        emit(vec2(box.z, box.y), s, clip);
        emit(vec2(box.x, box.w), s, clip);
        emit(box.zw, s, clip);
    }
    EndPrimitive();
}
