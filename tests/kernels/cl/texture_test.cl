// Test kernel: etk_texture at n texture coordinates and etk_hit_uv at n barycentrics, to compare
// with the host bit for bit (tests/kernels/texture_test.cpp).
#include "texture_lookup.h"

__kernel void texture_lookup(__global const float4* info, __global const float* texels, int tex,
                             __global const float2* uv, int n, __global float4* out) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    float3 c = etk_texture(info, texels, tex, uv[i]);
    out[i] = (float4)(c.x, c.y, c.z, 0.0f);
}

__kernel void hit_uv(__global const float* tri_uv, __global const float2* bary, int prim, int n,
                     __global float2* out) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    out[i] = etk_hit_uv(tri_uv, prim, bary[i].x, bary[i].y);
}
