#include "commands.h"
#include "util/json_file.h"
#include "util/error.h"
#include "image/image_io.h"
#include "image/preview.h"
#include "load/scene.h"
#include "prepare/device_scene.h"
#include "prepare/light_set.h"
#include "util/timer.h"
#include "render/renderer.h"
#include "prepare/sis.h"
#include "render/render_state.h"
#include "util/interrupt.h"
#include "util/output_batch.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace et::cli {
namespace {

struct RenderArgs {
    std::string scene, output, stats_file, strategy, heuristic, sampler, backend = "opencl";
    std::string bsdf_sampling;
    std::string light_share; // --light-share: "auto" or a number
    std::string lights;      // --lights: render with this directional light set
    int sis_samples = 64;
    int spp = 0, max_depth = 0, paths = -1, threads = 0;
    long long seed = -1;
    double time_limit = -1.0;
    double checkpoint = -1.0; // --checkpoint: seconds between saved states (< 0: none)
    bool resume = false;
    std::string state; // --state: the state file (default: beside the image)
};

// out.exr -> (out.exr, out.png); out.png -> (out.exr, out.png).
std::pair<std::string, std::string> output_names(const std::string& out) {
    fs::path p(out);
    std::string ext = p.extension().string();
    for (auto& c : ext)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg")
        return {fs::path(p).replace_extension(".exr").string(), out};
    if (ext == ".exr" || ext == ".hdr" || ext == ".pfm")
        return {out, fs::path(p).replace_extension(".png").string()};
    throw Error(out + ": unsupported output format '" + ext + "' (use .exr, .hdr, .pfm or .png)");
}

class Progress {
  public:
    Progress(int total, double limit) : total_(total), limit_(limit), tty_(isatty(2)) {}
    void update(int done, double elapsed) {
        double frac = limit_ > 0 ? std::min(1.0, elapsed / limit_) : double(done) / total_;
        if (tty_) {
            int width = 30, fill = static_cast<int>(frac * width);
            double eta = frac > 0 ? elapsed * (1 - frac) / frac : 0;
            std::fprintf(stderr, "\r[%.*s%*s] %3d%%  %d spp  %.1fs  ETA %.1fs ", fill,
                         "##############################", width - fill, "", int(frac * 100), done,
                         elapsed, eta);
        } else if (int(frac * 10) > last_decile_) {
            last_decile_ = int(frac * 10);
            std::fprintf(stderr, "envtrace: %d%% (%d spp, %.1f s)\n", last_decile_ * 10, done,
                         elapsed);
        }
    }
    void finish() {
        if (tty_)
            std::fprintf(stderr, "\n");
    }

  private:
    int total_;
    double limit_;
    bool tty_;
    int last_decile_ = 0;
};

// The command line over the scene's settings: parsed once into typed values.
RenderSettings settings_for(const RenderArgs& a, const Globals& g, RenderSettings st) {
    const std::string cli = "command line";
    if (a.spp > 0)
        st.spp = a.spp;
    if (a.max_depth > 0)
        st.max_depth = a.max_depth;
    if (!a.strategy.empty())
        st.strategy = parse_strategy(a.strategy, cli);
    if (!a.heuristic.empty())
        st.heuristic = parse_heuristic(a.heuristic, cli);
    if (!a.sampler.empty())
        st.sampler = parse_sampler(a.sampler, cli);
    if (!a.bsdf_sampling.empty())
        st.bsdf_sampling = parse_bsdf_sampling(a.bsdf_sampling, cli);
    if (!a.light_share.empty())
        st.light_share = parse_light_share(a.light_share, cli + ": --light-share");
    if (a.seed >= 0)
        st.seed = static_cast<uint32_t>(a.seed);
    if (a.time_limit >= 0)
        st.time_limit = a.time_limit;
    if (a.paths >= 0)
        st.paths = a.paths;
    st.backend = parse_backend(a.backend, cli);
    st.device = g.device;
    st.threads = a.threads;
    st.sis_samples = a.sis_samples;
    st.lights = a.lights;
    if (!st.lights.empty()) {
        if (st.strategy == Strategy::sis)
            throw Error("--lights and --strategy sis exclude each other");
        st.strategy = Strategy::lights;
    }
    const bool direct_only = st.strategy == Strategy::sis || st.strategy == Strategy::lights;
    if (direct_only && st.max_depth != 1) {
        warn("--lights and --strategy sis render direct lighting only: using --max-depth 1");
        st.max_depth = 1;
    }
    if (st.strategy == Strategy::sis && st.time_limit <= 0 && st.spp % st.sis_samples != 0)
        throw Error("--strategy sis visits one stratum per sample: --spp (" +
                    std::to_string(st.spp) + ") must be a multiple of --sis-samples (" +
                    std::to_string(st.sis_samples) + ")");
    return st;
}

// The state file of a render to `exr_name`: "out.exr" -> "out.envtrace-state".
std::string default_state_path(const std::string& exr_name) {
    return fs::path(exr_name).replace_extension(".envtrace-state").string();
}

nlohmann::json stats_json(const RenderArgs& a, const RenderSettings& st, const DeviceScene& ds,
                          Renderer& renderer, const ProgramBuildInfo& build,
                          const LightSet& light_set, const SisResult& sis, int done,
                          int resumed_from, int sig, double render_s) {
    const RenderStats& s = renderer.stats();
    const int rendered = done - resumed_from;
    nlohmann::json j;
    j["scene"] = a.scene;
    j["backend"] = renderer.name();
    j["width"] = ds.width();
    j["height"] = ds.height();
    j["spp"] = done;
    j["resumed_from_spp"] = resumed_from;
    j["interrupted"] = sig ? signal_name(sig) : "no";
    j["max_depth"] = st.max_depth;
    j["strategy"] = name_of(st.strategy);
    if (st.strategy == Strategy::lights)
        j["lights"] = {{"file", st.lights}, {"count", light_set.lights.size()}};
    if (st.strategy == Strategy::sis)
        j["sis"] = {{"samples", st.sis_samples},
                    {"precompute_seconds", sis.seconds},
                    {"level_samples", sis.level_samples}};
    j["sampler"] = name_of(st.sampler);
    j["bsdf_sampling"] = name_of(resolved_bsdf_sampling(st));
    if (st.strategy == Strategy::adaptive) {
        // Per material: the light share its bin rendered with after learning.
        nlohmann::json shares = nlohmann::json::object();
        const auto& sh = renderer.light_shares();
        const auto& fl = renderer.bin_flags();
        for (size_t m = 0; m < ds.material_names.size() && m < ds.material_bin.size(); ++m) {
            const size_t b = static_cast<size_t>(ds.material_bin[m]);
            shares[ds.material_names[m]] = {
                {"light_share", sh[b]},
                {"distribution", (fl[b] & ETK_BIN_COMPENSATED) ? "compensated" : "full"},
                {"ggx_sampling", (fl[b] & ETK_BIN_VNDF) ? "vndf" : "ndf"},
                {"candidate", renderer.choices()[b]}};
        }
        j["light_share"] = {{"learned", st.light_share < 0.0f},
                            {"learning_passes_extra", s.learning_passes},
                            {"materials", shares}};
    }
    j["render_seconds"] = render_s;
    j["seconds_per_spp"] = render_s / std::max(1, rendered);
    j["nonfinite_samples"] = s.nonfinite_samples;
    j["rays"] = {{"camera", s.camera_rays},
                 {"continuation", s.continuation_rays},
                 {"shadow", s.shadow_rays}};
    j["mrays_per_second"] = s.rays() / render_s * 1e-6;
    j["samples_per_second"] = double(rendered) * ds.width() * ds.height() / render_s;
    j["program_build_seconds"] = build.seconds;
    j["program_from_cache"] = build.from_cache;
    j["bvh"] = {{"nodes", ds.bvh.nodes},
                {"depth", ds.bvh.depth},
                {"sah_cost", ds.bvh.sah_cost},
                {"build_seconds", ds.bvh.build_seconds}};
    j["environment_build_seconds"] = ds.map_build_seconds;
    for (const auto& [name, t] : s.stage_seconds)
        j["stage_seconds"][name] = t;
    return j;
}

void run(const RenderArgs& a, Globals& g) {
    Timer total;
    Scene scene = load_scene(a.scene);
    const RenderSettings st = settings_for(a, g, scene.settings);
    std::string out = !a.output.empty()       ? a.output
                      : !scene.output.empty() ? scene.output
                                              : fs::path(a.scene).stem().string() + ".exr";
    auto [exr_name, png_name] = output_names(out);
    // Fail on an unwritable destination before spending the render time.
    check_writable_format(exr_name);
    check_writable_format(png_name);
    const bool keep_state = a.checkpoint >= 0 || a.resume;
    const std::string state_path = !a.state.empty() ? a.state : default_state_path(exr_name);

    // Directional lights and SIS strata: the light directions the shade stages sum or draw.
    LightSet light_set;
    SisResult sis;
    if (st.strategy == Strategy::lights) {
        light_set = read_lights(st.lights);
        std::printf("light set %s: %zu directional lights (%s)\n", st.lights.c_str(),
                    light_set.lights.size(), light_set.method.c_str());
    }
    RenderState state;
    if (a.resume)
        state = read_render_state(state_path);

    // Every output, reserved now that every input has been read: none may be an input (the
    // state continues itself), none may be two, and all are written together at the end.
    std::vector<std::string> targets = {exr_name, png_name};
    if (!a.stats_file.empty())
        targets.push_back(a.stats_file);
    if (keep_state)
        targets.push_back(state_path);
    OutputBatch outputs(targets, a.resume ? std::vector<std::string>{state_path}
                                          : std::vector<std::string>{});

    if (st.strategy == Strategy::sis) {
        SisOptions so;
        so.samples = st.sis_samples;
        sis = build_sis(scene.env, so);
        std::printf("SIS: %d strata (per level:", st.sis_samples);
        for (int n : sis.level_samples)
            std::printf(" %d", n);
        std::printf(") precomputed in %.3f s\n", sis.seconds);
    }
    const DeviceScene ds =
        prepare_device_scene(std::move(scene), st, &light_set.lights, &sis.strata);
    std::printf("scene %s: %zu triangles, BVH %d nodes (depth %d, SAH cost %.1f) in %.1f ms; "
                "environment %dx%d, distribution in %.2f ms\n",
                a.scene.c_str(), ds.triangle_count, ds.bvh.nodes, ds.bvh.depth, ds.bvh.sah_cost,
                ds.bvh.build_seconds * 1e3, ds.map_width, ds.map_height,
                ds.map_build_seconds * 1e3);
    if (a.resume) {
        check_render_state(state, ds, state_path);
        if (st.time_limit <= 0 && state.spp > st.spp)
            throw Error(state_path + ": the render state has " + std::to_string(state.spp) +
                        " spp, more than the --spp " + std::to_string(st.spp) +
                        " asked for; samples cannot be taken away");
    }
    if (keep_state)
        state.key = render_key(ds);

    ProgramBuildInfo build;
    std::unique_ptr<Renderer> renderer_ptr = make_renderer(ds, &build);
    Renderer& renderer = *renderer_ptr;
    if (st.backend == Backend::opencl)
        std::printf("OpenCL program build %.3f s (%s)\n", build.seconds,
                    build.from_cache ? "cached binary" : "compiled");
    int done = 0;
    if (a.resume) {
        renderer.resume(state.film);
        done = state.spp;
        std::printf("resumed from %s at %d spp\n", state_path.c_str(), done);
    }
    const int resumed_from = done;
    std::printf(
        "backend %s: %dx%d, %s spp, depth %d, strategy %s, sampler %s, %d paths in flight\n",
        renderer.name().c_str(), ds.width(), ds.height(),
        st.time_limit > 0 ? "time-limited" : std::to_string(st.spp).c_str(), st.max_depth,
        name_of(st.strategy), name_of(st.sampler), renderer.paths());
    std::fflush(stdout);

    // From here on a first SIGINT/SIGTERM keeps the samples: the pass in flight ends, the
    // outputs are written, and the status tells the signal. At least one sample is always
    // rendered (a --time-limit shorter than a pass still gives one).
    InterruptHandler interrupts;
    Progress progress(st.spp, st.time_limit);
    Timer render, since_checkpoint;
    for (;;) {
        if (InterruptHandler::signal())
            break;
        if (done > 0 && (st.time_limit > 0 ? render.seconds() >= st.time_limit : done >= st.spp))
            break;
        renderer.render_sample(static_cast<uint32_t>(done));
        ++done;
        progress.update(done, render.seconds());
        if (a.checkpoint >= 0 && since_checkpoint.seconds() >= a.checkpoint &&
            !InterruptHandler::signal()) {
            state.spp = done;
            state.film = renderer.film();
            write_render_state(state_path, state);
            since_checkpoint = Timer();
        }
    }
    progress.finish();
    const int sig = InterruptHandler::signal();
    if (sig)
        std::fprintf(stderr,
                     "envtrace: %s: stopped at %d spp; writing the image (a second "
                     "signal stops at once)\n",
                     signal_name(sig), done);
    const double render_s = render.seconds();
    std::vector<float> img = renderer.image();
    const RenderStats& s = renderer.stats();

    std::vector<std::pair<std::string, std::string>> meta = {
        {"envtrace:spp", std::to_string(done)},
        {"envtrace:interrupted", sig ? signal_name(sig) : "no"},
        {"envtrace:resumed_from_spp", std::to_string(resumed_from)},
        {"envtrace:strategy", name_of(st.strategy)},
        {"envtrace:mis_heuristic", name_of(st.heuristic)},
        {"envtrace:sampler", name_of(st.sampler)},
        {"envtrace:bsdf_sampling", name_of(resolved_bsdf_sampling(st))},
        {"envtrace:seed", std::to_string(st.seed)},
        {"envtrace:max_depth", std::to_string(st.max_depth)},
        {"envtrace:render_seconds", std::to_string(render_s)},
        {"envtrace:backend", renderer.name()},
        {"envtrace:lights", st.lights},
        {"envtrace:sis_seconds", std::to_string(sis.seconds)},
        {"Software", "envtrace " ENVTRACE_VERSION},
    };
    write_image(outputs, exr_name, ds.width(), ds.height(), 3, img, meta);
    RgbImage film{ds.width(), ds.height(), img};
    write_image(outputs, png_name, ds.width(), ds.height(), 3, tone_map(film, 1.0f));
    if (!a.stats_file.empty())
        write_json_file(outputs, a.stats_file,
                        stats_json(a, st, ds, renderer, build, light_set, sis, done, resumed_from,
                                   sig, render_s),
                        2);
    if (keep_state) {
        state.spp = done;
        state.film = renderer.film();
        write_render_state(outputs, state_path, state);
    }
    outputs.commit();

    const int rendered = done - resumed_from;
    const double mrays = s.rays() / render_s * 1e-6;
    std::printf(
        "rendered %d spp in %.2f s: %.2f Mrays/s (%llu camera, %llu continuation, %llu shadow), "
        "%.3g samples/s, %.4f s/spp\n",
        rendered, render_s, mrays, (unsigned long long)s.camera_rays,
        (unsigned long long)s.continuation_rays, (unsigned long long)s.shadow_rays,
        double(rendered) * ds.width() * ds.height() / render_s, render_s / std::max(1, rendered));
    if (s.nonfinite_samples > 0)
        warn(a.scene + ": " + std::to_string(s.nonfinite_samples) +
             " samples were not finite and counted as zero (a renderer bug: please "
             "report the scene)");
    std::printf("%s time per stage:", st.backend == Backend::cpu ? "thread" : "device");
    for (const auto& [name, t] : s.stage_seconds)
        std::printf(" %s %.3fs", name.c_str(), t);
    std::printf("\nwrote %s and %s%s%s at %d spp (total %.2f s)\n", exr_name.c_str(),
                png_name.c_str(), keep_state ? " and the state " : "",
                keep_state ? state_path.c_str() : "", done, total.seconds());
    if (sig)
        g.exit_code = 128 + sig;
}

} // namespace

void add_render_command(CLI::App& app, Globals& g) {
    auto a = std::make_shared<RenderArgs>();
    auto* cmd = app.add_subcommand("render", "Render a scene file with the wavefront path tracer");
    cmd->add_option("scene", a->scene, "Scene file (.json, see scenes/README.md)")->required();
    cmd->add_option("-o,--output", a->output,
                    "Output image: .exr/.hdr/.pfm (linear) plus a .png preview beside it");
    cmd->add_option("--spp", a->spp, "Samples per pixel")->check(CLI::Range(1, 1 << 24));
    cmd->add_option("--time-limit", a->time_limit, "Render for this many seconds instead of --spp")
        ->check(CLI::Range(0.0, 1e7));
    cmd->add_option("--max-depth", a->max_depth,
                    "Bounces (1: direct lighting only, the paper's setting)")
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--strategy", a->strategy,
                    "light | bsdf | mis (the paper's) | compensated (MIS with a compensated light "
                    "distribution) | adaptive (compensated, light/BSDF shares learned per "
                    "material) | uniform | sis (structured importance sampling)")
        ->check(CLI::IsMember(strategy_names()));
    cmd->add_option("--sis-samples", a->sis_samples,
                    "SIS strata (one shadow ray per sample; --spp a multiple of it)")
        ->check(CLI::Range(1, 1 << 16));
    cmd->add_option("--lights", a->lights,
                    "Render with this directional light set ('envtrace lights'), natively");
    cmd->add_option("--mis-heuristic", a->heuristic, "balance | power")
        ->check(CLI::IsMember(heuristic_names()));
    cmd->add_option("--sampler", a->sampler, "sobol | random")
        ->check(CLI::IsMember(sampler_names()));
    cmd->add_option("--bsdf-sampling", a->bsdf_sampling,
                    "GGX lobes: vndf (visible normals) | ndf (the paper's) | auto (vndf for "
                    "compensated and adaptive, ndf otherwise)")
        ->check(CLI::IsMember(bsdf_sampling_names()));
    cmd->add_option("--light-share", a->light_share,
                    "Adaptive strategy: expected light samples of the two at a vertex, 0 .. "
                    "1.875, or auto (learned per material from the first passes)");
    cmd->add_option("--seed", a->seed, "Sampler seed")->check(CLI::Range(0LL, 4294967295LL));
    cmd->add_option("--paths", a->paths, "Paths in flight (0: the whole film, capped by memory)")
        ->check(CLI::Range(0, 1 << 26));
    cmd->add_option("--stats", a->stats_file, "Write the render summary as JSON");
    cmd->add_option("--checkpoint", a->checkpoint,
                    "Save a resumable state every SECONDS of rendering (0: every pass), when "
                    "interrupted, and at the end")
        ->check(CLI::Range(0.0, 1e7));
    cmd->add_flag("--resume", a->resume,
                  "Continue from the saved state (same scene and settings; --spp is the total)");
    cmd->add_option("--state", a->state,
                    "The state file of --checkpoint and --resume (default: OUTPUT.envtrace-state "
                    "beside the image)");
    cmd->add_option("--backend", a->backend,
                    "opencl (default) or cpu (native C++, same kernels/ sources)")
        ->check(CLI::IsMember(backend_names()));
    cmd->add_option("--threads", a->threads, "Native back end threads (0: all cores)")
        ->check(CLI::Range(0, 1024));
    cmd->callback([a, &g] { run(*a, g); });
}

} // namespace et::cli
