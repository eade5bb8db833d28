// Test kernel: the sampler's values for n consecutive indices, to compare with the host bit for
// bit (tests/sampler_test.cpp).
#include "sampler.h"

__kernel void sample_pairs(int sampler, uint seed, uint stream, uint first, uint pair, int n,
                           __global float* out) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    float2 v = etk_sample_pair(sampler, seed, stream, first + (uint)i, pair);
    out[2 * i] = v.x;
    out[2 * i + 1] = v.y;
}
