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
