// Benchmark-only twin of envmap_sample_sequence (tools/bench/bench_sampling.cpp): the same
// sampling work, but each work-item draws `per_item` consecutive samples and writes only their
// sums (radiance rgb, solid-angle pdf), so the benchmark measures sampling rather than the copy
// of 40 bytes per sample back to the host. The native twin in the benchmark does the identical
// reduction from the same headers.
#include "envmap.h"
#include "sampler.h"

__kernel void envmap_sample_reduce(__global const float* dist, __global const float* texels,
                                   EtkEnvMap env, int sampler, uint seed, uint stream, uint first,
                                   int n, int per_item, __global float4* out) {
    int item = get_global_id(0);
    int begin = item * per_item;
    int end = min(begin + per_item, n);
    float4 acc = (float4)(0.0f, 0.0f, 0.0f, 0.0f);
    for (int i = begin; i < end; ++i) {
        float2 xi = etk_sample_pair(sampler, seed, stream, first + (uint)i, 0u);
        EtkEnvSample s = etk_env_sample(dist, env, xi);
        float3 L = etk_env_radiance_uv(texels, env, s.uv);
        acc += (float4)(L.x, L.y, L.z, s.pdf);
    }
    if (begin < n)
        out[item] = acc;
}
