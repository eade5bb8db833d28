// Bins of the sphere of normals for the cosine strategy (ETK_STRATEGY_COSINE): the octahedral
// map of a unit vector folded onto the square [0,1)^2, cut into ETK_NORMAL_BIN_SIDE^2 cells
// (their solid angles within 0.34 .. 1.65 of the mean, tests/kernels/normal_bins_test.cpp). A
// vertex's shading normal picks its bin; the bin's light table (the map's regions weighted by a
// bound of the clamped cosine to any normal of the bin, host/lib/prepare/cosine_tables.h) is what
// its light sample is drawn from. The bins are a fixed partition of the sphere, so preparation
// builds every table once, with no learning.
#ifndef ETK_NORMAL_BINS_H
#define ETK_NORMAL_BINS_H
#include "compat.h"

// 32 x 32 bins of ~6 degrees. Diffuse vertices, unoccluded, under the efficiency suite's maps, one
// light and one cosine sample by the balance heuristic (tools/experiments/cosine_bins.py): 8 x 8
// bins leave 0.22-0.44 of the paper's variance, 16 x 16 0.18-0.34, 32 x 32 0.17-0.31 (spot1Lux's
// one texel: 1.00); 2 MB of tables.
#define ETK_NORMAL_BIN_SIDE 32
#define ETK_NORMAL_BINS (ETK_NORMAL_BIN_SIDE * ETK_NORMAL_BIN_SIDE)

ETK_BEGIN

// The octahedral square's point of unit vector n, in [0,1]^2: the upper hemisphere (y >= 0) is
// the inner diamond, the lower one folded over its edges into the corners.
ETK_FN float2 etk_octahedral_point(float3 n) {
    float s = fabs(n.x) + fabs(n.y) + fabs(n.z);
    float x = n.x / s, z = n.z / s;
    if (n.y < 0.0f) {
        float fx = (1.0f - fabs(z)) * (x >= 0.0f ? 1.0f : -1.0f);
        float fz = (1.0f - fabs(x)) * (z >= 0.0f ? 1.0f : -1.0f);
        x = fx;
        z = fz;
    }
    return make_float2(0.5f * x + 0.5f, 0.5f * z + 0.5f);
}

// The unit vector of octahedral point q in [0,1]^2 (the inverse of etk_octahedral_point).
ETK_FN float3 etk_octahedral_dir(float2 q) {
    float x = 2.0f * q.x - 1.0f, z = 2.0f * q.y - 1.0f;
    float y = 1.0f - fabs(x) - fabs(z);
    if (y < 0.0f) {
        float fx = (1.0f - fabs(z)) * (x >= 0.0f ? 1.0f : -1.0f);
        float fz = (1.0f - fabs(x)) * (z >= 0.0f ? 1.0f : -1.0f);
        x = fx;
        z = fz;
    }
    return normalize(make_float3(x, y, z));
}

// The bin of unit normal n (world space), 0 .. ETK_NORMAL_BINS - 1.
ETK_FN int etk_normal_bin(float3 n) {
    float2 q = etk_octahedral_point(n);
    int i = clamp((int)(q.x * (float)ETK_NORMAL_BIN_SIDE), 0, ETK_NORMAL_BIN_SIDE - 1);
    int j = clamp((int)(q.y * (float)ETK_NORMAL_BIN_SIDE), 0, ETK_NORMAL_BIN_SIDE - 1);
    return j * ETK_NORMAL_BIN_SIDE + i;
}

// The direction at the centre of bin k's square.
ETK_FN float3 etk_normal_bin_centre(int k) {
    float inv = 1.0f / (float)ETK_NORMAL_BIN_SIDE;
    return etk_octahedral_dir(make_float2(((float)(k % ETK_NORMAL_BIN_SIDE) + 0.5f) * inv,
                                          ((float)(k / ETK_NORMAL_BIN_SIDE) + 0.5f) * inv));
}

ETK_END

#endif
