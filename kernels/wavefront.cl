// The wavefront path tracer: one small kernel per stage (integrator.h holds the stages, shared
// with the native back end). Every kernel takes the same argument list, so the host sets it once;
// each runs over exactly the live entries of its queue (global size rounded up to the fixed
// work-group size, the tail returning at once).
#include "integrator.h"

#define ETK_KERNEL_ARGS                                                                            \
    __global const float4 *nodes, __global const float4 *tris, __global const float4 *normals,     \
        __global const int *tri_material, __global const float4 *materials,                        \
        __global const float *env_dist, __global const float *env_texels, __global float4 *ray_o,  \
        __global float4 *ray_d, __global float4 *beta, __global float4 *radiance,                  \
        __global float4 *hit, __global float4 *shadow_o, __global float4 *shadow_d,                \
        __global float4 *shadow_L, __global int *pixel, __global const int *ray_in,                \
        __global int *ray_out, __global int *escaped, __global int *shade, __global int *shadow,   \
        volatile __global uint *counters, __global float4 *film, EtkParams params, int n

#define ETK_UNPACK                                                                                 \
    EtkScene S = {nodes, tris, normals, tri_material, materials, env_dist, env_texels};            \
    EtkPaths P = {ray_o, ray_d, beta, radiance, hit, shadow_o, shadow_d, shadow_L, pixel};         \
    EtkQueues Q = {ray_in, ray_out, escaped, shade, shadow, counters};                             \
    int i = get_global_id(0);                                                                      \
    if (i >= n)                                                                                    \
        return

__kernel void generate(ETK_KERNEL_ARGS) {
    ETK_UNPACK;
    (void)S;
    etk_generate(P, Q, params, i);
}

__kernel void intersect(ETK_KERNEL_ARGS) {
    ETK_UNPACK;
    etk_intersect(P, Q, S, params, i);
}

__kernel void escaped_rays(ETK_KERNEL_ARGS) {
    ETK_UNPACK;
    etk_escaped(P, Q, S, params, i);
}

__kernel void shade_hits(ETK_KERNEL_ARGS) {
    ETK_UNPACK;
    etk_shade(P, Q, S, params, i);
}

__kernel void trace_shadows(ETK_KERNEL_ARGS) {
    ETK_UNPACK;
    etk_shadow(P, Q, S, i);
}

__kernel void accumulate(ETK_KERNEL_ARGS) {
    ETK_UNPACK;
    (void)S;
    etk_accumulate(P, Q, film, i);
}
