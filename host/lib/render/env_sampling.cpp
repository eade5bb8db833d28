#include "render/env_sampling.h"
#include "util/parallel.h"

#include "util/error.h"
#include "kernels/envmap.h"
#include "kernels/sampler.h"

#include <algorithm>
#include <cstring>
#include <thread>

namespace et {
namespace {

EnvSampleRecord record(const EnvMap& env, const etk::EtkEnvMap& desc, etk::float2 xi) {
    etk::EtkEnvSample s = etk::etk_env_sample(env.dist.table.data(), desc, xi);
    etk::float3 L = etk::etk_env_radiance_uv(env.image.rgb.data(), desc, s.uv);
    return EnvSampleRecord{{s.dir.x, s.dir.y, s.dir.z}, s.pdf, {L.x, L.y, L.z}, 0.0f, s.row, s.col};
}

} // namespace

EnvSamplerCL::EnvSamplerCL(ClRuntime& rt, const EnvMap& env, ProgramBuildInfo* build)
    : rt_(rt), desc_(env.desc()) {
    check_buffer_sizes({{"env_dist", env.dist.table.size() * sizeof(float)},
                        {"env_texels", env.image.rgb.size() * sizeof(float)}},
                       rt.limits(), rt.device().device_name);
    program_ = rt.build("envmap_sample.cl", "", build);
    try {
        dist_ = cl::Buffer(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                           env.dist.table.size() * sizeof(float),
                           const_cast<float*>(env.dist.table.data()));
        texels_ = cl::Buffer(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                             env.image.rgb.size() * sizeof(float),
                             const_cast<float*>(env.image.rgb.data()));
        uniforms_kernel_ = cl::Kernel(program_, "envmap_sample_uniforms");
        batched_kernel_ = cl::Kernel(program_, "envmap_sample_uniforms_batched");
        sequence_kernel_ = cl::Kernel(program_, "envmap_sample_sequence");
    } catch (const cl::Error& e) {
        throw Error(std::string("cannot set up the sampling kernels: ") + e.what() + ": " +
                    cl_error_name(e.err()));
    }
    for (cl::Kernel* k : {&uniforms_kernel_, &batched_kernel_, &sequence_kernel_}) {
        k->setArg(0, dist_);
        k->setArg(1, texels_);
        k->setArg(2, sizeof(desc_), &desc_);
    }
}

// n samples from `items` work-items.
std::vector<EnvSampleRecord> EnvSamplerCL::run(cl::Kernel& k, int n, int items, int out_arg) {
    std::vector<EnvSampleRecord> result(n);
    if (n == 0)
        return result;
    try {
        cl::Buffer out(rt_.context(), CL_MEM_WRITE_ONLY, sizeof(float) * 8 * n);
        cl::Buffer cells(rt_.context(), CL_MEM_WRITE_ONLY, sizeof(int) * 2 * n);
        k.setArg(out_arg, out);
        k.setArg(out_arg + 1, cells);
        const size_t local = choose_local_size(k, rt_.device().device, rt_.limits());
        rt_.queue().enqueueNDRangeKernel(
            k, cl::NullRange, cl::NDRange((items + local - 1) / local * local), cl::NDRange(local));
        std::vector<float> o(8 * static_cast<size_t>(n));
        std::vector<int> c(2 * static_cast<size_t>(n));
        rt_.queue().enqueueReadBuffer(out, CL_FALSE, 0, o.size() * sizeof(float), o.data());
        rt_.queue().enqueueReadBuffer(cells, CL_TRUE, 0, c.size() * sizeof(int), c.data());
        for (int i = 0; i < n; ++i) {
            std::memcpy(&result[i], &o[8 * static_cast<size_t>(i)], 8 * sizeof(float));
            result[i].row = c[2 * i];
            result[i].col = c[2 * i + 1];
        }
    } catch (const cl::Error& e) {
        throw Error(std::string("sampling kernel failed: ") + e.what() + ": " +
                    cl_error_name(e.err()));
    }
    return result;
}

// The uniforms' samples, `per_item` of them per work-item.
std::vector<EnvSampleRecord>
EnvSamplerCL::run_uniforms(cl::Kernel& k, const std::vector<float>& uniforms, int per_item) {
    const int n = static_cast<int>(uniforms.size() / 2);
    cl::Buffer u(rt_.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                 std::max<size_t>(1, uniforms.size()) * sizeof(float),
                 uniforms.empty() ? nullptr : const_cast<float*>(uniforms.data()));
    k.setArg(3, u);
    k.setArg(4, n);
    return run(k, n, (n + per_item - 1) / per_item, 5);
}

std::vector<EnvSampleRecord> EnvSamplerCL::sample_uniforms(const std::vector<float>& uniforms) {
    return run_uniforms(uniforms_kernel_, uniforms, 1);
}

std::vector<EnvSampleRecord>
EnvSamplerCL::sample_uniforms_batched(const std::vector<float>& uniforms) {
    return run_uniforms(batched_kernel_, uniforms, ETK_LIGHT_BATCH);
}

std::vector<EnvSampleRecord> EnvSamplerCL::sample_sequence(int sampler, uint32_t seed,
                                                           uint32_t stream, uint32_t first, int n) {
    sequence_kernel_.setArg(3, sampler);
    sequence_kernel_.setArg(4, seed);
    sequence_kernel_.setArg(5, stream);
    sequence_kernel_.setArg(6, first);
    sequence_kernel_.setArg(7, n);
    return run(sequence_kernel_, n, n, 8);
}

std::vector<EnvSampleRecord> sample_env_host(const EnvMap& env,
                                             const std::vector<float>& uniforms) {
    const etk::EtkEnvMap desc = env.desc();
    std::vector<EnvSampleRecord> out(uniforms.size() / 2);
    for (size_t i = 0; i < out.size(); ++i)
        out[i] = record(env, desc, etk::make_float2(uniforms[2 * i], uniforms[2 * i + 1]));
    return out;
}

std::vector<EnvSampleRecord> sample_env_host_sequence(const EnvMap& env, int sampler, uint32_t seed,
                                                      uint32_t stream, uint32_t first, int n,
                                                      int threads) {
    const etk::EtkEnvMap desc = env.desc();
    std::vector<EnvSampleRecord> out(n);
    threads = thread_count(threads);
    auto work = [&](int t) {
        const int begin = static_cast<int>(static_cast<int64_t>(n) * t / threads);
        const int end = static_cast<int>(static_cast<int64_t>(n) * (t + 1) / threads);
        for (int i = begin; i < end; ++i)
            out[i] = record(env, desc, etk::etk_sample_pair(sampler, seed, stream, first + i, 0));
    };
    run_on_threads(threads, work);
    return out;
}

} // namespace et
