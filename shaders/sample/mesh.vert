#version 460
#extension GL_GOOGLE_include_directive : require
#include "sample_common.glsl"

layout(push_constant, scalar) uniform Push { DrawPush draw; };
layout(location = 0) in vec3 position;
layout(location = 0) out vec3 world;

void main() {
    vec4 p = draw.model * vec4(position, 1.0);
    if (draw.sway.x >= 0.0) {
        // A tree bends from sway.y upwards, quadratically, by its crown's spring displacement.
        uint slot = uint(draw.sway.x);
        float f = clamp((position.y - draw.sway.y) / max(draw.sway.z, 1e-3), 0.0, 1.0);
        vec2 bend = states[slot].bend.xy * seeds[slot].root_height.w * f * f;
        p.xyz += vec3(bend.x, -0.5 * dot(bend, bend) / max(seeds[slot].root_height.w, 1e-3), bend.y);
    }
    world = p.xyz;
    gl_Position = frame.view_proj * p;
}
