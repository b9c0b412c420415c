// Bindings every sample shader shares (one descriptor set; renderer.cpp creates its layout).
#include "sample_io.h"

#define GUST_CASCADES 4 // kWindCascades; the slots past a System's coarsest hold its coarsest again
#include "gust/gust_wind.glsl"

layout(set = 0, binding = 0, std140) uniform Frame { FrameUniforms frame; };
layout(set = 0, binding = 1) uniform sampler3D wind_textures[GUST_CASCADES]; // finest first
layout(set = 0, binding = 2, std430) readonly buffer Seeds { FoliageSeed seeds[]; };
layout(set = 0, binding = 3, std430) buffer States { FoliageState states[]; };

/// The wind (rgb, m/s) and the air fraction (a) at a world point: the finest cascade that holds it, blended
/// into the coarser ones as gust's own answers are; beyond the coarsest, the ambient wind and open air.
/// gust_wind's sum, cascade by cascade, but a coarser cascade is read only while the finer ones leave it a
/// share: in the middle of the finest cascade (the village, its grass) that is one texture read instead of
/// four.
vec4 wind_and_air_at(vec3 world) {
    vec4 sum = vec4(0.0);
    float left = 1.0;
    gust_blend_texel(wind_textures[0], frame.wind_world_to_texture[0], wind_textures[1],
                     frame.wind_world_to_texture[1], world, sum, left);
    gust_blend_texel(wind_textures[1], frame.wind_world_to_texture[1], wind_textures[2],
                     frame.wind_world_to_texture[2], world, sum, left);
    gust_blend_texel(wind_textures[2], frame.wind_world_to_texture[2], wind_textures[3],
                     frame.wind_world_to_texture[3], world, sum, left);
    gust_blend_texel(wind_textures[3], frame.wind_world_to_texture[3], true, world, sum, left);
    return sum + left * vec4(frame.ambient.xyz, 1.0);
}

/// gust's wind at a world point (m/s).
vec3 wind_at(vec3 world) { return wind_and_air_at(world).xyz; }

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
