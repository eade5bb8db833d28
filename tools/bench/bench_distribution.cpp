// Distribution build time (paper, Section 3.4 precompute) on one core: the optimised
// build_env_distribution next to the original implementation, measured side by side in one run.
#include "bench_maps.h"
#include "load/env_distribution.h"

#include <benchmark/benchmark.h>

namespace {

using Builder = et::EnvDistribution (*)(const et::RgbImage&, const et::DistributionOptions&);
using MapFn = const et::RgbImage& (*)();

struct MapCase {
    const char* name;
    MapFn image; // made on first use (outside the timed loop), then cached
    bool big;
};

void run_build(benchmark::State& state, Builder build, MapFn map, int threads) {
    const et::RgbImage* image = &map();
    et::DistributionOptions opt; // the defaults: map resolution, blur sigma 0.5
    opt.threads = threads;
    for (auto _ : state) {
        et::EnvDistribution d = build(*image, opt);
        benchmark::DoNotOptimize(d.table.data());
        benchmark::ClobberMemory();
    }
    const double texels = static_cast<double>(image->width) * image->height;
    state.counters["Mtexel/s"] =
        benchmark::Counter(texels * 1e-6 * state.iterations(), benchmark::Counter::kIsRate);
}

void register_all() {
    const MapCase maps[] = {
        {"royal_esplanade_1k_1024x512",
         []() -> const et::RgbImage& { return et::bench::real_map("royal_esplanade_1k.hdr"); },
         false},
        {"sky_1024x512", []() -> const et::RgbImage& { return et::bench::sky_map(1024, 512); },
         false},
        {"esplanade_upsampled_8192x4096",
         []() -> const et::RgbImage& {
             return et::bench::upsampled_map("royal_esplanade_1k.hdr", 8192, 4096);
         },
         true},
        {"sky_8192x4096", []() -> const et::RgbImage& { return et::bench::sky_map(8192, 4096); },
         true},
    };
    // One core (the targets), then two threads (an extra: the 1-core figure is what the targets
    // are about). The pre-optimisation builder is in git history (before c3333e8).
    const struct {
        const char* name;
        Builder fn;
        int threads;
    } impls[] = {{"optimised", &et::build_env_distribution, 1},
                 {"optimised_2threads", &et::build_env_distribution, 2}};
    for (const auto& m : maps)
        for (const auto& impl : impls) {
            auto* b = benchmark::RegisterBenchmark(
                (std::string("BM_Distribution/") + impl.name + "/" + m.name).c_str(), run_build,
                impl.fn, m.image, impl.threads);
            b->Unit(benchmark::kMillisecond)->UseRealTime();
            if (m.big)
                b->MinTime(2.0);
        }
}

} // namespace

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv))
        return 1;
    register_all();
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
