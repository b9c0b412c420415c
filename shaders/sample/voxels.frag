#version 460
#extension GL_GOOGLE_include_directive : require
// The seed's voxel view: a ray per pixel walks the occupancy volume voxel by voxel (Amanatides and Woo,
// "A fast voxel traversal algorithm", Eurographics 1987) and shades the first solid voxel's face.
#include "sample_common.glsl"

layout(location = 0) in vec2 ndc;
layout(location = 0) out vec4 colour;

void main() {
    if (frame.voxel_dims.w < 0.5) discard;
    vec4 near = frame.inverse_view_proj * vec4(ndc, 0.0, 1.0);
    vec4 far = frame.inverse_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 origin = near.xyz / near.w;
    vec3 dir = normalize(far.xyz / far.w - origin);
    float h = frame.voxel_origin.w;
    ivec3 dims = ivec3(frame.voxel_dims.xyz);
    // Enter the grid's box (slab test), then step in voxel units.
    vec3 lo = (frame.voxel_origin.xyz - origin) / dir;
    vec3 hi = (frame.voxel_origin.xyz + vec3(dims) * h - origin) / dir;
    vec3 t_near = min(lo, hi), t_far = max(lo, hi);
    float t0 = max(max(t_near.x, t_near.y), max(t_near.z, 0.0));
    float t1 = min(min(t_far.x, t_far.y), t_far.z);
    if (t0 >= t1) discard;
    vec3 start = (origin + dir * (t0 + 1e-4 * h) - frame.voxel_origin.xyz) / h;
    ivec3 cell = clamp(ivec3(floor(start)), ivec3(0), dims - 1);
    ivec3 step_dir = ivec3(sign(dir));
    vec3 delta = abs(1.0 / dir);
    vec3 next = (vec3(cell) + max(vec3(step_dir), vec3(0.0)) - start) / dir;
    next = mix(next, vec3(1e30), equal(dir, vec3(0.0)));
    int axis = t_near.x >= max(t_near.y, t_near.z) ? 0 : (t_near.y >= t_near.z ? 1 : 2);
    float t = 0.0;
    for (int i = 0; i < dims.x + dims.y + dims.z; ++i) {
        if (texelFetch(occupancy, cell, 0).r > 0.5) {
            vec3 n = vec3(0.0);
            n[axis] = -float(step_dir[axis]);
            vec3 hit = origin + dir * (t0 + t * h);
            vec3 albedo = mix(vec3(0.85, 0.55, 0.2), vec3(0.95, 0.85, 0.5), float((cell.x + cell.y + cell.z) & 1));
            colour = vec4(shade(albedo, n, hit), 1.0);
            vec4 clip = frame.view_proj * vec4(hit, 1.0);
            gl_FragDepth = clip.z / clip.w;
            return;
        }
        if (next.x < next.y && next.x < next.z) {
            axis = 0;
            t = next.x;
            next.x += delta.x;
            cell.x += step_dir.x;
        } else if (next.y < next.z) {
            axis = 1;
            t = next.y;
            next.y += delta.y;
            cell.y += step_dir.y;
        } else {
            axis = 2;
            t = next.z;
            next.z += delta.z;
            cell.z += step_dir.z;
        }
        if (any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, dims))) break;
    }
    discard;
}
