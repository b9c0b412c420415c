// gust's wind in a host's shaders (docs/api.md "Wind texture"): each cascade's wind texture
// (gust::System::wind_textures, gust_system_cascade_texture), picked and blended as gust's own answers are.
// The finest cascade that holds a point answers there, blended into the next coarser one over its last
// GUST_BLEND_CELLS cells, so no seam shows; beyond the coarsest cascade, the ambient wind.
//
//     #define GUST_CASCADES 3 // domain.cascades of the System
//     #include "gust/gust_wind.glsl"
//     layout(set = 0, binding = 1) uniform sampler3D gust_cascades[GUST_CASCADES]; // finest first
//     ...
//     vec3 wind = gust_wind(gust_cascades, world_to_texture, ambient, world_position); // m/s
//
// world_to_texture[k] is cascade k's WindTexture::world_to_texture, and ambient the System's ambient wind.
// Without GUST_CASCADES, call gust_blend_cascade for each cascade, finest first. The textures are read as
// their sampler reads them (trilinear on cell centres), so in a cell without air the answer mixes the
// solid's velocity with its neighbours' air, where System::sample answers the solid's alone.
#ifndef GUST_WIND_GLSL
#define GUST_WIND_GLSL

/// Cells over which a cascade's answer blends into the next coarser one's, inward from its border
/// (gust::kCascadeBlendCells).
const float GUST_BLEND_CELLS = 3.0;

/// A cascade's share of the answer at texture coordinates `uvw` of its grid of `cells` cells: 0 outside it,
/// 1 inside the coarsest, otherwise rising from 0 at its border to 1 GUST_BLEND_CELLS cells in.
float gust_cascade_weight(vec3 uvw, vec3 cells, bool coarsest) {
    if (any(lessThan(uvw, vec3(0.0))) || any(greaterThan(uvw, vec3(1.0)))) return 0.0;
    if (coarsest) return 1.0;
    vec3 inside = min(uvw, vec3(1.0) - uvw) * cells;
    return clamp(min(inside.x, min(inside.y, inside.z)) / GUST_BLEND_CELLS, 0.0, 1.0);
}

/// Adds cascade `wind`'s share at world point `world` to `sum` (m/s), taken from what the finer cascades
/// left (`left`: 1 before the finest). The coarsest cascade is `coarsest`; after it, add left · ambient.
void gust_blend_cascade(sampler3D wind, mat4 world_to_texture, bool coarsest, vec3 world, inout vec3 sum,
                        inout float left) {
    vec3 uvw = (world_to_texture * vec4(world, 1.0)).xyz;
    float w = gust_cascade_weight(uvw, vec3(textureSize(wind, 0)), coarsest);
    if (w > 0.0) {
        // An explicit level: no derivatives are needed, so it may run in any control flow or stage.
        sum += left * w * textureLod(wind, uvw, 0.0).xyz;
        left *= 1.0 - w;
    }
}

#ifdef GUST_CASCADES
#if GUST_CASCADES < 1 || GUST_CASCADES > 8
#error "GUST_CASCADES must be 1..8, as domain.cascades"
#endif
/// The wind at world point `world` (m/s) from every cascade, finest first. Each cascade is indexed by a
/// constant, so the host needs no dynamic indexing of sampler arrays.
vec3 gust_wind(sampler3D cascades[GUST_CASCADES], mat4 world_to_texture[GUST_CASCADES], vec3 ambient,
               vec3 world) {
    vec3 sum = vec3(0.0);
    float left = 1.0;
    gust_blend_cascade(cascades[0], world_to_texture[0], GUST_CASCADES == 1, world, sum, left);
#if GUST_CASCADES > 1
    gust_blend_cascade(cascades[1], world_to_texture[1], GUST_CASCADES == 2, world, sum, left);
#endif
#if GUST_CASCADES > 2
    gust_blend_cascade(cascades[2], world_to_texture[2], GUST_CASCADES == 3, world, sum, left);
#endif
#if GUST_CASCADES > 3
    gust_blend_cascade(cascades[3], world_to_texture[3], GUST_CASCADES == 4, world, sum, left);
#endif
#if GUST_CASCADES > 4
    gust_blend_cascade(cascades[4], world_to_texture[4], GUST_CASCADES == 5, world, sum, left);
#endif
#if GUST_CASCADES > 5
    gust_blend_cascade(cascades[5], world_to_texture[5], GUST_CASCADES == 6, world, sum, left);
#endif
#if GUST_CASCADES > 6
    gust_blend_cascade(cascades[6], world_to_texture[6], GUST_CASCADES == 7, world, sum, left);
#endif
#if GUST_CASCADES > 7
    gust_blend_cascade(cascades[7], world_to_texture[7], true, world, sum, left);
#endif
    return sum + left * ambient;
}
#endif

#endif
