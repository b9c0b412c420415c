// Bindings every sample shader shares (one descriptor set; renderer.cpp creates its layout).
#include "sample_io.h"

#define GUST_CASCADES 4 // kWindCascades
#include "gust/gust_wind.glsl"

layout(set = 0, binding = 0, std140) uniform Frame { FrameUniforms frame; };
layout(set = 0, binding = 1) uniform sampler3D wind_textures[GUST_CASCADES]; // finest first
layout(set = 0, binding = 2, std430) readonly buffer Seeds { FoliageSeed seeds[]; };
layout(set = 0, binding = 3, std430) buffer States { FoliageState states[]; };

/// gust's wind at a world point (m/s): the finest cascade that holds it, blended into the coarser ones as
/// gust's own answers are; beyond the coarsest, the ambient wind.
vec3 wind_at(vec3 world) {
    return gust_wind(wind_textures, frame.wind_world_to_texture, frame.ambient.xyz, world);
}

/// Cascade k's share of the air fraction (gust's alpha: 1 − solid fraction) at `world`, as gust_wind
/// blends the wind.
#define SAMPLE_BLEND_AIR(k)                                                                                 \
    {                                                                                                        \
        vec3 uvw = (frame.wind_world_to_texture[k] * vec4(world, 1.0)).xyz;                                  \
        float w = gust_cascade_weight(uvw, vec3(textureSize(wind_textures[k], 0)), k == GUST_CASCADES - 1);  \
        if (w > 0.0) air += left * w * textureLod(wind_textures[k], uvw, 0.0).a;                             \
        left *= 1.0 - w;                                                                                     \
    }

/// The air fraction at a world point (1 beyond the coarsest cascade).
float air_at(vec3 world) {
    float air = 0.0, left = 1.0;
    SAMPLE_BLEND_AIR(0)
    SAMPLE_BLEND_AIR(1)
    SAMPLE_BLEND_AIR(2)
    SAMPLE_BLEND_AIR(3)
    return air + left;
}

/// Sun and sky on a surface of albedo `albedo` with normal `n`, faded into haze with distance.
vec3 shade(vec3 albedo, vec3 n, vec3 world) {
    float sun = max(dot(n, frame.light.xyz), 0.0);
    float sky = 0.5 + 0.5 * n.y;
    vec3 lit = albedo * (0.85 * sun * vec3(1.0, 0.96, 0.88) + 0.35 * sky * vec3(0.55, 0.65, 0.8));
    float haze = 1.0 - exp(-0.0007 * length(world - frame.camera.xyz));
    return mix(lit, vec3(0.62, 0.72, 0.85), haze);
}

/// Blue (still) through green to red (frame.wind_cells.w m/s and above).
vec3 speed_colour(float speed) {
    float s = clamp(speed / max(frame.wind_cells.w, 1e-3), 0.0, 1.0);
    return s < 0.5 ? mix(vec3(0.1, 0.2, 0.9), vec3(0.1, 0.85, 0.3), 2.0 * s)
                   : mix(vec3(0.1, 0.85, 0.3), vec3(0.95, 0.15, 0.1), 2.0 * s - 1.0);
}
