// Bindings every sample shader shares (one descriptor set; renderer.cpp creates its layout).
#include "sample_io.h"

layout(set = 0, binding = 0, std140) uniform Frame { FrameUniforms frame; };
layout(set = 0, binding = 1) uniform sampler3D wind_texture;
layout(set = 0, binding = 2, std430) readonly buffer Seeds { FoliageSeed seeds[]; };
layout(set = 0, binding = 3, std430) buffer States { FoliageState states[]; };

/// gust's wind at a world point (m/s); the ambient wind outside the domain comes from the clamped edge.
vec3 wind_at(vec3 world) {
    vec3 uvw = (frame.wind_world_to_texture * vec4(world, 1.0)).xyz;
    return texture(wind_texture, uvw).xyz;
}

/// Sun and sky on a surface of albedo `albedo` with normal `n`, faded into haze with distance.
vec3 shade(vec3 albedo, vec3 n, vec3 world) {
    float sun = max(dot(n, frame.light.xyz), 0.0);
    float sky = 0.5 + 0.5 * n.y;
    vec3 lit = albedo * (0.85 * sun * vec3(1.0, 0.96, 0.88) + 0.35 * sky * vec3(0.55, 0.65, 0.8));
    float haze = 1.0 - exp(-0.004 * length(world - frame.camera.xyz));
    return mix(lit, vec3(0.62, 0.72, 0.85), haze);
}

/// Blue (still) through green to red (frame.wind_cells.w m/s and above).
vec3 speed_colour(float speed) {
    float s = clamp(speed / max(frame.wind_cells.w, 1e-3), 0.0, 1.0);
    return s < 0.5 ? mix(vec3(0.1, 0.2, 0.9), vec3(0.1, 0.85, 0.3), 2.0 * s)
                   : mix(vec3(0.1, 0.85, 0.3), vec3(0.95, 0.15, 0.1), 2.0 * s - 1.0);
}
