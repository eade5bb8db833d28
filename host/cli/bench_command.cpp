// `envtrace bench`: the OpenCL back end against the native one on one scene, side by side.
//
// The scene is prepared once. After a warm-up render of each back end (reported separately:
// PoCL compiles each kernel's work-group function at its first launch), the two back ends render
// in alternation (opencl, cpu, opencl, cpu, ...), each run a fresh renderer doing N spp. The
// table gives medians and spreads, the OpenCL/native ratio of the medians and the median of the
// ratios of each alternating pair (robust to a machine whose load drifts). Cold program builds
// and the environment-sampling share of a frame are measured by tools/bench/render_probes.
#include "commands.h"
#include "util/json_file.h"
#include "util/output_batch.h"
#include "util/parallel.h"
#include "util/error.h"
#include "opencl/opencl_runtime.h"
#include "render/renderer.h"
#include "load/scene.h"
#include "prepare/device_scene.h"
#include "prepare/sis.h"
#include "util/timer.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sys/utsname.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace et::cli {
namespace {

struct BenchArgs {
    std::string scene, json_file, strategy;
    int spp = 0, runs = 5, max_depth = 0, threads = 0, paths = -1;
    double target_seconds = 2.0;
};

DeviceScene prepare(const BenchArgs& a, const Globals& g) {
    Scene scene = load_scene(a.scene);
    RenderSettings st = scene.settings;
    if (a.max_depth > 0)
        st.max_depth = a.max_depth;
    if (a.paths >= 0)
        st.paths = a.paths;
    if (!a.strategy.empty()) {
        st.strategy = parse_strategy(a.strategy, "command line: --strategy");
        check_split(st);
    }
    st.device = g.device;
    st.threads = a.threads;
    if (st.strategy == Strategy::sis) { // a scene may ask for SIS: its strata, as render builds
        SisOptions so;
        so.samples = st.sis_samples;
        const SisResult sis = build_sis(scene.env, so);
        return prepare_device_scene(std::move(scene), st, nullptr, &sis.strata);
    }
    return prepare_device_scene(std::move(scene), st);
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

Run render_run(DeviceScene& ds, Backend backend, int spp) {
    Run r;
    r.backend = name_of(backend);
    r.spp = spp;
    ds.settings.backend = backend;
    ProgramBuildInfo build;
    Timer construct;
    auto renderer = make_renderer(ds, &build);
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

void print_row(const char* label, const char* unit, const Summary& s, int digits) {
    std::printf("  %-14s %10.*f  [%.*f - %.*f]  IQR %.*f - %.*f %s\n", label, digits, s.median,
                digits, s.min, digits, s.max, digits, s.q1, digits, s.q3, unit);
}

void run(const BenchArgs& a, const Globals& g) {
    const std::string load_before = load_average();
    DeviceScene ds = prepare(a, g);
    // --json reserved before the runs (minutes of them): a missing folder or a name of an input
    // fails first.
    std::optional<OutputBatch> outputs;
    if (!a.json_file.empty())
        outputs.emplace(std::vector<std::string>{a.json_file});
    const RenderSettings& st = ds.settings;
    const int pixels = ds.width() * ds.height();
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    const int threads = a.threads > 0 ? a.threads : static_cast<int>(cores);
    std::printf("scene %s: %zu triangles, BVH %d nodes (depth %d, SAH cost %.1f) in %.1f ms; "
                "%dx%d, depth %d, strategy %s, sampler %s\n",
                a.scene.c_str(), ds.triangle_count, ds.bvh.nodes, ds.bvh.depth, ds.bvh.sah_cost,
                ds.bvh.build_seconds * 1e3, ds.width(), ds.height(), st.max_depth,
                name_of(st.strategy), name_of(st.sampler));
    std::printf("machine: %u hardware threads, native back end on %d threads; load average "
                "%s\n",
                cores, threads, load_before.c_str());
    std::fflush(stdout);

    // Warm-up, not counted: the OpenCL renderer's first launch compiles work-group functions.
    Run warm_cl = render_run(ds, Backend::opencl, 2);
    Run warm_cpu = render_run(ds, Backend::cpu, 1);
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

    std::vector<Run> cl_runs, cpu_runs;
    for (int r = 0; r < a.runs; ++r) {
        cl_runs.push_back(render_run(ds, Backend::opencl, spp));
        cpu_runs.push_back(render_run(ds, Backend::cpu, spp));
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
    std::printf("program build, warm (this process, normal cache, %d renderers): median %.3f s "
                "[%.3f - %.3f]\n",
                a.runs, warm_build.median, warm_build.min, warm_build.max);
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
        j["width"] = ds.width();
        j["height"] = ds.height();
        j["max_depth"] = st.max_depth;
        j["rr_depth"] = st.rr_depth;
        j["strategy"] = name_of(st.strategy);
        j["sampler"] = name_of(st.sampler);
        j["triangles"] = ds.triangle_count;
        j["bvh"] = {{"nodes", ds.bvh.nodes},
                    {"depth", ds.bvh.depth},
                    {"sah_cost", ds.bvh.sah_cost},
                    {"build_seconds", ds.bvh.build_seconds}};
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
        }
        j["ratio_opencl_over_native"] = {{"of_medians", ratio_of_medians},
                                         {"per_pair", pair_ratios},
                                         {"per_pair_summary", to_json(pr)}};
        j["program_build"] = {{"warm_in_process", to_json(warm_build)}};
        write_json_file(*outputs, a.json_file, j, 2);
        outputs->commit();
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
    cmd->add_option("--paths", a->paths, "Paths in flight per lane (OpenCL; 0: the default)")
        ->check(CLI::Range(0, 1 << 26));
    cmd->add_option("--strategy", a->strategy,
                    "The scene's strategy otherwise (throughput comparisons across versions name "
                    "one: tools/bench/render_benchmarks.py runs mis)")
        ->check(CLI::IsMember(strategy_names()));
    cmd->add_option("--threads", a->threads, "Native back end threads (0: all cores)")
        ->check(CLI::Range(0, 1024));
    cmd->add_option("--target-seconds", a->target_seconds,
                    "Seconds per run when choosing the default --spp (default 2)")
        ->check(finite_range(0.01, 3600.0));
    cmd->add_option("--json", a->json_file, "Write everything as JSON");
    cmd->callback([a, &g] { run(*a, g); });
}

} // namespace et::cli
