// gust's wind in a host's shaders (docs/api.md "Wind texture"): each cascade's wind texture
// (gust::System::wind_textures, gust_system_cascade_texture), picked and blended as gust's own answers are.
// The finest cascade that holds a point answers there, blended into the next coarser one over its last
// GUST_BLEND_CELLS cells (1 cell where the coarser one's cells hold solid), so no seam shows; beyond the
// coarsest cascade, the ambient wind.
//
//     #define GUST_CASCADES 3 // domain.cascades of the System
//     #include "gust/gust_wind.glsl"
//     layout(set = 0, binding = 1) uniform sampler3D gust_cascades[GUST_CASCADES]; // finest first
//     ...
//     vec3 wind = gust_wind(gust_cascades, world_to_texture, ambient, world_position); // m/s
//
// world_to_texture[k] is cascade k's WindTexture::world_to_texture, and ambient the System's ambient wind.
// Without GUST_CASCADES, call gust_blend_cascade for each cascade, finest first. The textures are read as
// their sampler reads them (trilinear on cell centres): the same wind System::query and System::sample
// answer from the same texels (docs/api.md "One wind at a point").
#ifndef GUST_WIND_GLSL
#define GUST_WIND_GLSL

/// Cells over which a cascade's answer blends into the next coarser one's, inward from its border
/// (gust::kCascadeBlendCells), where the coarser cascade is open; where its cells around the point hold
/// GUST_SOLID_SHARE of solid or more (its texture's alpha, the open fraction, under 1 − GUST_SOLID_SHARE),
/// over 1 cell (gust::kCascadeSolidShare, gust::cascade_blend_cells).
const float GUST_BLEND_CELLS = 3.0;
const float GUST_SOLID_SHARE = 0.3;

/// The blend's width in cells where the next coarser cascade's texture reads open fraction `coarser_open`
/// (its alpha).
float gust_blend_cells(float coarser_open) {
    float open = clamp((coarser_open - (1.0 - GUST_SOLID_SHARE)) / GUST_SOLID_SHARE, 0.0, 1.0);
    return 1.0 + (GUST_BLEND_CELLS - 1.0) * open;
}

/// A cascade's share of the answer at texture coordinates `uvw` of its grid of `cells` cells: 0 outside it,
/// 1 inside the coarsest, otherwise rising from 0 at its border to 1 `blend_cells` cells in
/// (gust_blend_cells).
float gust_cascade_weight(vec3 uvw, vec3 cells, bool coarsest, float blend_cells) {
    if (any(lessThan(uvw, vec3(0.0))) || any(greaterThan(uvw, vec3(1.0)))) return 0.0;
    if (coarsest) return 1.0;
    vec3 inside = min(uvw, vec3(1.0) - uvw) * cells;
    return clamp(min(inside.x, min(inside.y, inside.z)) / blend_cells, 0.0, 1.0);
}

/// gust_cascade_weight where the next coarser cascade is open (GUST_BLEND_CELLS wide).
float gust_cascade_weight(vec3 uvw, vec3 cells, bool coarsest) {
    return gust_cascade_weight(uvw, cells, coarsest, GUST_BLEND_CELLS);
}

/// The share at texture coordinates `uvw` of a cascade of `cells` cells (not the coarsest) at world point
/// `world`, with `coarser` the next coarser cascade: its open fraction is read only inside the blend.
float gust_cascade_weight(vec3 uvw, vec3 cells, sampler3D coarser, mat4 coarser_world_to_texture,
                          vec3 world) {
    float w = gust_cascade_weight(uvw, cells, false);
    if (w <= 0.0 || w >= 1.0) return w;
    vec3 coarser_uvw = (coarser_world_to_texture * vec4(world, 1.0)).xyz;
    return gust_cascade_weight(uvw, cells, false, gust_blend_cells(textureLod(coarser, coarser_uvw, 0.0).a));
}

/// Adds cascade `wind`'s whole texel at world point `world` to `sum`, the wind (xyz, m/s) and the open
/// fraction (w: 1 − the solid fraction), its share taken from what the finer cascades left (`left`: 1 before
/// the finest), with `coarser` the next coarser cascade. Once the finer cascades took everything, nothing
/// is read.
void gust_blend_texel(sampler3D wind, mat4 world_to_texture, sampler3D coarser, mat4 coarser_world_to_texture,
                      vec3 world, inout vec4 sum, inout float left) {
    if (left <= 0.0) return;
    vec3 uvw = (world_to_texture * vec4(world, 1.0)).xyz;
    float w = gust_cascade_weight(uvw, vec3(textureSize(wind, 0)), coarser, coarser_world_to_texture, world);
    if (w <= 0.0) return;
    // An explicit level: no derivatives are needed, so it may run in any control flow or stage.
    sum += left * w * textureLod(wind, uvw, 0.0);
    left *= 1.0 - w;
}

/// gust_blend_texel for the coarsest cascade (`coarsest` true); after it, add left · (ambient, 1). With
/// `coarsest` false it blends a cascade as if the next coarser one were open everywhere (GUST_BLEND_CELLS
/// wide): pass the coarser cascade, as above, to answer as gust does.
void gust_blend_texel(sampler3D wind, mat4 world_to_texture, bool coarsest, vec3 world, inout vec4 sum,
                      inout float left) {
    if (left <= 0.0) return;
    vec3 uvw = (world_to_texture * vec4(world, 1.0)).xyz;
    float w = gust_cascade_weight(uvw, vec3(textureSize(wind, 0)), coarsest);
    if (w <= 0.0) return;
    sum += left * w * textureLod(wind, uvw, 0.0);
    left *= 1.0 - w;
}

/// Adds cascade `wind`'s share of the wind at world point `world` to `sum` (m/s), as gust_blend_texel.
void gust_blend_cascade(sampler3D wind, mat4 world_to_texture, sampler3D coarser,
                        mat4 coarser_world_to_texture, vec3 world, inout vec3 sum, inout float left) {
    vec4 texel_sum = vec4(sum, 0.0);
    gust_blend_texel(wind, world_to_texture, coarser, coarser_world_to_texture, world, texel_sum, left);
    sum = texel_sum.xyz;
}

/// Adds the coarsest cascade's share (`coarsest` true) as above; after it, add left · ambient. With
/// `coarsest` false it blends a cascade as if the next coarser one were open everywhere (GUST_BLEND_CELLS
/// wide): pass the coarser cascade, as above, to answer as gust does.
void gust_blend_cascade(sampler3D wind, mat4 world_to_texture, bool coarsest, vec3 world, inout vec3 sum,
                        inout float left) {
    vec4 texel_sum = vec4(sum, 0.0);
    gust_blend_texel(wind, world_to_texture, coarsest, world, texel_sum, left);
    sum = texel_sum.xyz;
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
#if GUST_CASCADES > 1
    gust_blend_cascade(cascades[0], world_to_texture[0], cascades[1], world_to_texture[1], world, sum, left);
#endif
#if GUST_CASCADES > 2
    gust_blend_cascade(cascades[1], world_to_texture[1], cascades[2], world_to_texture[2], world, sum, left);
#endif
#if GUST_CASCADES > 3
    gust_blend_cascade(cascades[2], world_to_texture[2], cascades[3], world_to_texture[3], world, sum, left);
#endif
#if GUST_CASCADES > 4
    gust_blend_cascade(cascades[3], world_to_texture[3], cascades[4], world_to_texture[4], world, sum, left);
#endif
#if GUST_CASCADES > 5
    gust_blend_cascade(cascades[4], world_to_texture[4], cascades[5], world_to_texture[5], world, sum, left);
#endif
#if GUST_CASCADES > 6
    gust_blend_cascade(cascades[5], world_to_texture[5], cascades[6], world_to_texture[6], world, sum, left);
#endif
#if GUST_CASCADES > 7
    gust_blend_cascade(cascades[6], world_to_texture[6], cascades[7], world_to_texture[7], world, sum, left);
#endif
    gust_blend_cascade(cascades[GUST_CASCADES - 1], world_to_texture[GUST_CASCADES - 1], true, world, sum,
                       left);
    return sum + left * ambient;
}
#endif

#endif
