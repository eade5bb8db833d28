// Cost of one environment-map sample, in pieces, on one core: the two CDF searches
// with the plain binary search (etk_find_interval) and with the guide tables
// (etk_find_interval_guided), the whole 2D inversion both ways, and etk_env_sample (2D sample +
// direction + solid-angle pdf), one at a time and in the sample_lights stage's batches. The sample
// values are those the shade stage draws for a 512x512 frame's first bounce (pixel streams in turn,
// sampler pair 1, scrambled Sobol'), computed once beforehand so that only the sampling is timed.
// Plain and guided run in one process, on the same values and the same table, interleaved with
// --benchmark_enable_random_interleaving. Also: the distribution build (with its guides) and the
// guides' share of the table, per map size (procedural sky from 256x128 to 16384x8192, and
// royal_esplanade_1k), for "How cost grows".
#include "bench_maps.h"
#include "load/env_distribution.h"
#include "kernels/envmap.h"
#include "kernels/sampler.h"
#include "util/timer.h"

#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

namespace {

constexpr int kSamples = 1 << 18;

struct Fixture {
    et::EnvDistribution dist;
    etk::EtkEnvMap env{};
    std::vector<etk::float2> u;
};

const Fixture& fixture(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Fixture>> cache;
    auto& f = cache[name];
    if (!f) {
        f = std::make_unique<Fixture>();
        const et::RgbImage& img =
            name == "royal_esplanade_1k"
                ? et::bench::real_map("royal_esplanade_1k.hdr")
                : et::bench::sky_map(std::stoi(name.substr(4)), std::stoi(name.substr(4)) / 2);
        et::DistributionOptions o;
        o.threads = 1;
        f->dist = et::build_env_distribution(img, o);
        f->env.tex_w = img.width;
        f->env.tex_h = img.height;
        f->env.dist_w = f->dist.width;
        f->env.dist_h = f->dist.height;
        f->env.scale = 1.0f;
        f->env.rot_cos = 1.0f;
        f->env.has_light = f->dist.has_light() ? 1 : 0;
        const unsigned pixels = 512u * 512u;
        f->u.resize(kSamples);
        for (unsigned k = 0; k < kSamples; ++k)
            f->u[k] = etk::etk_sample_pair(ETK_SAMPLER_SOBOL, 1u, k % pixels, k / pixels, 1u);
    }
    return *f;
}

// The 2D inversion as it was before the guides: etk_sample_1d (plain search) on both CDFs.
etk::float2 sample_2d_plain(const float* dist, int w, int h, etk::float2 xi, float* density) {
    float pv, pu;
    int row, col;
    const float v = etk::etk_sample_1d(dist + etk::etk_dist2d_marginal_cdf(h), h, xi.y, &pv, &row);
    const float u =
        etk::etk_sample_1d(etk::etk_dist2d_row_cdf(dist, w, h, row), w, xi.x, &pu, &col);
    *density = pv * pu;
    return etk::make_float2(u, v);
}

void BM_Search(benchmark::State& st, std::string map, bool guided) {
    const Fixture& f = fixture(map);
    const float* t = f.dist.table.data();
    const int w = f.dist.width, h = f.dist.height;
    const float* mcdf = t + etk::etk_dist2d_marginal_cdf(h);
    const float* mguide = t + etk::etk_dist2d_marginal_guide(w, h);
    for (auto _ : st) {
        long acc = 0;
        for (const etk::float2& xi : f.u) {
            const int r = guided ? etk::etk_find_interval_guided(mcdf, h, mguide, xi.y)
                                 : etk::etk_find_interval(mcdf, h, xi.y);
            const float* ccdf = etk::etk_dist2d_row_cdf(t, w, h, r);
            acc += r + (guided ? etk::etk_find_interval_guided(
                                     ccdf, w, etk::etk_dist2d_row_guide(t, w, h, r), xi.x)
                               : etk::etk_find_interval(ccdf, w, xi.x));
        }
        benchmark::DoNotOptimize(acc);
    }
    st.SetItemsProcessed(st.iterations() * kSamples);
}

void BM_Sample2D(benchmark::State& st, std::string map, bool guided) {
    const Fixture& f = fixture(map);
    const float* t = f.dist.table.data();
    const int w = f.dist.width, h = f.dist.height;
    for (auto _ : st) {
        float acc = 0;
        for (const etk::float2& xi : f.u) {
            float d;
            int row, col;
            const etk::float2 uv = guided ? etk::etk_sample_2d(t, w, h, xi, &d, &row, &col)
                                          : sample_2d_plain(t, w, h, xi, &d);
            acc += uv.x + uv.y + d;
        }
        benchmark::DoNotOptimize(acc);
    }
    st.SetItemsProcessed(st.iterations() * kSamples);
}

void BM_EnvSample(benchmark::State& st, std::string map, bool guided) {
    const Fixture& f = fixture(map);
    const float* t = f.dist.table.data();
    for (auto _ : st) {
        float acc = 0;
        for (const etk::float2& xi : f.u) {
            if (guided) {
                const etk::EtkEnvSample s = etk::etk_env_sample(t, f.env, xi);
                acc += s.dir.x + s.pdf;
            } else { // etk_env_sample with the plain 2D inversion
                float d;
                const etk::float2 uv = sample_2d_plain(t, f.env.dist_w, f.env.dist_h, xi, &d);
                const etk::float3 dir = etk::etk_env_to_world(f.env, etk::etk_latlong_to_dir(uv));
                acc += dir.x + etk::etk_latlong_pdf_to_solid_angle(d, uv.y);
            }
        }
        benchmark::DoNotOptimize(acc);
    }
    st.SetItemsProcessed(st.iterations() * kSamples);
}

// etk_env_sample_batch, as the sample_lights stage draws the samples: ETK_LIGHT_BATCH at a time.
void BM_EnvSampleBatch(benchmark::State& st, std::string map) {
    const Fixture& f = fixture(map);
    const float* t = f.dist.table.data();
    etk::EtkEnvSample out[ETK_LIGHT_BATCH];
    std::vector<float> xu(f.u.size()), xv(f.u.size()); // the stage's layout: arrays of scalars
    for (size_t k = 0; k < f.u.size(); ++k) {
        xu[k] = f.u[k].x;
        xv[k] = f.u[k].y;
    }
    for (auto _ : st) {
        float acc = 0;
        for (size_t k = 0; k + ETK_LIGHT_BATCH <= f.u.size(); k += ETK_LIGHT_BATCH) {
            etk::etk_env_sample_batch(t, f.env, &xu[k], &xv[k], out);
            for (const etk::EtkEnvSample& s : out)
                acc += s.dir.x + s.pdf;
        }
        benchmark::DoNotOptimize(acc);
    }
    st.SetItemsProcessed(st.iterations() * kSamples);
}

// The distribution build (one thread) with its guides; counters: the table and the guides' bytes.
void BM_Build(benchmark::State& st, std::string map) {
    const et::RgbImage& img =
        map == "royal_esplanade_1k"
            ? et::bench::real_map("royal_esplanade_1k.hdr")
            : et::bench::sky_map(std::stoi(map.substr(4)), std::stoi(map.substr(4)) / 2);
    et::DistributionOptions o;
    o.threads = 1;
    size_t bytes = 0;
    for (auto _ : st) {
        const et::EnvDistribution d = et::build_env_distribution(img, o);
        bytes = d.table.size() * sizeof(float);
        benchmark::DoNotOptimize(d.table.data());
    }
    const int w = img.width, h = img.height;
    const size_t guide = (static_cast<size_t>(etk::etk_guide_cells(h)) + 1 +
                          static_cast<size_t>(h) * (etk::etk_guide_cells(w) + 1)) *
                         sizeof(float);
    st.counters["table_MB"] = static_cast<double>(bytes) / 1e6;
    st.counters["guides_MB"] = static_cast<double>(guide) / 1e6;
}

const std::vector<std::string> kSampleMaps = {"royal_esplanade_1k", "sky_256",  "sky_1024",
                                              "sky_4096",           "sky_8192", "sky_16384"};

int register_all() {
    for (const std::string& m : kSampleMaps) {
        for (bool g : {false, true}) {
            const std::string how = g ? "guided" : "plain";
            benchmark::RegisterBenchmark(("search/" + m + "/" + how).c_str(), BM_Search, m, g);
            benchmark::RegisterBenchmark(("sample2d/" + m + "/" + how).c_str(), BM_Sample2D, m, g);
            benchmark::RegisterBenchmark(("env_sample/" + m + "/" + how).c_str(), BM_EnvSample, m,
                                         g);
        }
        benchmark::RegisterBenchmark(("env_sample/" + m + "/batched").c_str(), BM_EnvSampleBatch,
                                     m);
        benchmark::RegisterBenchmark(("build/" + m).c_str(), BM_Build, m)
            ->Unit(benchmark::kMillisecond);
    }
    return 0;
}
const int registered = register_all();

} // namespace

BENCHMARK_MAIN();
