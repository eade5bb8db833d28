// `envtrace bench`: the OpenCL back end against the native one on one scene, side by side.
//
// The scene is loaded once. After a warm-up render of each back end (reported separately: PoCL
// compiles each kernel's work-group function at its first launch), the two back ends render in
// alternation (opencl, cpu, opencl, cpu, ...), each run a fresh renderer doing N spp. The table
// gives medians and spreads, the OpenCL/native ratio of the medians and the median of the ratios
// of each alternating pair (robust to a machine whose load drifts). Program build times: cold in a
// child process (`envtrace bench --build-probe` with empty ENVTRACE_CACHE_DIR and POCL_CACHE_DIR,
// which PoCL reads at platform init), warm from the renderers of this process (normal cache).
// Finally, the cost of drawing the environment-map samples of one frame, timed on its own (see
// tools/bench/README.md, "Environment-sampling share").
#include "commands.h"
#include "util/json_file.h"
#include "util/parallel.h"
#include "util/error.h"
#include "opencl/opencl_runtime.h"
#include "render/renderer.h"
#include "load/scene.h"
#include "prepare/device_scene.h"
#include "util/timer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/utsname.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace et::cli {
namespace {

struct BenchArgs {
    std::string scene, json_file;
    int spp = 0, runs = 5, max_depth = 0, threads = 0, paths = -1;
    double target_seconds = 2.0;
    bool build_probe = false, no_cold = false, no_insitu = false;
};

struct Prepared {
    Scene scene;
    SceneArrays arrays;
    etk::EtkParams params{};
};

void prepare(const BenchArgs& a, Prepared& p) {
    p.scene = load_scene(a.scene);
    if (a.max_depth > 0)
        p.scene.settings.max_depth = a.max_depth;
    if (a.paths >= 0)
        p.scene.settings.paths = a.paths;
    p.arrays = build_scene_arrays(p.scene);
    p.params = make_params(p.scene, p.arrays);
}

RendererOptions options(const BenchArgs& a, const Globals& g, const Prepared& p,
                        const std::string& backend) {
    RendererOptions ro;
    ro.backend = backend;
    ro.device = g.device;
    ro.paths = p.scene.settings.paths;
    ro.threads = a.threads;
    return ro;
}

struct Run {
    std::string backend;
    int spp = 0;
    double seconds = 0, first_sample_seconds = 0, construct_seconds = 0;
    double build_seconds = 0;
    bool from_cache = false;
    RenderStats stats;
    double mrays() const { return stats.rays() / seconds * 1e-6; }
};

Run render_run(const BenchArgs& a, const Globals& g, const Prepared& p, const std::string& backend,
               int spp, const etk::EtkParams* params = nullptr) {
    Run r;
    r.backend = backend;
    r.spp = spp;
    ProgramBuildInfo build;
    Timer construct;
    auto renderer =
        make_renderer(options(a, g, p, backend), p.arrays, params ? *params : p.params, &build);
    r.construct_seconds = construct.seconds();
    r.build_seconds = build.seconds;
    r.from_cache = build.from_cache;
    Timer t;
    for (int i = 0; i < spp; ++i) {
        renderer->render_sample(static_cast<uint32_t>(i));
        if (i == 0)
            r.first_sample_seconds = t.seconds();
    }
    r.seconds = t.seconds();
    r.stats = renderer->stats();
    return r;
}

struct Summary {
    double median = 0, min = 0, max = 0, q1 = 0, q3 = 0;
};

double quantile(std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    const double x = q * (v.size() - 1);
    const size_t i = static_cast<size_t>(x);
    return i + 1 < v.size() ? v[i] + (x - i) * (v[i + 1] - v[i]) : v[i];
}

Summary summarize(const std::vector<double>& v) {
    Summary s;
    if (v.empty())
        return s;
    s.median = quantile(v, 0.5);
    s.q1 = quantile(v, 0.25);
    s.q3 = quantile(v, 0.75);
    s.min = *std::min_element(v.begin(), v.end());
    s.max = *std::max_element(v.begin(), v.end());
    return s;
}

json to_json(const Summary& s) {
    return {{"median", s.median}, {"min", s.min}, {"max", s.max}, {"q1", s.q1}, {"q3", s.q3}};
}

json to_json(const Run& r, int pixels) {
    json j = {{"backend", r.backend},
              {"spp", r.spp},
              {"seconds", r.seconds},
              {"seconds_per_spp", r.seconds / r.spp},
              {"first_sample_seconds", r.first_sample_seconds},
              {"renderer_construct_seconds", r.construct_seconds},
              {"mrays_per_second", r.mrays()},
              {"samples_per_second", double(r.spp) * pixels / r.seconds},
              {"rays",
               {{"camera", r.stats.camera_rays},
                {"continuation", r.stats.continuation_rays},
                {"shadow", r.stats.shadow_rays}}}};
    if (r.backend == "opencl")
        j["program_build"] = {{"seconds", r.build_seconds}, {"from_cache", r.from_cache}};
    for (const auto& [name, t] : r.stats.stage_seconds)
        j["stage_seconds"][name] = t;
    return j;
}

std::string load_average() {
    std::ifstream f("/proc/loadavg");
    double a = 0, b = 0, c = 0;
    f >> a >> b >> c;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f %.2f %.2f", a, b, c);
    return buf;
}

std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// --build-probe: one OpenCL renderer, its program build and its first two samples, as one line of
// JSON on stdout. Run by the parent with the caches it wants measured.
void build_probe(const BenchArgs& a, const Globals& g) {
    Prepared p;
    prepare(a, p);
    ProgramBuildInfo build;
    auto renderer = make_renderer(options(a, g, p, "opencl"), p.arrays, p.params, &build);
    Timer t1;
    renderer->render_sample(0);
    const double first = t1.seconds();
    Timer t2;
    renderer->render_sample(1);
    const double second = t2.seconds();
    json j = {{"program_build_seconds", build.seconds},
              {"from_cache", build.from_cache},
              {"first_sample_seconds", first},
              {"second_sample_seconds", second}};
    std::printf("%s\n", j.dump().c_str());
}

// Runs the probe in a child process with ENVTRACE_CACHE_DIR and POCL_CACHE_DIR set to `dir`/et
// and `dir`/pocl.
json run_probe(const BenchArgs& a, const Globals& g, const fs::path& dir) {
    fs::create_directories(dir / "et");
    fs::create_directories(dir / "pocl");
    const std::string exe = fs::read_symlink("/proc/self/exe").string();
    std::string cmd = "ENVTRACE_CACHE_DIR=" + shell_quote((dir / "et").string()) +
                      " POCL_CACHE_DIR=" + shell_quote((dir / "pocl").string()) + " " +
                      shell_quote(exe) + " --device " + std::to_string(g.device) + " bench " +
                      shell_quote(a.scene) + " --build-probe";
    if (a.max_depth > 0)
        cmd += " --max-depth " + std::to_string(a.max_depth);
    if (a.paths >= 0)
        cmd += " --paths " + std::to_string(a.paths);
    FILE* f = popen(cmd.c_str(), "r");
    if (!f)
        throw Error("cannot run the build probe: " + cmd);
    std::string out;
    char buf[4096];
    while (size_t n = std::fread(buf, 1, sizeof buf, f))
        out.append(buf, n);
    const int status = pclose(f);
    const size_t brace = out.rfind('{');
    if (status != 0 || brace == std::string::npos)
        throw Error("the build probe failed (exit status " + std::to_string(status) + "): " + cmd +
                    "\n" + out);
    return json::parse(out.substr(brace));
}

// The pixels whose camera ray hits the scene: the first bounce's shade calls, each of which draws
// one light sample. Runs the renderer's first two stages (etk_generate, etk_intersect) natively.
std::vector<etk::uint> camera_hit_pixels(const Prepared& p) {
    const int pixels = p.params.width * p.params.height, tile = 4096;
    std::vector<etk::float4> ray_o(tile), ray_d(tile), beta(tile), radiance(tile), hit(tile),
        shadow_o(tile), shadow_d(tile), shadow_L(tile);
    std::vector<int> pixel(tile), queue_a(tile), queue_b(tile), escaped(tile), shade(tile),
        shadow(tile);
    uint32_t counters[ETK_Q_COUNT];
    etk::EtkPaths P{ray_o.data(),    ray_d.data(),    beta.data(),     radiance.data(), hit.data(),
                    shadow_o.data(), shadow_d.data(), shadow_L.data(), pixel.data()};
    etk::EtkQueues Q{queue_a.data(), queue_b.data(), escaped.data(),
                     shade.data(),   shadow.data(),  counters};
    const SceneArrays& a = p.arrays;
    const etk::EtkScene S = scene_view(a);
    etk::EtkParams prm = p.params;
    std::vector<etk::uint> hits;
    for (int first = 0; first < pixels; first += tile) {
        const int n = std::min(tile, pixels - first);
        prm.first_pixel = first;
        std::fill(counters, counters + ETK_Q_COUNT, 0u);
        for (int i = 0; i < n; ++i) // fills queue_b (Q.ray_out)
            etk::etk_generate(P, Q, prm, i);
        etk::EtkQueues Qi = Q;
        Qi.ray_in = queue_b.data();
        Qi.ray_out = queue_a.data();
        std::fill(counters, counters + ETK_Q_COUNT, 0u);
        for (int q = 0; q < n; ++q)
            etk::etk_intersect(P, Qi, S, prm, q);
        for (uint32_t k = 0; k < counters[ETK_Q_SHADE]; ++k)
            hits.push_back(static_cast<etk::uint>(pixel[shade[k]]));
    }
    return hits;
}

// Environment-map sampling of one frame on its own: `n` samples drawn as the shade stage draws
// them: sample k at pixel hits[k mod H] with sampler pair 1 + 3 (k / H) (bounce k / H), over
// `threads` threads. mode 0: the sample values only; 1: plus etk_env_sample; 2: plus the
// radiance lookup in the sampled direction (what the shade stage does with the sample). Returns
// seconds.
double native_env_sampling(const Prepared& p, const std::vector<etk::uint>& hits, long long n,
                           int threads, int mode, double* sink) {
    const etk::EtkParams& prm = p.params;
    const float* dist = p.arrays.env->dist.table.data();
    const float* texels = p.arrays.env->image.rgb.data();
    const long long h = std::max<long long>(1, static_cast<long long>(hits.size()));
    std::vector<double> sums(threads, 0.0);
    std::atomic<long long> next{0};
    constexpr long long kChunk = 4096;
    auto work = [&](int t) {
        double acc = 0.0;
        for (;;) {
            const long long begin = next.fetch_add(kChunk);
            if (begin >= n)
                break;
            const long long end = std::min(n, begin + kChunk);
            for (long long k = begin; k < end; ++k) {
                const etk::uint pixel = hits.empty() ? 0u : hits[k % h];
                const etk::uint pair = 1u + 3u * static_cast<etk::uint>(k / h);
                const etk::float2 u =
                    etk::etk_sample_pair(prm.sampler, prm.seed, pixel, prm.sample_index, pair);
                if (mode == 0) {
                    acc += u.x + u.y;
                    continue;
                }
                const etk::EtkEnvSample s = etk::etk_env_sample(dist, prm.env, u);
                acc += s.pdf;
                if (mode == 2) {
                    const etk::float3 L = etk::etk_env_radiance_uv(texels, prm.env, s.uv);
                    acc += L.x + L.y + L.z;
                }
            }
        }
        sums[t] = acc;
    };
    Timer timer;
    run_on_threads(threads, work);
    const double s = timer.seconds();
    for (double v : sums)
        *sink += v;
    return s;
}

// The same on the OpenCL device: envmap_sample_reduce (kernels/envmap_sample_bench.cl) with one
// sample per work-item, work-groups of 64 like the renderer's: sample values, etk_env_sample and
// the radiance lookup (mode 2 above). time() is the wall time from enqueue to finish; the
// constructor launches once (PoCL compiles the work-group function at the first launch).
class ClEnvSampling {
  public:
    ClEnvSampling(const Prepared& p, const Globals& g, long long n) : rt_(g.device) {
        program_ = rt_.build("envmap_sample_bench.cl");
        k_ = cl::Kernel(program_, "envmap_sample_reduce");
        auto& ctx = rt_.context();
        std::vector<float> dist = p.arrays.env->dist.table, texels = p.arrays.env->image.rgb;
        dist_ = cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                           dist.size() * sizeof(float), dist.data());
        tex_ = cl::Buffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                          texels.size() * sizeof(float), texels.data());
        global_ = (static_cast<size_t>(n) + kLocal - 1) / kLocal * kLocal;
        out_ = cl::Buffer(ctx, CL_MEM_WRITE_ONLY, global_ * sizeof(cl_float4));
        etk::EtkEnvMap env = p.params.env;
        k_.setArg(0, dist_);
        k_.setArg(1, tex_);
        k_.setArg(2, sizeof(env), &env);
        k_.setArg(3, static_cast<cl_int>(p.params.sampler));
        k_.setArg(4, static_cast<cl_uint>(p.params.seed));
        k_.setArg(5, cl_uint(0));
        k_.setArg(6, cl_uint(0));
        k_.setArg(7, static_cast<cl_int>(n));
        k_.setArg(8, cl_int(1));
        k_.setArg(9, out_);
        first_launch_seconds_ = time();
    }
    double time() {
        Timer t;
        rt_.queue().enqueueNDRangeKernel(k_, cl::NullRange, cl::NDRange(global_),
                                         cl::NDRange(kLocal));
        rt_.queue().finish();
        return t.seconds();
    }
    double first_launch_seconds() const { return first_launch_seconds_; }

  private:
    static constexpr int kLocal = 64;
    ClRuntime rt_;
    cl::Program program_;
    cl::Kernel k_;
    cl::Buffer dist_, tex_, out_;
    size_t global_ = 0;
    double first_launch_seconds_ = 0;
};

double stage_seconds(const Run& r, const char* stage) {
    for (const auto& [name, t] : r.stats.stage_seconds)
        if (name == stage)
            return t;
    return 0.0;
}

double total_stage_seconds(const Run& r) {
    double total = 0;
    for (const auto& st : r.stats.stage_seconds)
        total += st.second;
    return total;
}

double stage_share(const Run& r, const char* stage) {
    double total = 0, s = 0;
    for (const auto& [name, t] : r.stats.stage_seconds) {
        total += t;
        if (name == stage)
            s = t;
    }
    return total > 0 ? s / total : 0.0;
}

void print_row(const char* label, const char* unit, const Summary& s, int digits) {
    std::printf("  %-14s %10.*f  [%.*f - %.*f]  IQR %.*f - %.*f %s\n", label, digits, s.median,
                digits, s.min, digits, s.max, digits, s.q1, digits, s.q3, unit);
}

void run(const BenchArgs& a, const Globals& g) {
    if (a.build_probe)
        return build_probe(a, g);
    const std::string load_before = load_average();
    Prepared p;
    prepare(a, p);
    const Scene& sc = p.scene;
    const int pixels = sc.width * sc.height;
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    const int threads = a.threads > 0 ? a.threads : static_cast<int>(cores);
    std::printf("scene %s: %zu triangles, BVH %d nodes (depth %d, SAH cost %.1f) in %.1f ms; "
                "%dx%d, depth %d, strategy %s, sampler %s\n",
                a.scene.c_str(), sc.triangles.size(), p.arrays.bvh.node_count(), p.arrays.bvh.depth,
                p.arrays.bvh.sah_cost, p.arrays.bvh.build_seconds * 1e3, sc.width, sc.height,
                sc.settings.max_depth, sc.settings.strategy.c_str(), sc.settings.sampler.c_str());
    std::printf("machine: %u hardware threads, native back end on %d threads; load average "
                "%s\n",
                cores, threads, load_before.c_str());
    std::fflush(stdout);

    // Warm-up, not counted: the OpenCL renderer's first launch compiles work-group functions.
    Run warm_cl = render_run(a, g, p, "opencl", 2);
    Run warm_cpu = render_run(a, g, p, "cpu", 1);
    const double cl_second = warm_cl.seconds - warm_cl.first_sample_seconds;
    int spp = a.spp;
    if (spp <= 0) {
        const double per_spp = std::max(cl_second, warm_cpu.seconds);
        spp = std::clamp(static_cast<int>(std::lround(a.target_seconds / per_spp)), 1, 4096);
    }
    std::printf("warm-up: opencl program build %.3f s (%s), first sample %.3f s, second %.3f s; "
                "cpu first sample %.3f s -> %d spp per run\n",
                warm_cl.build_seconds, warm_cl.from_cache ? "cached binary" : "compiled",
                warm_cl.first_sample_seconds, cl_second, warm_cpu.seconds, spp);
    std::fflush(stdout);

    // Light samples of one frame: one per shade call. At depth 1 exactly one per camera ray that
    // hits the scene; beyond, also at most one per continuation ray (an upper bound: continuation
    // rays that escape or reach the last depth are not shaded). Timed on their own right after
    // each render (see tools/bench/README.md).
    const std::vector<etk::uint> hits = camera_hit_pixels(p);
    const RenderStats& ws = warm_cpu.stats;
    const long long n_env =
        static_cast<long long>(hits.size()) +
        (sc.settings.max_depth > 1 ? static_cast<long long>(ws.continuation_rays) : 0);
    ClEnvSampling cl_env(p, g, n_env);
    double sink = 0;
    for (int mode = 0; mode < 3; ++mode) // warm-up
        native_env_sampling(p, hits, n_env, threads, mode, &sink);

    // In situ: the same renders with the light sample drawn uniformly on the sphere
    // (--strategy uniform: etk_sample_uniform_sphere instead of etk_env_sample and no MIS weight;
    // the rest of the shade stage is the same). The shade stage's time difference estimates
    // what drawing the environment-map samples costs inside the frame.
    const bool insitu = !a.no_insitu && (p.params.strategy == ETK_STRATEGY_MIS ||
                                         p.params.strategy == ETK_STRATEGY_LIGHT);
    etk::EtkParams uniform = p.params;
    uniform.strategy = ETK_STRATEGY_UNIFORM;
    std::vector<Run> cl_runs, cpu_runs, cl_uniform, cpu_uniform;
    std::vector<double> env_t[4]; // native modes 0-2, opencl
    for (int r = 0; r < a.runs; ++r) {
        cl_runs.push_back(render_run(a, g, p, "opencl", spp));
        env_t[3].push_back(cl_env.time());
        cpu_runs.push_back(render_run(a, g, p, "cpu", spp));
        for (int mode = 0; mode < 3; ++mode)
            env_t[mode].push_back(native_env_sampling(p, hits, n_env, threads, mode, &sink));
        if (insitu) {
            cl_uniform.push_back(render_run(a, g, p, "opencl", spp, &uniform));
            cpu_uniform.push_back(render_run(a, g, p, "cpu", spp, &uniform));
        }
        std::printf("  pair %d: opencl %.3f Mrays/s, cpu %.3f Mrays/s, ratio %.3f\n", r + 1,
                    cl_runs.back().mrays(), cpu_runs.back().mrays(),
                    cl_runs.back().mrays() / cpu_runs.back().mrays());
        std::fflush(stdout);
    }

    auto metric = [&](const std::vector<Run>& runs, int which) {
        std::vector<double> v;
        for (const Run& r : runs)
            v.push_back(which == 0   ? r.mrays()
                        : which == 1 ? double(r.spp) * pixels / r.seconds
                                     : r.seconds / r.spp);
        return summarize(v);
    };
    Summary m[2][3];
    for (int w = 0; w < 3; ++w) {
        m[0][w] = metric(cl_runs, w);
        m[1][w] = metric(cpu_runs, w);
    }
    std::vector<double> pair_ratios, cl_builds;
    for (int r = 0; r < a.runs; ++r) {
        pair_ratios.push_back(cl_runs[r].mrays() / cpu_runs[r].mrays());
        cl_builds.push_back(cl_runs[r].build_seconds);
    }
    const Summary pr = summarize(pair_ratios), warm_build = summarize(cl_builds);
    const double ratio_of_medians = m[0][0].median / m[1][0].median;
    const RenderStats& rs = cpu_runs[0].stats;

    std::printf("\n%d runs of %d spp per back end, alternating; median [min - max] IQR q1 - q3\n",
                a.runs, spp);
    std::printf("rays per spp: %.0f camera, %.0f continuation, %.0f shadow (native run 1)\n",
                double(rs.camera_rays) / spp, double(rs.continuation_rays) / spp,
                double(rs.shadow_rays) / spp);
    const char* names[2] = {"opencl (PoCL)", "native (cpu)"};
    for (int b = 0; b < 2; ++b) {
        std::printf("%s\n", names[b]);
        print_row("Mrays/s", "", m[b][0], 3);
        print_row("samples/s", "", m[b][1], 0);
        print_row("s/spp", "", m[b][2], 4);
    }
    std::printf("ratio OpenCL/native (throughput): %.3f of medians; per pair: median %.3f "
                "[%.3f - %.3f]\n",
                ratio_of_medians, pr.median, pr.min, pr.max);

    // Program build times.
    json cold = nullptr, warm_probe = nullptr;
    if (!a.no_cold) {
        const fs::path dir =
            fs::temp_directory_path() / ("envtrace-bench-" + std::to_string(::getpid()) + "-cache");
        fs::remove_all(dir);
        try {
            cold = run_probe(a, g, dir);
            warm_probe = run_probe(a, g, dir);
        } catch (...) {
            fs::remove_all(dir);
            throw;
        }
        fs::remove_all(dir);
        std::printf("program build, cold (child process, empty ENVTRACE_CACHE_DIR and "
                    "POCL_CACHE_DIR): %.3f s (%s); first sample %.3f s, second %.3f s\n",
                    cold["program_build_seconds"].get<double>(),
                    cold["from_cache"].get<bool>() ? "cached binary" : "compiled",
                    cold["first_sample_seconds"].get<double>(),
                    cold["second_sample_seconds"].get<double>());
        std::printf("program build, warm (child process, the same caches again): %.3f s (%s); "
                    "first sample %.3f s, second %.3f s\n",
                    warm_probe["program_build_seconds"].get<double>(),
                    warm_probe["from_cache"].get<bool>() ? "cached binary" : "compiled",
                    warm_probe["first_sample_seconds"].get<double>(),
                    warm_probe["second_sample_seconds"].get<double>());
    }
    std::printf("program build, warm (this process, normal cache, %d renderers): median %.3f s "
                "[%.3f - %.3f]\n",
                a.runs, warm_build.median, warm_build.min, warm_build.max);

    // Shares of the frame, per pair (each sampling run against the render just before it).
    std::vector<double> sh[4];
    for (int r = 0; r < a.runs; ++r) {
        const double cpu_spp = cpu_runs[r].seconds / spp, cl_spp = cl_runs[r].seconds / spp;
        sh[0].push_back((env_t[1][r] - env_t[0][r]) / cpu_spp);
        sh[1].push_back(env_t[1][r] / cpu_spp);
        sh[2].push_back(env_t[2][r] / cpu_spp);
        sh[3].push_back(env_t[3][r] / cl_spp);
    }
    const Summary env_vals = summarize(env_t[0]), env_sample = summarize(env_t[1]),
                  env_lookup = summarize(env_t[2]), env_cl = summarize(env_t[3]);
    const Summary share_only = summarize(sh[0]), share_values = summarize(sh[1]),
                  share_lookup = summarize(sh[2]), share_cl = summarize(sh[3]);
    const double cpu_spp = m[1][2].median, cl_spp = m[0][2].median;
    std::vector<double> shade_cl, shade_cpu;
    for (int r = 0; r < a.runs; ++r) {
        shade_cl.push_back(stage_share(cl_runs[r], "shade_hits"));
        shade_cpu.push_back(stage_share(cpu_runs[r], "shade_hits"));
    }
    const double shade_cl_share = summarize(shade_cl).median,
                 shade_cpu_share = summarize(shade_cpu).median;
    std::printf("environment sampling, %lld samples (one frame's light samples%s), "
                "medians of %d, each right after a render:\n",
                n_env, sc.settings.max_depth > 1 ? ", an upper bound" : ", exact", a.runs);
    std::printf("  native, %d threads: sample values %.2f ms, + etk_env_sample %.2f ms, + "
                "radiance lookup %.2f ms; frame %.1f ms -> etk_env_sample %.2f%% of the frame "
                "(%.2f%% with the sample values, %.2f%% with the lookup)\n",
                threads, env_vals.median * 1e3, env_sample.median * 1e3, env_lookup.median * 1e3,
                cpu_spp * 1e3, 100 * share_only.median, 100 * share_values.median,
                100 * share_lookup.median);
    std::printf("  opencl, envmap_sample_reduce (values + sample + lookup): %.2f ms; frame %.1f "
                "ms -> %.2f%% of the frame\n",
                env_cl.median * 1e3, cl_spp * 1e3, 100 * share_cl.median);
    // Shade-stage time saved by the uniform light sample, as a share of the frame's stage time.
    std::vector<double> saved_cl, saved_cpu;
    for (size_t r = 0; r < cl_uniform.size(); ++r) {
        auto saved = [](const Run& env, const Run& uni) {
            return stage_share(env, "shade_hits") -
                   stage_seconds(uni, "shade_hits") / total_stage_seconds(env);
        };
        saved_cl.push_back(saved(cl_runs[r], cl_uniform[r]));
        saved_cpu.push_back(saved(cpu_runs[r], cpu_uniform[r]));
    }
    const Summary insitu_cl = summarize(saved_cl), insitu_cpu = summarize(saved_cpu);
    if (insitu)
        std::printf("  in situ: the shade stage with a uniform-sphere light sample instead is "
                    "shorter by %.1f%% of the frame's stage time natively [%.1f - %.1f], %.1f%% "
                    "on OpenCL [%.1f - %.1f]\n",
                    100 * insitu_cpu.median, 100 * insitu_cpu.min, 100 * insitu_cpu.max,
                    100 * insitu_cl.median, 100 * insitu_cl.min, 100 * insitu_cl.max);
    std::printf("  in situ, upper bound: the shade stage (which draws the sample) is %.1f%% of "
                "opencl device time and %.1f%% of native thread time\n",
                100 * shade_cl_share, 100 * shade_cpu_share);
    const std::string load_after = load_average();
    std::printf("load average before %s, after %s\n", load_before.c_str(), load_after.c_str());

    if (!a.json_file.empty()) {
        json j;
        utsname u{};
        uname(&u);
        j["scene"] = a.scene;
        j["host"] = {{"hardware_threads", cores},
                     {"native_threads", threads},
                     {"kernel", std::string(u.sysname) + " " + u.release},
                     {"load_average_before", load_before},
                     {"load_average_after", load_after}};
        try {
            auto devices = list_devices();
            if (g.device < static_cast<int>(devices.size()))
                j["host"]["opencl_device"] =
                    devices[g.device].device_name + " (" + devices[g.device].driver_version + ")";
        } catch (const std::exception&) {
        }
        j["width"] = sc.width;
        j["height"] = sc.height;
        j["max_depth"] = sc.settings.max_depth;
        j["strategy"] = sc.settings.strategy;
        j["sampler"] = sc.settings.sampler;
        j["triangles"] = sc.triangles.size();
        j["bvh"] = {{"nodes", p.arrays.bvh.node_count()},
                    {"depth", p.arrays.bvh.depth},
                    {"sah_cost", p.arrays.bvh.sah_cost},
                    {"build_seconds", p.arrays.bvh.build_seconds}};
        j["spp_per_run"] = spp;
        j["runs"] = a.runs;
        j["warmup"] = {{"opencl", to_json(warm_cl, pixels)}, {"cpu", to_json(warm_cpu, pixels)}};
        const char* keys[2] = {"opencl", "cpu"};
        for (int b = 0; b < 2; ++b) {
            j["summary"][keys[b]] = {{"mrays_per_second", to_json(m[b][0])},
                                     {"samples_per_second", to_json(m[b][1])},
                                     {"seconds_per_spp", to_json(m[b][2])}};
            for (const Run& r : b == 0 ? cl_runs : cpu_runs)
                j["runs_detail"][keys[b]].push_back(to_json(r, pixels));
            for (const Run& r : b == 0 ? cl_uniform : cpu_uniform)
                j["runs_detail"][std::string(keys[b]) + "_uniform_light"].push_back(
                    to_json(r, pixels));
        }
        j["ratio_opencl_over_native"] = {{"of_medians", ratio_of_medians},
                                         {"per_pair", pair_ratios},
                                         {"per_pair_summary", to_json(pr)}};
        j["program_build"] = {{"cold_child", cold},
                              {"warm_child", warm_probe},
                              {"warm_in_process", to_json(warm_build)}};
        j["env_sampling"] = {
            {"samples", n_env},
            {"samples_exact", sc.settings.max_depth == 1},
            {"camera_hits", hits.size()},
            {"native_threads", threads},
            {"native_values_seconds", to_json(env_vals)},
            {"native_sample_seconds", to_json(env_sample)},
            {"native_sample_lookup_seconds", to_json(env_lookup)},
            {"opencl_seconds", to_json(env_cl)},
            {"opencl_first_launch_seconds", cl_env.first_launch_seconds()},
            {"share_native_sample_only", to_json(share_only)},
            {"share_native_with_values", to_json(share_values)},
            {"share_native_with_lookup", to_json(share_lookup)},
            {"share_opencl", to_json(share_cl)},
            {"shade_stage_share_opencl", shade_cl_share},
            {"shade_stage_share_native", shade_cpu_share},
            {"insitu_uniform_saving_native", insitu ? to_json(insitu_cpu) : json()},
            {"insitu_uniform_saving_opencl", insitu ? to_json(insitu_cl) : json()},
            {"checksum", sink}};
        write_json_file(a.json_file, j, 2);
        std::printf("wrote %s\n", a.json_file.c_str());
    }
}

} // namespace

void add_bench_command(CLI::App& app, Globals& g) {
    auto a = std::make_shared<BenchArgs>();
    auto* cmd = app.add_subcommand(
        "bench", "Benchmark the OpenCL back end against the native one on a scene, alternating");
    cmd->add_option("scene", a->scene, "Scene file (.json, see scenes/README.md)")->required();
    cmd->add_option("--spp", a->spp,
                    "Samples per pixel per run (default: about 2 s per run, from the warm-up)")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--runs", a->runs, "Runs per back end, alternating (default 5)")
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--max-depth", a->max_depth,
                    "Bounces (1: direct lighting only, the paper's setting)")
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--paths", a->paths, "Paths in flight (OpenCL; 0: the whole film)")
        ->check(CLI::Range(0, 1 << 26));
    cmd->add_option("--threads", a->threads, "Native back end threads (0: all cores)")
        ->check(CLI::Range(0, 1024));
    cmd->add_option("--target-seconds", a->target_seconds,
                    "Seconds per run when choosing the default --spp (default 2)")
        ->check(CLI::Range(0.01, 3600.0));
    cmd->add_flag("--no-cold", a->no_cold, "Skip the cold program build measurement");
    cmd->add_flag("--no-insitu", a->no_insitu,
                  "Skip the extra renders with a uniform light sample (in-situ sampling cost)");
    cmd->add_option("--json", a->json_file, "Write everything as JSON");
    // Internal: the child process of the cold/warm program build measurement.
    cmd->add_flag("--build-probe", a->build_probe)->group("");
    cmd->callback([a, &g] { run(*a, g); });
}

} // namespace et::cli
