// Draws environment-map samples: one work-item per sample, binary searches in the kernel.
// Output per sample: 8 floats (direction xyz, solid-angle pdf, radiance rgb, 0) and 2 ints (cell).
#include "envmap.h"
#include "sampler.h"

static void store_sample(__global const float* texels, EtkEnvMap env, EtkEnvSample s, int i,
                         __global float* out, __global int* cells) {
    float3 L = etk_env_radiance_uv(texels, env, s.uv);
    __global float* o = out + 8 * i;
    o[0] = s.dir.x;
    o[1] = s.dir.y;
    o[2] = s.dir.z;
    o[3] = s.pdf;
    o[4] = L.x;
    o[5] = L.y;
    o[6] = L.z;
    o[7] = 0.0f;
    cells[2 * i] = s.row;
    cells[2 * i + 1] = s.col;
}

// Samples from given uniforms (2 floats each): for comparison with the host reference.
__kernel void envmap_sample_uniforms(__global const float* dist, __global const float* texels,
                                     EtkEnvMap env, __global const float* uniforms, int n,
                                     __global float* out, __global int* cells) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    float2 xi = (float2)(uniforms[2 * i], uniforms[2 * i + 1]);
    store_sample(texels, env, etk_env_sample(dist, env, xi), i, out, cells);
}

// The same uniforms drawn ETK_LIGHT_BATCH per work-item, as the sample_lights stage draws them
// (etk_env_light_batch): meant to give etk_env_sample's bits on every device.
__kernel void envmap_sample_uniforms_batched(__global const float* dist,
                                             __global const float* texels, EtkEnvMap env,
                                             __global const float* uniforms, int n,
                                             __global float* out, __global int* cells) {
    int first = get_global_id(0) * ETK_LIGHT_BATCH;
    if (first >= n)
        return;
    float xu[ETK_LIGHT_BATCH], xv[ETK_LIGHT_BATCH];
    for (int k = 0; k < ETK_LIGHT_BATCH; ++k) { // past the end: the last sample again, not stored
        int j = min(first + k, n - 1);
        xu[k] = uniforms[2 * j];
        xv[k] = uniforms[2 * j + 1];
    }
    float dx[ETK_LIGHT_BATCH], dy[ETK_LIGHT_BATCH], dz[ETK_LIGHT_BATCH], pdf[ETK_LIGHT_BATCH];
    float Lr[ETK_LIGHT_BATCH], Lg[ETK_LIGHT_BATCH], Lb[ETK_LIGHT_BATCH];
    int row[ETK_LIGHT_BATCH], col[ETK_LIGHT_BATCH];
    etk_env_light_batch(dist, texels, env, xu, xv, dx, dy, dz, pdf, Lr, Lg, Lb, row, col);
    for (int k = 0; k < ETK_LIGHT_BATCH && first + k < n; ++k) {
        __global float* o = out + 8 * (first + k);
        o[0] = dx[k];
        o[1] = dy[k];
        o[2] = dz[k];
        o[3] = pdf[k];
        o[4] = Lr[k];
        o[5] = Lg[k];
        o[6] = Lb[k];
        o[7] = 0.0f;
        cells[2 * (first + k)] = row[k];
        cells[2 * (first + k) + 1] = col[k];
    }
}

// Samples with the sampler: sample i is index (first + i) of `stream`, dimension pair 0.
__kernel void envmap_sample_sequence(__global const float* dist, __global const float* texels,
                                     EtkEnvMap env, int sampler, uint seed, uint stream, uint first,
                                     int n, __global float* out, __global int* cells) {
    int i = get_global_id(0);
    if (i >= n)
        return;
    float2 xi = etk_sample_pair(sampler, seed, stream, first + (uint)i, 0u);
    store_sample(texels, env, etk_env_sample(dist, env, xi), i, out, cells);
}
