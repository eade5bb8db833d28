// Test kernel: passes of a film added to the exact sums by etk_fixed_add_pixel, the function the
// renderer's fold_film runs on a GPU (tests/kernels/film_fixed_test.cpp).
#include "film_fixed.h"

__kernel void fold(__global const float4* sum, __global const float4* sq,
                   __global EtkFixedPixel* sums, int n) {
    int i = get_global_id(0);
    if (i < n)
        etk_fixed_add_pixel(sums + i, sum[i], sq[i]);
}
