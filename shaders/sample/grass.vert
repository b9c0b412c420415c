#version 460
#extension GL_GOOGLE_include_directive : require
#include "sample_common.glsl"

layout(location = 0) out vec3 world;
layout(location = 1) out vec3 albedo;
layout(location = 2) out vec3 normal;

void main() {
    // One non-instanced draw of one triangle per blade: lavapipe shades large vertex batches far faster
    // than tiny instances, and a blade's bend needs only its tip to move. Vertices 0, 1: root; 2: tip.
    uint blade = uint(gl_VertexIndex) / kBladeVertices, v = uint(gl_VertexIndex) % kBladeVertices;
    FoliageSeed seed = seeds[blade];
    vec2 bend = states[blade].bend.xy;
    float t = v == 2u ? 1.0 : 0.0;
    float side = v == 2u ? 0.0 : (v == 0u ? -0.5 : 0.5);
    float height = seed.root_height.w;
    float width = seed.yaw_width.y;
    vec2 across = vec2(cos(seed.yaw_width.x), sin(seed.yaw_width.x));
    // The blade bends along a parabola and keeps roughly its length: what leans over sinks.
    vec2 offset = bend * height * t * t;
    float sink = 0.5 * dot(offset, offset) / max(height, 1e-3);
    world = seed.root_height.xyz + vec3(across.x * side * width + offset.x, height * t - sink,
                                        across.y * side * width + offset.y);
    float variation = seed.yaw_width.w;
    albedo = mix(vec3(0.10, 0.22, 0.05), mix(vec3(0.35, 0.55, 0.12), vec3(0.55, 0.6, 0.2), variation), t);
    normal = normalize(vec3(-across.y, 0.6, across.x));
    gl_Position = frame.view_proj * vec4(world, 1.0);
}
