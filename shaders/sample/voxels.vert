#version 460
#extension GL_GOOGLE_include_directive : require
// The seed's voxel view as faces: the host lists every side of a voxel that no other voxel covers, and
// one non-instanced draw makes two triangles of each (lavapipe shades large vertex batches fast, where a
// ray per pixel through the volume cost it more than the rest of the frame).
#include "sample_common.glsl"

layout(set = 0, binding = 4, std430) readonly buffer Faces { VoxelFace faces[]; };
layout(location = 0) out vec3 world;
layout(location = 1) out vec3 albedo;
layout(location = 2) out vec3 normal;

void main() {
    VoxelFace face = faces[uint(gl_VertexIndex) / kFaceVertices];
    uint corner = uint(gl_VertexIndex) % kFaceVertices;
    ivec3 voxel = ivec3(face.ij & 0xffffu, face.ij >> 16, face.k_side & 0xffffu);
    uint side = face.k_side >> 16;
    int axis = int(side >> 1);
    bool positive = (side & 1u) != 0u;
    const vec2 quad[6] = vec2[6](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1), vec2(0, 1));
    vec3 p = vec3(voxel);
    p[axis] += positive ? 1.0 : 0.0;
    p[(axis + 1) % 3] += quad[corner].x;
    p[(axis + 2) % 3] += quad[corner].y;
    world = frame.voxel_origin.xyz + p * frame.voxel_origin.w;
    normal = vec3(0.0);
    normal[axis] = positive ? 1.0 : -1.0;
    albedo = mix(vec3(0.85, 0.55, 0.2), vec3(0.95, 0.85, 0.5), float((voxel.x + voxel.y + voxel.z) & 1));
    // A face turned away from the eye collapses to a point, which the rasterizer drops before any setup:
    // half the faces of a closed shell, and the whole underside of the ground.
    float plane = frame.voxel_origin[axis] + p[axis] * frame.voxel_origin.w;
    bool facing = positive ? frame.camera[axis] > plane : frame.camera[axis] < plane;
    gl_Position = facing ? frame.view_proj * vec4(world, 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
