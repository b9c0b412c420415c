// Layouts shared by the sample game's shaders and sample_game/renderer.cpp.
#ifndef GUST_SAMPLE_IO_H
#define GUST_SAMPLE_IO_H

#include "../common.h"

GUST_NAMESPACE_BEGIN

GUST_CONST uint kFoliageGroupSize = 64;
/// Vertices of one grass blade: one triangle, root to tip.
GUST_CONST uint kBladeVertices = 3;
/// Vertices of one wind arrow: a shaft of two triangles and a head.
GUST_CONST uint kArrowVertices = 9;
/// Workgroup edge of the slice's fill (slice.comp): kSliceGroupSize² texels a group.
GUST_CONST uint kSliceGroupSize = 8;
/// Most texels along each side of the slice's image.
GUST_CONST uint kSliceTexelsMax = 1024;

/// Wind textures the shaders read, finest first (GUST_CASCADES in sample_common.glsl): a System with fewer
/// cascades has the slots past its coarsest bound to its coarsest, which leaves gust_wind's answer as it
/// is (a cascade blended into itself), so the shaders need no count and index the array by constants only.
GUST_CONST uint kWindCascades = 4;

/// Per-frame values every pass reads (uniform buffer, binding 0; only vec4 and mat4 for std140).
struct FrameUniforms {
    mat4 view_proj;
    mat4 inverse_view_proj;
    mat4 wind_world_to_texture[kWindCascades]; ///< each cascade's WindTexture::world_to_texture
    vec4 ambient;    ///< xyz: gust's ambient wind this frame (m/s), which answers beyond the coarsest cascade
    vec4 coarse_min; ///< xyz: min corner of the coarsest cascade (world, m); w: its cell size (m)
    vec4 camera;     ///< xyz: eye (world, m); w: time (s)
    vec4 light;      ///< xyz: unit vector towards the sun; w: grass count
    vec4 voxel_origin; ///< xyz: min corner of the voxel grid (world, m); w: voxel size (m)
    vec4 wind_min;     ///< xyz: min corner of the wind domain (world, m); w: cell size (m)
    vec4 wind_cells;   ///< xyz: wind cells per axis; w: speed drawn as the top colour (m/s)
    vec4 slice;        ///< x: slice height (world y, m); y: arrow length per m/s (m); zw: frame size (px)
};

/// One side of a voxel that no other voxel covers (the W view draws these as two triangles each).
struct VoxelFace {
    uint ij;     ///< i in bits 0-15, j in bits 16-31
    uint k_side; ///< k in bits 0-15, side in bits 16-18: 2 * axis + (1 on the axis' positive side)
};
/// Vertices of one voxel face.
GUST_CONST uint kFaceVertices = 6;

/// Push constants of mesh draws.
struct DrawPush {
    mat4 model;
    vec4 color; ///< rgb: linear albedo; a: 1
    vec4 sway; ///< x: foliage slot (< 0: rigid); y: model height where bending starts; z: height of full bend
};

/// Push constants of the foliage update.
struct FoliagePush {
    float dt;   ///< s
    uint count; ///< blades and crowns
    float drag; ///< bend per (m/s)^2 of wind, before the spring
    float pad;
};

/// One blade or crown: what it is (seed, read-only) and how it moves (state, read-write).
struct FoliageSeed {
    vec4 root_height; ///< xyz: root (world, m); w: height (m)
    vec4 yaw_width;   ///< x: yaw (rad); y: width (m); z: stiffness (1/s^2); w: colour variation
};
struct FoliageState {
    vec4 bend; ///< xy: tip displacement over height along world x and z; zw: its rate (1/s)
};

GUST_NAMESPACE_END

#endif
