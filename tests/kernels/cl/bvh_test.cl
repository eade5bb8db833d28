// Test kernel: etk_bvh_traverse on a batch of rays, to compare with brute force on the host
// (tests/bvh_test.cpp). Ray i: origin org[i].xyz with tmax in org[i].w, direction dir[i].xyz.
// Result: (t, triangle as int bits or -1, b1, b2).
#include "bvh.h"

__kernel void bvh_trace(__global const float4* nodes, __global const float4* packets,
                        __global const float4* org, __global const float4* dir, int any_hit, int n,
                        __global float4* out) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    float4 o = org[i], d = dir[i];
    EtkHit h;
    int hit = etk_bvh_traverse(nodes, packets, (float3)(o.x, o.y, o.z), (float3)(d.x, d.y, d.z),
                               o.w, any_hit, &h);
    out[i] = (float4)(h.t, as_float(hit ? h.prim : -1), h.b1, h.b2);
}
