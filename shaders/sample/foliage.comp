#version 460
#extension GL_GOOGLE_include_directive : require
// One spring-damper per grass blade or tree crown, driven by gust's wind sampled at its middle.
#include "sample_common.glsl"

layout(local_size_x = kFoliageGroupSize) in;
layout(push_constant, scalar) uniform Push { FoliagePush push; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) return;
    FoliageSeed seed = seeds[i];
    vec4 s = states[i].bend;
    // Blades (width > 0) feel the wind at 60% of their height, but no lower than one wind cell above
    // their root: a coarse grid's lowest cell centre may lie inside the ground, and the texture would
    // blend that still air into the grass. Crowns (width 0) feel it at their seed, the top.
    bool blade = seed.yaw_width.y > 0.0;
    float lift = blade ? max(0.6 * seed.root_height.w, frame.wind_min.w) : 0.0;
    vec3 probe = seed.root_height.xyz + vec3(0.0, lift, 0.0);
    vec2 w = wind_at(probe).xz;
    // Drag grows with the square of the wind speed (a bluff body); scaled by k, the steady bend is
    // drag * |w|^2 whatever the stiffness, which sets only how fast it sways. A crown bends a third as far.
    // The damper (critical at 2*sqrt(k)) settles the spring, so gusts make it sway rather than snap.
    float k = seed.yaw_width.z;
    vec2 force = push.drag * (blade ? 1.0 : 0.3) * k * w * length(w);
    vec2 accel = force - k * s.xy - 1.2 * sqrt(k) * s.zw;
    // Semi-implicit Euler: stable for the stiff blades at the frame rates the sample runs.
    s.zw += push.dt * accel;
    s.xy += push.dt * s.zw;
    float reach = length(s.xy);
    if (reach > 1.2) {
        s.xy *= 1.2 / reach;
        s.zw *= 0.5;
    }
    states[i].bend = s;
}
