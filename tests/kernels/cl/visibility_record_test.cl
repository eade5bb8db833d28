// Test kernel: the shadow stage's record sums (etk_guide_record_light) of a batch of records, to
// compare with the host's bit for bit (tests/kernels/visibility_record_test.cpp).
#include "visibility_record.h"

__kernel void record_lights(volatile __global uint* sums, EtkParams p, __global const float* box,
                            __global const int* keys, __global const float* values,
                            __global const float* reaches, __global const int* exits,
                            __global const float2* parts, int n) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    etk_guide_record_light(sums, p, box, keys[i], values[i], reaches[i], exits[i], parts[i]);
}

// The accumulate stage's continuation records (etk_guide_record_continuation) of a batch: ray i
// is rays[2 i] (origin, density) and rays[2 i + 1] (direction).
__kernel void record_continuations(volatile __global uint* sums, EtkParams p,
                                   __global const float* cells, __global const int* keys,
                                   __global const float* values, __global const float4* rays,
                                   int n) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    float4 o = rays[2 * i], d = rays[2 * i + 1];
    etk_guide_record_continuation(sums, p, cells, keys[i], values[i], (float3)(o.x, o.y, o.z),
                                  (float3)(d.x, d.y, d.z), o.w);
}
