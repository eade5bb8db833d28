// Environment-map sampling throughput: the OpenCL kernel on the PoCL CPU device (both cores)
// next to the same sampling done natively on the host with two threads, same map, same sampler
// (scrambled Sobol'), same number of samples per batch, in one run. Samples/s are rate counters;
// tools/bench/ratios.py turns the JSON output into kernel/native ratios.
//
//   records: the project's API as it is (EnvSamplerCL::sample_sequence vs
//            sample_env_host_sequence): every sample's direction, pdf, radiance and cell come back
//            to the host (40 bytes a sample), so this also measures allocation and copying.
//   reduce:  benchmark-only tools/bench/envmap_sample_bench.cl and its native twin here: the same
//            sampling, each work-item / loop iteration summing `per_item` consecutive samples'
//            radiance and pdf, so the output is small and both sides measure sampling.
#include "bench_kernels.h"
#include "bench_maps.h"
#include "util/parallel.h"
#include "render/env_sampling.h"
#include "load/environment_map.h"
#include "kernels/sampler.h"
#include "opencl/opencl_runtime.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <thread>

namespace {

constexpr int kSamples = 1 << 20; // per batch
constexpr uint32_t kSeed = 1;
constexpr int kSampler = ETK_SAMPLER_SOBOL;

struct Sum4 {
    float x, y, z, w; // radiance rgb, pdf; laid out like the kernel's float4
};
static_assert(sizeof(Sum4) == 16, "must match cl float4");

et::ClRuntime& runtime() {
    static et::ClRuntime rt(0);
    return rt;
}

// One map with everything both sides need, made on first use (outside the timed loops).
struct Fixture {
    et::EnvMap env;
    etk::EtkEnvMap desc;
    std::unique_ptr<et::EnvSamplerCL> sampler;
    cl::Program bench_program;
    cl::Kernel reduce;
    cl::Buffer dist, texels, out;
};

Fixture& fixture(const std::string& map) {
    static std::map<std::string, std::unique_ptr<Fixture>> cache;
    auto& f = cache[map];
    if (!f) {
        f = std::make_unique<Fixture>();
        f->env = et::make_envmap(map, et::bench::real_map(map), et::DistributionOptions{});
        f->desc = f->env.desc();
        et::ClRuntime& rt = runtime();
        f->sampler = std::make_unique<et::EnvSamplerCL>(rt, f->env);
        f->bench_program = etb::build_bench_kernel(rt, "envmap_sample_bench.cl");
        f->reduce = cl::Kernel(f->bench_program, "envmap_sample_reduce");
        f->dist = cl::Buffer(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                             f->env.dist.table.size() * sizeof(float), f->env.dist.table.data());
        f->texels = cl::Buffer(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                               f->env.image.rgb.size() * sizeof(float), f->env.image.rgb.data());
        f->out = cl::Buffer(rt.context(), CL_MEM_WRITE_ONLY, sizeof(Sum4) * kSamples);
        f->reduce.setArg(0, f->dist);
        f->reduce.setArg(1, f->texels);
        f->reduce.setArg(2, sizeof(f->desc), &f->desc);
        f->reduce.setArg(3, kSampler);
        f->reduce.setArg(4, kSeed);
        f->reduce.setArg(5, 0u);
        f->reduce.setArg(9, f->out);
    }
    return *f;
}

int items_for(int n, int per_item) {
    return (n + per_item - 1) / per_item;
}

// The kernel's reduction on the device; local == 0 lets PoCL choose the work-group size.
void kernel_reduce(Fixture& f, uint32_t first, int n, int per_item, int local,
                   std::vector<Sum4>& out) {
    const int items = items_for(n, per_item);
    f.reduce.setArg(6, first);
    f.reduce.setArg(7, n);
    f.reduce.setArg(8, per_item);
    cl::CommandQueue& q = runtime().queue();
    if (local > 0)
        q.enqueueNDRangeKernel(f.reduce, cl::NullRange,
                               cl::NDRange((items + local - 1) / local * local),
                               cl::NDRange(local));
    else
        q.enqueueNDRangeKernel(f.reduce, cl::NullRange, cl::NDRange(items), cl::NullRange);
    out.resize(items);
    q.enqueueReadBuffer(f.out, CL_TRUE, 0, items * sizeof(Sum4), out.data());
}

// The native twin: the identical per-item loop from the same headers, items split over threads.
void native_reduce(const Fixture& f, uint32_t first, int n, int per_item, int threads,
                   std::vector<Sum4>& out) {
    const int items = items_for(n, per_item);
    out.resize(items);
    const float* dist = f.env.dist.table.data();
    const float* texels = f.env.image.rgb.data();
    const etk::EtkEnvMap desc = f.desc;
    auto work = [&](int t) {
        const int i0 = static_cast<int>(static_cast<int64_t>(items) * t / threads);
        const int i1 = static_cast<int>(static_cast<int64_t>(items) * (t + 1) / threads);
        for (int item = i0; item < i1; ++item) {
            const int begin = item * per_item, end = std::min(begin + per_item, n);
            Sum4 acc{0.0f, 0.0f, 0.0f, 0.0f};
            for (int i = begin; i < end; ++i) {
                etk::float2 xi = etk::etk_sample_pair(kSampler, kSeed, 0u, first + i, 0u);
                etk::EtkEnvSample s = etk::etk_env_sample(dist, desc, xi);
                etk::float3 L = etk::etk_env_radiance_uv(texels, desc, s.uv);
                acc.x += L.x;
                acc.y += L.y;
                acc.z += L.z;
                acc.w += s.pdf;
            }
            out[item] = acc;
        }
    };
    et::run_on_threads(threads, work);
}

double total_radiance(const std::vector<Sum4>& v) {
    double s = 0.0;
    for (const Sum4& x : v)
        s += double(x.x) + x.y + x.z;
    return s;
}

void set_rate(benchmark::State& state) {
    state.counters["samples/s"] = benchmark::Counter(
        static_cast<double>(kSamples) * state.iterations(), benchmark::Counter::kIsRate);
}

void BM_KernelRecords(benchmark::State& state, std::string map) {
    Fixture& f = fixture(map);
    f.sampler->sample_sequence(kSampler, kSeed, 0, 0, 1024); // first launch builds the WG function
    uint32_t first = 0;
    for (auto _ : state) {
        auto r = f.sampler->sample_sequence(kSampler, kSeed, 0, first, kSamples);
        benchmark::DoNotOptimize(r.data());
        first += kSamples;
    }
    set_rate(state);
}

void BM_NativeRecords(benchmark::State& state, std::string map, int threads) {
    Fixture& f = fixture(map);
    uint32_t first = 0;
    for (auto _ : state) {
        auto r = et::sample_env_host_sequence(f.env, kSampler, kSeed, 0, first, kSamples, threads);
        benchmark::DoNotOptimize(r.data());
        first += kSamples;
    }
    set_rate(state);
}

void BM_KernelReduce(benchmark::State& state, std::string map, int per_item, int local) {
    Fixture& f = fixture(map);
    std::vector<Sum4> dev, host;
    // Warm-up (the work-group function for this local size is compiled at first launch) and a
    // check that both sides computed the same thing.
    kernel_reduce(f, 0, kSamples, per_item, local, dev);
    native_reduce(f, 0, kSamples, per_item, 2, host);
    const double a = total_radiance(dev), b = total_radiance(host);
    uint32_t first = 0;
    for (auto _ : state) {
        kernel_reduce(f, first, kSamples, per_item, local, dev);
        benchmark::DoNotOptimize(dev.data());
        first += kSamples;
    }
    set_rate(state);
    state.counters["check_rel_diff"] = std::fabs(a - b) / std::max(std::fabs(b), 1e-30);
}

void BM_NativeReduce(benchmark::State& state, std::string map, int per_item, int threads) {
    Fixture& f = fixture(map);
    std::vector<Sum4> host;
    uint32_t first = 0;
    for (auto _ : state) {
        native_reduce(f, first, kSamples, per_item, threads, host);
        benchmark::DoNotOptimize(host.data());
        first += kSamples;
    }
    set_rate(state);
}

void register_all() {
    for (std::string map : {"royal_esplanade_1k.hdr", "grace.hdr"}) {
        const std::string m = map.substr(0, map.find('.'));
        auto reg = [&](const std::string& name, auto fn, auto... args) {
            benchmark::RegisterBenchmark(("BM_Sample/" + m + "/" + name).c_str(), fn, args...)
                ->Unit(benchmark::kMillisecond)
                ->UseRealTime();
        };
        reg("kernel_records", BM_KernelRecords, map);
        reg("native_records_2threads", BM_NativeRecords, map, 2);
        for (int per_item : {1, 64}) {
            const std::string p = "/per_item:" + std::to_string(per_item);
            reg("kernel_reduce" + p + "/local:64", BM_KernelReduce, map, per_item, 64);
            reg("native_reduce_2threads" + p, BM_NativeReduce, map, per_item, 2);
        }
        // Exploration: work-group size (PoCL generates one work-group function per size) and a
        // single native thread for scale.
        for (int local : {0, 8, 16, 256})
            reg("kernel_reduce/per_item:64/local:" + std::to_string(local), BM_KernelReduce, map,
                64, local);
        reg("native_reduce_1thread/per_item:64", BM_NativeReduce, map, 64, 1);
    }
}

} // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    try {
        const auto& dev = runtime().device();
        benchmark::AddCustomContext("opencl_device", dev.device_name + " (" + dev.platform_name +
                                                         ", " + dev.driver_version + ", " +
                                                         std::to_string(dev.compute_units) +
                                                         " compute units)");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_sampling: %s\n", e.what());
        return 1;
    }
    if (const char* m = std::getenv("POCL_WORK_GROUP_METHOD"))
        benchmark::AddCustomContext("POCL_WORK_GROUP_METHOD", m);
    register_all();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
