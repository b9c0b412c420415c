// Push constants and the per-vertex blend shared by skin.comp and voxelizer/src/voxelizer.cpp (and the tests,
// which pose meshes on the CPU with the same function).
#ifndef GUST_SKIN_IO_H
#define GUST_SKIN_IO_H

#include "../common.h"

GUST_NAMESPACE_BEGIN

/// Threads per workgroup of the skinning pass (one vertex each).
GUST_CONST uint kSkinGroupSize = 64;
/// Workgroups per row of a skinning dispatch (the guaranteed x limit); larger meshes take more rows.
GUST_CONST uint kSkinMaxGroupsX = 65535;

/// Push constants of the skinning pass (<= 128 bytes).
struct SkinPush {
    GUST_ADDRESS bind;      ///< float[3 * vertex_count], the bind pose (mesh space)
    GUST_ADDRESS joints;    ///< uvec2[vertex_count]: four uint16 joint indices, two a word, low half first
    GUST_ADDRESS weights;   ///< vec4[vertex_count]
    GUST_ADDRESS palette;   ///< mat4[joint_count]: bind-pose mesh space -> posed mesh space
    GUST_ADDRESS positions; ///< float[3 * vertex_count], written: the posed vertices the voxelizer reads
    uint vertex_count;
    uint pad;
};

/// Linear-blend skinning of one vertex (glTF 2.0 section 3.7.3): the weighted sum of its four joints'
/// matrices applied to its bind position. Weights are used as given (glTF makes them sum to 1).
GUST_INLINE vec3 skin_point(mat4 m0, mat4 m1, mat4 m2, mat4 m3, vec4 w, vec3 bind) {
    vec4 p = vec4(bind, 1.0);
    return vec3(w.x * (m0 * p) + w.y * (m1 * p) + w.z * (m2 * p) + w.w * (m3 * p));
}

GUST_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(gust::shaderio::SkinPush) == 48);
#endif

#endif
