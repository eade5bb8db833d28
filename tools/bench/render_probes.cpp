// Probes of one scene's render beside `envtrace bench` (which keeps the OpenCL/native table):
//  - environment sampling's share of a frame: the frame's light samples (one per shaded hit, as
//    counted by the schedule) drawn on their own, natively (sample values; + etk_env_sample, in
//    the sample_lights stage's batches where the render draws them so;
//    + the radiance lookup) and on the device (tools/bench/envmap_sample_bench.cl), each right
//    after a render of the frame; and in situ: the shade stage (with the sample_lights stage that
//    draws its light samples ahead) of the same render against the shade stage with --strategy
//    uniform (etk_sample_uniform_sphere instead of etk_env_sample);
//  - cold and warm OpenCL program builds of kernels/wavefront.cl: `envtrace render --spp 2
//    --stats` in a child process with empty (cold) then populated (warm) ENVTRACE_CACHE_DIR and
//    POCL_CACHE_DIR.
// Renders go through the one schedule (host/lib/render). Output: a table, and --json F with the
// keys tools/bench/render_benchmarks.py reads.
// Usage: render_probes SCENE [--max-depth D] [--runs R] [--spp N] [--strategy S] [--envtrace BIN]
//                      [--json F]
#include "bench_kernels.h"
#include "kernels/envmap.h"
#include "load/scene.h"
#include "opencl/opencl_runtime.h"
#include "prepare/device_scene.h"
#include "prepare/technique.h"
#include "render/renderer.h"
#include "util/json_file.h"
#include "util/parallel.h"
#include "util/timer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

double median(std::vector<double> v) {
    if (v.empty())
        return 0.0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

json stats_of(const std::vector<double>& v) {
    return {{"median", median(v)},
            {"min", v.empty() ? 0.0 : *std::min_element(v.begin(), v.end())},
            {"max", v.empty() ? 0.0 : *std::max_element(v.begin(), v.end())}};
}

struct Frame {
    double seconds_per_spp = 0, shade_share = 0, shade_seconds = 0, stage_seconds = 0;
    uint64_t shaded = 0;
};

Frame render(const et::DeviceScene& ds, int spp) {
    auto r = et::make_renderer(ds);
    et::Timer t;
    for (int i = 0; i < spp; ++i)
        r->render_sample(static_cast<uint32_t>(i));
    Frame f;
    f.seconds_per_spp = t.seconds() / spp;
    const et::RenderStats& s = r->stats();
    for (const auto& [name, sec] : s.stage_seconds) {
        f.stage_seconds += sec;
        if (name == "shade_hits" || name == "sample_lights") // the light samples, drawn ahead
            f.shade_seconds += sec;
    }
    f.shade_share = f.stage_seconds > 0 ? f.shade_seconds / f.stage_seconds : 0.0;
    f.shaded = s.shaded_hits / spp;
    return f;
}

// n light samples drawn as a frame draws them (pixel stream k mod pixels, pair 1): `batch` 1, one
// etk_env_sample each, as the shade stage draws them; ETK_LIGHT_BATCH, by etk_env_sample_batch,
// as the sample_lights stage does. Mode 0: the sample values only; 1: plus the samples; 2: plus
// the radiance lookup.
double native_env_sampling(const et::DeviceScene& ds, long long n, int threads, int mode, int batch,
                           double* sink) {
    const etk::EtkParams& p = ds.params;
    const long long pixels = static_cast<long long>(ds.width()) * ds.height();
    std::vector<double> sums(threads, 0.0);
    std::atomic<long long> next{0};
    auto work = [&](int t) {
        double acc = 0.0;
        etk::float2 u[ETK_LIGHT_BATCH];
        etk::EtkEnvSample s[ETK_LIGHT_BATCH];
        for (long long begin; (begin = next.fetch_add(4096)) < n;) {
            const long long end = std::min(n, begin + 4096);
            for (long long k0 = begin; k0 < end; k0 += batch) {
                const int m = static_cast<int>(std::min<long long>(batch, end - k0));
                for (int j = 0; j < batch; ++j) { // a partial batch repeats its last value
                    const long long k = k0 + std::min(j, m - 1);
                    u[j] =
                        etk::etk_sample_pair(p.sampler, p.seed, static_cast<etk::uint>(k % pixels),
                                             static_cast<etk::uint>(k / pixels), 1u);
                }
                if (mode == 0) {
                    for (int j = 0; j < m; ++j)
                        acc += u[j].x + u[j].y;
                    continue;
                }
                if (batch > 1) {
                    float xu[ETK_LIGHT_BATCH], xv[ETK_LIGHT_BATCH];
                    for (int j = 0; j < batch; ++j) {
                        xu[j] = u[j].x;
                        xv[j] = u[j].y;
                    }
                    etk::etk_env_sample_batch(ds.env_dist.data(), p.env, xu, xv, s);
                } else {
                    s[0] = etk::etk_env_sample(ds.env_dist.data(), p.env, u[0]);
                }
                for (int j = 0; j < m; ++j) {
                    acc += s[j].pdf;
                    if (mode == 2) {
                        const etk::float3 L =
                            etk::etk_env_radiance_uv(ds.env_texels.data(), p.env, s[j].uv);
                        acc += L.x + L.y + L.z;
                    }
                }
            }
        }
        sums[t] = acc;
    };
    et::Timer timer;
    et::run_on_threads(threads, work);
    const double s = timer.seconds();
    for (double v : sums)
        *sink += v;
    return s;
}

// The same on the OpenCL device: envmap_sample_reduce, one sample per work-item.
class ClEnvSampling {
  public:
    ClEnvSampling(const et::DeviceScene& ds, int device, long long n) : rt_(device) {
        program_ = etb::build_bench_kernel(rt_, "envmap_sample_bench.cl");
        k_ = cl::Kernel(program_, "envmap_sample_reduce");
        auto& ctx = rt_.context();
        dist_ =
            cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                       ds.env_dist.size() * sizeof(float), const_cast<float*>(ds.env_dist.data()));
        tex_ = cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                          ds.env_texels.size() * sizeof(float),
                          const_cast<float*>(ds.env_texels.data()));
        global_ = (static_cast<size_t>(n) + 63) / 64 * 64;
        out_ = cl::Buffer(ctx, CL_MEM_WRITE_ONLY, global_ * sizeof(cl_float4));
        etk::EtkEnvMap env = ds.params.env;
        k_.setArg(0, dist_);
        k_.setArg(1, tex_);
        k_.setArg(2, sizeof(env), &env);
        k_.setArg(3, static_cast<cl_int>(ds.params.sampler));
        k_.setArg(4, static_cast<cl_uint>(ds.params.seed));
        k_.setArg(5, cl_uint(0));
        k_.setArg(6, cl_uint(0));
        k_.setArg(7, static_cast<cl_int>(n));
        k_.setArg(8, cl_int(1));
        k_.setArg(9, out_);
        time(); // PoCL compiles the work-group function at the first launch
    }
    double time() {
        et::Timer t;
        rt_.queue().enqueueNDRangeKernel(k_, cl::NullRange, cl::NDRange(global_), cl::NDRange(64));
        rt_.queue().finish();
        return t.seconds();
    }

  private:
    et::ClRuntime rt_;
    cl::Program program_;
    cl::Kernel k_;
    cl::Buffer dist_, tex_, out_;
    size_t global_ = 0;
};

std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// `envtrace render` in a child process with the caches in `dir`; its --stats JSON.
json build_probe(const std::string& exe, const std::string& scene, int depth, const fs::path& dir) {
    fs::create_directories(dir / "et");
    fs::create_directories(dir / "pocl");
    const fs::path stats = dir / "stats.json", out = dir / "out.exr";
    const std::string cmd = "ENVTRACE_CACHE_DIR=" + quote((dir / "et").string()) +
                            " POCL_CACHE_DIR=" + quote((dir / "pocl").string()) + " " + quote(exe) +
                            " render " + quote(scene) + " --spp 2 --max-depth " +
                            std::to_string(depth) + " -o " + quote(out.string()) + " --stats " +
                            quote(stats.string()) + " > /dev/null";
    if (std::system(cmd.c_str()) != 0)
        throw std::runtime_error("failed: " + cmd);
    std::ifstream f(stats);
    const json j = json::parse(f);
    return {{"program_build_seconds", j["program_build_seconds"]},
            {"from_cache", j["program_from_cache"]},
            {"render_seconds_2spp", j["render_seconds"]}};
}

} // namespace

int main(int argc, char** argv) try {
    std::string scene_path, json_file, strategy, exe = "build/envtrace";
    int depth = 1, runs = 5, spp = 4;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc)
                throw std::runtime_error(a + " needs a value");
            return argv[++i];
        };
        if (a == "--max-depth")
            depth = std::stoi(next());
        else if (a == "--runs")
            runs = std::stoi(next());
        else if (a == "--spp")
            spp = std::stoi(next());
        else if (a == "--json")
            json_file = next();
        else if (a == "--envtrace")
            exe = next();
        else if (a == "--strategy")
            strategy = next();
        else
            scene_path = a;
    }
    if (scene_path.empty())
        throw std::runtime_error("usage: render_probes SCENE [--max-depth D] [--runs R] [--spp N] "
                                 "[--strategy S] [--envtrace BIN] [--json F]");
    et::Scene scene = et::load_scene(scene_path);
    et::RenderSettings st = scene.settings;
    st.max_depth = depth;
    if (!strategy.empty()) // the scene's own otherwise
        st.strategy = et::parse_strategy(strategy, "--strategy");
    et::DeviceScene ds = et::prepare_device_scene(std::move(scene), st);
    const int threads = et::thread_count(0);

    ds.settings.backend = et::Backend::cpu;
    const Frame first = render(ds, 1);
    const long long n = static_cast<long long>(first.shaded); // one light sample per shaded hit
    ClEnvSampling cl_env(ds, st.device, n);
    double sink = 0;
    std::vector<double> share[5], insitu[2], shade[2];
    for (int r = 0; r < runs; ++r) {
        for (et::Backend b : {et::Backend::cpu, et::Backend::opencl}) {
            const int k = b == et::Backend::cpu ? 0 : 1;
            ds.settings.backend = b;
            const Frame env = render(ds, spp);
            // The in-situ comparison: the same scene with uniform light directions.
            const etk::EtkParams kept = ds.params;
            et::set_technique(ds.params, et::Strategy::uniform);
            // (the device scene's rule for the stage: the uniform direction has none)
            ds.params.light_batch = et::technique_batches_light_samples(ds.params);
            const Frame uni = render(ds, spp);
            ds.params = kept;
            shade[k].push_back(env.shade_share);
            insitu[k].push_back((env.shade_seconds - uni.shade_seconds) / env.stage_seconds);
            if (b == et::Backend::cpu) {
                // As the frame draws them (batches where the strategy has the sample_lights
                // stage), and one at a time beside it.
                const int batch = ds.params.light_batch ? ETK_LIGHT_BATCH : 1;
                double t[3];
                for (int mode = 0; mode < 3; ++mode)
                    t[mode] = native_env_sampling(ds, n, threads, mode, batch, &sink);
                share[0].push_back((t[1] - t[0]) / env.seconds_per_spp);
                share[1].push_back(t[1] / env.seconds_per_spp);
                share[2].push_back(t[2] / env.seconds_per_spp);
                const double single = native_env_sampling(ds, n, threads, 1, 1, &sink);
                share[4].push_back((single - t[0]) / env.seconds_per_spp);
            } else {
                share[3].push_back(cl_env.time() / env.seconds_per_spp);
            }
        }
    }
    std::printf("%s, depth %d: %lld light samples per frame; medians of %d\n", scene_path.c_str(),
                depth, n, runs);
    std::printf("  isolated native (%d threads): map samples %.2f%% of the frame (%s; %.2f%% with "
                "the sample values, %.2f%% with the lookup; one etk_env_sample at a time "
                "%.2f%%); OpenCL %.2f%%\n",
                threads, 100 * median(share[0]),
                ds.params.light_batch ? "in the sample_lights stage's batches" : "one at a time",
                100 * median(share[1]), 100 * median(share[2]), 100 * median(share[4]),
                100 * median(share[3]));
    std::printf("  in situ (shade stage shorter with uniform directions): native %.1f%%, OpenCL "
                "%.1f%%; whole shade stage native %.1f%%, OpenCL %.1f%%\n",
                100 * median(insitu[0]), 100 * median(insitu[1]), 100 * median(shade[0]),
                100 * median(shade[1]));

    const fs::path dir = fs::temp_directory_path() / ("render-probes-" + std::to_string(getpid()));
    fs::remove_all(dir);
    json cold, warm;
    try {
        cold = build_probe(exe, scene_path, depth, dir);
        warm = build_probe(exe, scene_path, depth, dir);
    } catch (...) {
        fs::remove_all(dir);
        throw;
    }
    fs::remove_all(dir);
    std::printf("  wavefront.cl program build: cold %.3f s, warm %.3f s (%s)\n",
                cold["program_build_seconds"].get<double>(),
                warm["program_build_seconds"].get<double>(),
                warm["from_cache"].get<bool>() ? "cached binary" : "compiled");
    if (!json_file.empty()) {
        json j;
        j["env_sampling"] = {{"samples", n},
                             {"samples_exact", depth == 1},
                             {"native_threads", threads},
                             {"share_native_sample_only", stats_of(share[0])},
                             {"share_native_one_at_a_time", stats_of(share[4])},
                             {"share_native_with_values", stats_of(share[1])},
                             {"share_native_with_lookup", stats_of(share[2])},
                             {"share_opencl", stats_of(share[3])},
                             {"insitu_uniform_saving_native", stats_of(insitu[0])},
                             {"insitu_uniform_saving_opencl", stats_of(insitu[1])},
                             {"shade_stage_share_native", median(shade[0])},
                             {"shade_stage_share_opencl", median(shade[1])},
                             {"checksum", sink}};
        j["program_build"] = {{"cold_child", cold}, {"warm_child", warm}};
        et::write_json_file(json_file, j, 2);
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "render_probes: error: %s\n", e.what());
    return 1;
}
