// Drawing environment-map samples in bulk: on an OpenCL device (kernels/envmap_sample.cl) and
// natively on the host from the same shared header (kernels/envmap.h).
#pragma once
#include "load/environment_map.h"
#include "opencl/opencl_runtime.h"

#include <vector>

namespace et {

struct EnvSampleRecord {
    float dir[3];
    float pdf;
    float radiance[3];
    float pad;
    int row, col;
};

// The device side: uploads the map once, then draws batches.
class EnvSamplerCL {
  public:
    EnvSamplerCL(ClRuntime& rt, const EnvMap& env, ProgramBuildInfo* build = nullptr);

    std::vector<EnvSampleRecord> sample_uniforms(const std::vector<float>& uniforms);
    // The same, ETK_LIGHT_BATCH samples per work-item as the sample_lights stage draws them.
    std::vector<EnvSampleRecord> sample_uniforms_batched(const std::vector<float>& uniforms);
    std::vector<EnvSampleRecord> sample_sequence(int sampler, uint32_t seed, uint32_t stream,
                                                 uint32_t first, int n);

  private:
    std::vector<EnvSampleRecord> run(cl::Kernel& k, int n, int items, int out_arg);
    std::vector<EnvSampleRecord> run_uniforms(cl::Kernel& k, const std::vector<float>& uniforms,
                                              int per_item);
    ClRuntime& rt_;
    etk::EtkEnvMap desc_;
    cl::Buffer dist_, texels_;
    cl::Kernel uniforms_kernel_, batched_kernel_, sequence_kernel_;
    cl::Program program_;
};

// The host reference from the same shared code, one sample per uniform pair.
std::vector<EnvSampleRecord> sample_env_host(const EnvMap& env, const std::vector<float>& uniforms);
// The same with the sampler's values, on `threads` threads (0: all cores).
std::vector<EnvSampleRecord> sample_env_host_sequence(const EnvMap& env, int sampler, uint32_t seed,
                                                      uint32_t stream, uint32_t first, int n,
                                                      int threads = 1);

} // namespace et
