#include "cluster.h"
#include "commands.h"
#include "util/json_file.h"
#include "util/error.h"
#include "util/file_check.h"
#include "image/image_io.h"
#include "image/preview.h"
#include "load/scene.h"
#include "prepare/device_scene.h"
#include "prepare/light_set.h"
#include "util/timer.h"
#include "render/film_layers.h"
#include "render/noise_estimate.h"
#include "render/renderer.h"
#include "prepare/sis.h"
#include "render/render_state.h"
#include "util/interrupt.h"
#include "util/output_batch.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <xxhash.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <tuple>
#include <unistd.h>

namespace fs = std::filesystem;

namespace et::cli {

// out.exr -> (out.exr, out.png); out.png -> (out.exr, out.png). A build without OpenImageIO
// writes no preview: out.pfm -> (out.pfm, "").
std::pair<std::string, std::string> output_names(const std::string& out) {
    fs::path p(out);
    std::error_code ec;
    if (!out.empty() && (out.back() == '/' || p.filename() == "." || p.filename() == ".." ||
                         fs::is_directory(p, ec)))
        throw Error(out + ": is a folder: name the image to write in it (e.g. " +
                    (fs::path(out) / "render.exr").lexically_normal().string() + ")");
    const std::string ext = lower_extension(out);
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg")
        return {fs::path(p).replace_extension(".exr").string(), out};
    if (ext == ".exr" || ext == ".hdr" || ext == ".pfm")
        return {out, have_image_library() ? fs::path(p).replace_extension(".png").string() : ""};
    throw Error(out + ": unsupported output format '" + ext +
                "' (use .exr, .hdr, .pfm, or .png / .jpg for the preview beside an .exr)");
}

namespace {

struct RenderArgs {
    std::string scene, output, stats_file, strategy, heuristic, sampler, backend = "opencl";
    std::string bsdf_sampling;
    std::string light_batch;   // --light-batch: auto, on, off
    std::string guide_verdict; // --guide-verdict: on, off
    std::string lights;        // --lights: render with this directional light set
    int sis_samples = 64;
    int light_samples = 0, bsdf_samples = 0; // --light-samples, --bsdf-samples
    // Which options the command line gave (set by the callback from CLI11's counts): for
    // options whose every value means something, and those that only apply to some renders.
    bool light_samples_given = false, bsdf_samples_given = false, sis_samples_given = false;
    bool device_given = false, paths_given = false;
    int spp = 0, max_depth = 0, rr_depth = -1, paths = -1, threads = 0;
    long long seed = -1;
    double time_limit = -1.0;
    double checkpoint = -1.0;  // --checkpoint: seconds between saved states (< 0: none)
    double noise_target = 0.0; // --noise-target: stop at this relative error (0: none)
    bool aovs = false;         // --aovs: albedo, normal, depth and variance layers in the EXR
    bool resume = false;
    std::string state;        // --state: the state file (default: beside the image)
    std::string sample_range; // --sample-range A:B: a farm task, samples A .. B-1
};

class Progress {
  public:
    Progress(int total, double limit) : total_(total), limit_(limit), tty_(isatty(2)) {}
    // A noise target without --spp: progress towards the next check.
    void set_total(int total) { total_ = std::max(1, total); }
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
    if (a.rr_depth >= 0)
        st.rr_depth = a.rr_depth;
    if (!a.strategy.empty())
        st.strategy = parse_strategy(a.strategy, cli);
    if (!a.heuristic.empty())
        st.heuristic = parse_heuristic(a.heuristic, cli);
    if (!a.sampler.empty())
        st.sampler = parse_sampler(a.sampler, cli);
    if (!a.bsdf_sampling.empty())
        st.bsdf_sampling = parse_bsdf_sampling(a.bsdf_sampling, cli);
    if (!a.light_batch.empty())
        st.light_batch = parse_light_batch(a.light_batch, cli);
    if (!a.guide_verdict.empty())
        st.guide_verdict = a.guide_verdict == "on";
    if (a.light_samples_given)
        st.light_samples = check_split_count(a.light_samples, cli + ": --light-samples");
    if (a.bsdf_samples_given)
        st.bsdf_samples = check_split_count(a.bsdf_samples, cli + ": --bsdf-samples");
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
    st.aovs = a.aovs;
    if (!st.lights.empty()) {
        // A light set is its own estimator: a strategy asked for as well would be dropped.
        if (!a.strategy.empty())
            throw Error(cli +
                        ": --lights renders with the directional light set; it excludes "
                        "--strategy " +
                        a.strategy);
        st.strategy = Strategy::lights;
    }
    // Options this render does not use: said, not silently dropped.
    if (a.sis_samples_given && st.strategy != Strategy::sis)
        warn("--sis-samples applies to --strategy sis only: ignored");
    if (!a.guide_verdict.empty() && st.strategy != Strategy::visibility)
        warn("--guide-verdict applies to --strategy visibility only: ignored");
    if (st.backend == Backend::cpu && a.device_given)
        warn("--device picks an OpenCL device: ignored with --backend cpu");
    if (st.backend == Backend::cpu && a.paths_given)
        warn("--paths sets the OpenCL back end's paths in flight: ignored with --backend cpu "
             "(each native thread keeps its own wave)");
    const bool direct_only = st.strategy == Strategy::sis || st.strategy == Strategy::lights;
    if (direct_only && st.max_depth != 1) {
        warn("--lights and --strategy sis render direct lighting only: using --max-depth 1");
        st.max_depth = 1;
    }
    check_split(st);
    if (st.strategy == Strategy::sis && st.time_limit <= 0 && a.sample_range.empty() &&
        st.spp % st.sis_samples != 0)
        throw Error("--strategy sis visits one stratum per sample: --spp (" +
                    std::to_string(st.spp) + ") must be a multiple of --sis-samples (" +
                    std::to_string(st.sis_samples) + ")");
    return st;
}

// The visibility strategy's verdict (render/guide_verdict.h), as the stats and the EXR name it.
std::string verdict_name(const RenderStats& s) {
    return s.learning.contains("verdict") ? s.learning["verdict"].get<std::string>() : "none";
}

// The state file of a render to `exr_name`: "out.exr" -> "out.envtrace-state".
std::string default_state_path(const std::string& exr_name) {
    return fs::path(exr_name).replace_extension(".envtrace-state").string();
}

// A render only a --time-limit or --noise-target ends: either without --spp on the command line
// (the scene's spp is then no cap), and not a farm task's fixed range.
bool uncapped_render(const RenderArgs& a, const RenderSettings& st, bool partial) {
    return !partial && (st.time_limit > 0 || a.noise_target > 0) && a.spp <= 0;
}

nlohmann::json stats_json(const RenderArgs& a, const RenderSettings& st, const DeviceScene& ds,
                          const std::string& backend, const RenderStats& s,
                          const ProgramBuildInfo& build, const LightSet& light_set,
                          const SisResult& sis, int done, int resumed_from, int sig,
                          double render_s, int ranks, int first, const Renderer& renderer) {
    const int rendered = done - resumed_from;
    nlohmann::json j;
    j["scene"] = a.scene;
    j["backend"] = backend;
    j["ranks"] = ranks;
    j["width"] = ds.width();
    j["height"] = ds.height();
    j["spp"] = done;
    j["first_sample"] = first;
    j["resumed_from_spp"] = resumed_from;
    j["interrupted"] = sig ? signal_name(sig) : "no";
    j["max_depth"] = st.max_depth;
    j["rr_depth"] = st.rr_depth;
    j["strategy"] = name_of(st.strategy);
    if (st.strategy == Strategy::lights)
        j["lights"] = {{"file", st.lights}, {"count", light_set.lights.size()}};
    if (st.strategy == Strategy::sis)
        j["sis"] = {{"samples", st.sis_samples},
                    {"precompute_seconds", sis.seconds},
                    {"level_samples", sis.level_samples}};
    j["sampler"] = name_of(st.sampler);
    j["mis_heuristic"] = name_of(resolved_heuristic(st));
    j["bsdf_sampling"] = name_of(resolved_bsdf_sampling(st));
    j["light_batch"] = renderer.batches_light_samples();
    j["light_samples"] = st.light_samples; // per vertex (mis splitting; 1: the paper's)
    j["bsdf_samples"] = st.bsdf_samples;
    if (!s.learning.is_null()) { // the learning technique's figures (LearningPolicy::stats)
        j[name_of(st.strategy)] = s.learning;
        j[name_of(st.strategy)]["learning_passes_extra"] = s.learning_passes;
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

// "A:B" -> [A, B): the sample indices of one farm task.
std::pair<int, int> parse_sample_range(const std::string& text) {
    const std::string bad = "--sample-range '" + text.substr(0, 40) + "': ";
    const size_t colon = text.find(':');
    if (colon == std::string::npos)
        throw Error(bad + "expected FIRST:END (sample indices FIRST .. END-1, e.g. 0:64)");
    auto number = [&](const std::string& t) {
        if (t.empty() || t.size() > 9 || t.find_first_not_of("0123456789") != std::string::npos)
            throw Error(bad + "expected two integers in [0, 16777216], FIRST:END");
        return std::stoi(t);
    };
    const int first = number(text.substr(0, colon)), end = number(text.substr(colon + 1));
    if (end <= first || end > (1 << 24))
        throw Error(bad + "END must be above FIRST and at most 16777216");
    return {first, end};
}

// The message of the exception in flight, as main would print it.
std::string error_text() {
    try {
        throw;
    } catch (const cl::Error& e) {
        return std::string("OpenCL call ") + e.what() + " failed: " + cl_error_name(e.err());
    } catch (const std::bad_alloc&) {
        return "out of memory (a smaller film, fewer --paths or a smaller scene needs less)";
    } catch (const std::exception& e) {
        return e.what();
    } catch (...) {
        return "unexpected exception (not a std::exception)";
    }
}

// Runs f, returning its error message ("" when it succeeded), for Cluster::check.
template <class F> std::string attempt(F&& f) {
    try {
        f();
        return "";
    } catch (...) {
        return error_text();
    }
}

void run(const RenderArgs& a, Globals& g) {
    const Cluster& cl = *g.cluster;
    if (cl.launched_without_mpi())
        throw Error("started by mpirun as one of several ranks, but this envtrace was built "
                    "without MPI (configure with libopenmpi-dev installed, ENVTRACE_MPI=AUTO or "
                    "ON): each rank would render the whole image alone");
    // Rank 0 speaks for the render; the other ranks' errors reach it through Cluster::check.
    if (!cl.root() && !std::freopen("/dev/null", "w", stdout))
        throw Error("cannot redirect the standard output of " + cl.describe(cl.rank()));
    Timer total;
    const bool partial = !a.sample_range.empty();
    std::pair<int, int> range{0, 0};
    std::optional<Scene> scene;
    RenderSettings st;
    std::string exr_name, png_name, state_path;
    bool keep_state = false;
    LightSet light_set;
    SisResult sis;
    RenderState state;
    std::unique_ptr<OutputBatch> outputs;
    std::optional<DeviceScene> ds_store;
    std::vector<std::pair<std::string, std::string>> env_meta; // the scene's environment settings
    ProgramBuildInfo build;
    std::unique_ptr<Renderer> renderer_ptr;

    // Every rank reads and prepares everything; rank 0 alone reads the state and reserves the
    // outputs. A failure on any rank ends every rank here, named.
    cl.check(attempt([&] {
        if (partial) {
            range = parse_sample_range(a.sample_range);
            if (a.time_limit >= 0 || a.noise_target > 0)
                throw Error("--sample-range renders a fixed range of sample indices: it excludes "
                            "--time-limit and --noise-target");
            // --spp with a range: the whole render's samples, which merge checks are all there.
            if (a.spp > 0 && range.second > a.spp)
                throw Error("--sample-range " + a.sample_range + " reaches past --spp " +
                            std::to_string(a.spp) +
                            " (with a range, --spp is the whole render's samples)");
        }
        scene.emplace(load_scene(a.scene));
        st = settings_for(a, g, scene->settings);
        // A farm task of SIS: whole rounds of its strata, so that the merged tasks are too.
        if (partial && st.strategy == Strategy::sis &&
            (range.first % st.sis_samples != 0 || range.second % st.sis_samples != 0))
            throw Error("--strategy sis visits one stratum per sample: --sample-range (" +
                        a.sample_range + ") must start and end at multiples of --sis-samples (" +
                        std::to_string(st.sis_samples) + ")");
        const std::string out = !a.output.empty() ? a.output
                                : !scene->output.empty()
                                    ? scene->output
                                    : fs::path(a.scene).stem().string() + ".exr";
        std::tie(exr_name, png_name) = output_names(out);
        if (st.aovs && !partial && fs::path(exr_name).extension() != ".exr")
            throw Error(exr_name + ": --aovs writes its layers into an OpenEXR image: name an "
                                   ".exr output (-o)");
        // Fail on an unwritable destination before spending the render time.
        check_writable_format(exr_name);
        if (!png_name.empty())
            check_writable_format(png_name);
        keep_state = a.checkpoint >= 0 || a.resume || partial;
        if (!a.state.empty() && !keep_state)
            throw Error("--state " + a.state +
                        ": names the state of --checkpoint, --resume or --sample-range; this "
                        "render keeps none (add --checkpoint SECONDS to save one)");
        state_path = !a.state.empty() ? a.state
                     : partial ? fs::path(exr_name).replace_extension("").string() + ".samples-" +
                                     std::to_string(range.first) + "-" +
                                     std::to_string(range.second) + ".envtrace-state"
                               : default_state_path(exr_name);

        // Directional lights and SIS strata: the light directions the shade stages sum or draw.
        if (st.strategy == Strategy::lights) {
            light_set = read_lights(st.lights);
            std::printf("light set %s: %zu directional lights (%s)\n", st.lights.c_str(),
                        light_set.lights.size(), light_set.method.c_str());
        }
        if (a.resume && cl.root())
            state = read_render_state(state_path);

        // Every output, reserved now that every input has been read: none may be an input (the
        // state continues itself), none may be two, and all are written together at the end. A
        // part of a render (--sample-range) writes its film's sums only, for `envtrace merge`.
        if (cl.root()) {
            std::vector<std::string> targets;
            if (!partial)
                targets = {exr_name};
            if (!partial && !png_name.empty())
                targets.push_back(png_name);
            if (!a.stats_file.empty())
                targets.push_back(a.stats_file);
            if (keep_state)
                targets.push_back(state_path);
            outputs = std::make_unique<OutputBatch>(targets,
                                                    a.resume ? std::vector<std::string>{state_path}
                                                             : std::vector<std::string>{});
        }

        if (st.strategy == Strategy::sis) {
            SisOptions so;
            so.samples = st.sis_samples;
            sis = build_sis(scene->env, so);
            std::printf("SIS: %d strata (per level:", st.sis_samples);
            for (int n : sis.level_samples)
                std::printf(" %d", n);
            std::printf(") precomputed in %.3f s\n", sis.seconds);
        }
        env_meta = {
            {"envtrace:environment_rotation_degrees", std::to_string(scene->env.rotation_degrees)},
            {"envtrace:environment_convention", name_of(scene->env.convention)},
            {"envtrace:environment_intensity", std::to_string(scene->env.scale)}};
        ds_store.emplace(
            prepare_device_scene(std::move(*scene), st, &light_set.lights, &sis.strata));
        const DeviceScene& ds = *ds_store;
        std::printf("scene %s: %zu triangles, BVH %d nodes (depth %d, SAH cost %.1f) in %.1f ms; "
                    "environment %dx%d, distribution in %.2f ms\n",
                    a.scene.c_str(), ds.triangle_count, ds.bvh.nodes, ds.bvh.depth, ds.bvh.sah_cost,
                    ds.bvh.build_seconds * 1e3, ds.map_width, ds.map_height,
                    ds.map_build_seconds * 1e3);
        if (a.resume && cl.root()) {
            check_render_state(state, ds, state_path);
            if (state.first != range.first)
                throw Error(state_path + ": the render state holds samples from index " +
                            std::to_string(state.first) + ", this render starts at " +
                            std::to_string(range.first));
            const int asked = partial ? range.second - range.first : st.spp;
            // Uncapped: --time-limit or --noise-target without --spp (the scene's spp is no cap
            // then, as for the render itself below).
            if (!uncapped_render(a, st, partial) && state.spp > asked)
                throw Error(state_path + ": the render state has " + std::to_string(state.spp) +
                            " spp, more than the " + std::to_string(asked) +
                            (partial     ? " of --sample-range"
                             : a.spp > 0 ? " of --spp"
                                         : " of the scene's render.spp") +
                            " asked for; samples cannot be taken away");
        }
        state.key = render_key(ds);
        renderer_ptr = make_renderer(ds, &build);
    }));
    const DeviceScene& ds = *ds_store;
    Renderer& renderer = *renderer_ptr;
    // The ranks must render one film: the same scene, inputs and settings everywhere.
    const uint64_t root_key = static_cast<uint64_t>(cl.broadcast(static_cast<int64_t>(state.key)));
    cl.check(root_key == state.key
                 ? ""
                 : a.scene +
                       ": the scene, its inputs, the settings or envtrace differ from rank "
                       "0's (render key " +
                       std::to_string(state.key) + ", rank 0 has " + std::to_string(root_key) +
                       "): the ranks would not render one film");
    // And how many samples, which and until when: options outside the render key, which ranks
    // started with different command lines (MPMD) could disagree on, rendering a wrong film or
    // ending in an MPI error without a word.
    char limits[96];
    std::snprintf(limits, sizeof limits, ", time limit %g, noise target %g", st.time_limit,
                  a.noise_target);
    const std::string control = "range " + std::to_string(range.first) + ":" +
                                std::to_string(range.second) + ", spp " + std::to_string(st.spp) +
                                (a.spp > 0 ? " (--spp)" : "") + limits +
                                (a.resume ? ", resumed" : "");
    const uint64_t control_key = XXH3_64bits(control.data(), control.size());
    const uint64_t root_control =
        static_cast<uint64_t>(cl.broadcast(static_cast<int64_t>(control_key)));
    cl.check(root_control == control_key
                 ? ""
                 : a.scene + ": this rank's samples (" + control +
                       ") differ from rank 0's: --spp, --sample-range, --time-limit, "
                       "--noise-target and --resume must be the same on every rank");

    if (st.backend == Backend::opencl)
        std::printf("OpenCL program build %.3f s (%s)\n", build.seconds,
                    build.from_cache ? "cached binary" : "compiled");
    // Sample indices first .. end-1; `done` of them are in the film (on rank 0: a resumed state's
    // count too). In each round, rank r renders index first + done + r: the ranks take disjoint
    // indices, and a round ends with the film holding a prefix of the range, which an interrupted
    // or time-limited render writes and a resumed one continues, with any number of ranks.
    const int64_t first = range.first;
    // --noise-target and --time-limit: --spp, when given on the command line, caps the render;
    // else only the target or the time ends it.
    const bool noise = a.noise_target > 0;
    const bool uncapped = uncapped_render(a, st, partial);
    const int64_t end = partial ? range.second : uncapped ? int64_t(1) << 24 : st.spp;
    // The whole render's samples, kept in the state for merge (render_state.h).
    const int whole_render = partial    ? (a.spp > 0 ? a.spp : range.second)
                             : uncapped ? 0
                                        : static_cast<int>(end);
    int64_t done = cl.broadcast(state.spp);
    if (a.resume && cl.root()) {
        renderer.resume(state.sums);
        std::printf("resumed from %s at %d spp\n", state_path.c_str(), state.spp);
    }
    const int64_t resumed_from = done;
    std::printf(
        "backend %s: %dx%d, %s spp%s, depth %d, strategy %s, sampler %s, %d paths in "
        "flight%s\n",
        renderer.name().c_str(), ds.width(), ds.height(),
        st.time_limit > 0 ? "time-limited" : std::to_string(end - first).c_str(),
        partial
            ? (" (samples " + std::to_string(first) + ".." + std::to_string(end - 1) + ")").c_str()
            : "",
        st.max_depth, name_of(st.strategy), name_of(st.sampler), renderer.paths(),
        cl.size() > 1 ? (", " + std::to_string(cl.size()) + " MPI ranks").c_str() : "");
    std::fflush(stdout);

    // From here on a first SIGINT/SIGTERM keeps the samples: the round in flight is abandoned
    // between two bounces (a pass of a deep scene can take minutes), the outputs are written
    // with the rounds before it, and the status tells the signal. The --time-limit stops a
    // round the same way. The first round is always finished (a signal or a --time-limit
    // shorter than a pass still gives an image of one sample).
    InterruptHandler interrupts;
    Progress progress(static_cast<int>(end - first), st.time_limit);
    Timer render, since_checkpoint;
    std::string render_error;
    int sig = 0;
    bool stopped = false; // a round was abandoned (on some rank): stop, keeping none of it
    // The time limit abandons no round before this run's first is whole: a resumed render whose
    // first round (learning passes replayed included) outlasts the limit would otherwise drop it
    // every time, and a loop of time-limited resumes never get further.
    renderer.set_stop([&] {
        return done > 0 &&
               (InterruptHandler::signal() != 0 ||
                (st.time_limit > 0 && done > resumed_from && render.seconds() >= st.time_limit));
    });
    // MPI ranks keep a round only where no rank abandoned its part (a film of rounds whole).
    renderer.set_hold(cl.size() > 1);
    // The noise target is checked on the summed film (every rank's, reduced to rank 0) at spp
    // counts every rank knows (kNoiseFirstCheck, then where the error is predicted to meet the
    // target, at most doubling), so that the few reductions cost little.
    double noise_error = std::numeric_limits<double>::infinity();
    bool noise_reached = false;
    int64_t next_check = std::max<int64_t>(kNoiseFirstCheck, done);
    if (noise && a.spp <= 0)
        progress.set_total(static_cast<int>(std::min(end, next_check)));
    for (;;) {
        if (noise && !noise_reached && !stopped && done >= next_check && first + done < end) {
            const FilmSums all = cl.reduce(renderer.sums());
            int64_t next = next_check, reached = 0;
            if (cl.root()) {
                noise_error = relative_error(all);
                reached = noise_error <= a.noise_target;
                next = next_noise_check(done, noise_error, a.noise_target);
                std::fprintf(
                    stderr,
                    "envtrace: noise check at %lld spp: estimated relative error %.4g "
                    "(target %g)%s\n",
                    static_cast<long long>(done), noise_error, a.noise_target,
                    reached ? "" : (", next check at " + std::to_string(next) + " spp").c_str());
            }
            noise_reached = cl.broadcast(reached) != 0;
            next_check = cl.broadcast(next);
            if (a.spp <= 0)
                progress.set_total(static_cast<int>(std::min(end, next_check)));
        }
        // What the ranks agree on before each round: stop (a signal on any rank, the time limit
        // by rank 0's clock, or the range done), save a checkpoint (rank 0's clock), a failure.
        int64_t f[4] = {0, 0, render_error.empty() ? 0 : 1, InterruptHandler::signal()};
        if (f[3] != 0 || stopped || (done > 0 && first + done >= end) || noise_reached ||
            (cl.root() && done > resumed_from && st.time_limit > 0 &&
             render.seconds() >= st.time_limit))
            f[0] = 1;
        if (cl.root() && a.checkpoint >= 0 && done > resumed_from &&
            since_checkpoint.seconds() >= a.checkpoint)
            f[1] = 1;
        cl.max_all(f, 4);
        if (f[2])
            cl.check(render_error);
        sig = static_cast<int>(f[3]);
        if (f[1] && !f[0]) {
            const FilmSums all = cl.reduce(renderer.sums());
            cl.check(attempt([&] {
                if (cl.root())
                    write_render_state(state_path,
                                       RenderState{state.key, static_cast<int>(done),
                                                   static_cast<int>(first), all, whole_render});
            }));
            since_checkpoint = Timer();
        }
        if (f[0])
            break;
        const int64_t index = first + done + cl.rank();
        bool whole = true;
        if (index < end)
            render_error =
                attempt([&] { whole = renderer.render_sample(static_cast<uint32_t>(index)); });
        if (cl.size() > 1) {
            int64_t g[2] = {whole ? 0 : 1, renderer.abandoned() ? 1 : 0};
            cl.max_all(g, 2);
            whole = g[0] == 0;
            stopped = g[1] != 0;
            if (whole)
                renderer.keep_held();
            else
                renderer.drop_held();
        } else {
            stopped = renderer.abandoned();
        }
        if (!whole)
            continue; // the next agreement stops, with the rounds before this one
        done += std::min<int64_t>(cl.size(), end - (first + done));
        if (cl.root())
            progress.update(static_cast<int>(done), render.seconds());
    }
    progress.finish();
    if (stopped && !sig && cl.root())
        std::fprintf(stderr,
                     "envtrace: time limit of %g s reached inside a pass: that pass is dropped, "
                     "the image holds the %d spp before it\n",
                     st.time_limit, static_cast<int>(done));
    if (sig && cl.root())
        std::fprintf(stderr,
                     "envtrace: %s: stopped at %d spp; writing the %s (a second "
                     "signal stops at once)\n",
                     signal_name(sig), static_cast<int>(done), partial ? "partial film" : "image");
    const double render_s = render.seconds();
    // The film of every rank, summed on rank 0 (exactly: in any order), and the rays they traced.
    const FilmSums sums = cl.reduce(renderer.sums());
    RenderStats s = renderer.stats();
    uint64_t counts[5] = {s.camera_rays, s.continuation_rays, s.shadow_rays, s.nonfinite_samples,
                          s.shaded_hits};
    cl.sum_to_root(counts, 5);
    s.camera_rays = counts[0];
    s.continuation_rays = counts[1];
    s.shadow_rays = counts[2];
    s.nonfinite_samples = counts[3];
    s.shaded_hits = counts[4];
    const int spp = static_cast<int>(done);
    if (cl.root() && !partial) // of the image written (metadata said "inf" where not asked)
        noise_error = relative_error(sums);
    cl.check(attempt([&] {
        if (!cl.root())
            return;
        if (!partial) {
            const std::vector<float> img = sums.mean();
            char error_text[32];
            std::snprintf(error_text, sizeof error_text, "%.6g", noise_error);
            std::vector<std::pair<std::string, std::string>> meta = {
                {"envtrace:noise_error", error_text},
                {"envtrace:noise_target",
                 noise ? std::to_string(a.noise_target) : std::string("none")},
                {"envtrace:noise_target_reached", noise_reached ? "yes" : "no"},
                {"envtrace:spp", std::to_string(spp)},
                {"envtrace:interrupted", sig ? signal_name(sig) : "no"},
                {"envtrace:resumed_from_spp", std::to_string(resumed_from)},
                {"envtrace:strategy", name_of(st.strategy)},
                {"envtrace:mis_heuristic", name_of(resolved_heuristic(st))},
                {"envtrace:sampler", name_of(st.sampler)},
                {"envtrace:bsdf_sampling", name_of(resolved_bsdf_sampling(st))},
                {"envtrace:visibility_verdict", verdict_name(renderer.stats())},
                {"envtrace:seed", std::to_string(st.seed)},
                {"envtrace:max_depth", std::to_string(st.max_depth)},
                {"envtrace:rr_depth", std::to_string(st.rr_depth)},
                {"envtrace:light_samples", std::to_string(st.light_samples)},
                {"envtrace:bsdf_samples", std::to_string(st.bsdf_samples)},
                {"envtrace:environment", ds.map_name},
                {"envtrace:render_seconds", std::to_string(render_s)},
                {"envtrace:backend", renderer.name()},
                {"envtrace:lights", st.lights},
                {"envtrace:sis_seconds", std::to_string(sis.seconds)},
                {"envtrace:ranks", std::to_string(cl.size())},
                {"Software", "envtrace " ENVTRACE_VERSION},
            };
            meta.insert(meta.end(), env_meta.begin(), env_meta.end());
            if (sums.has_aovs()) {
                const FilmLayers layers = film_layers(sums);
                write_image_channels(*outputs, exr_name, ds.width(), ds.height(), layers.names,
                                     layers.pixels, meta);
            } else {
                write_image(*outputs, exr_name, ds.width(), ds.height(), 3, img, meta);
            }
            RgbImage film{ds.width(), ds.height(), img};
            if (!png_name.empty())
                write_image(*outputs, png_name, ds.width(), ds.height(), 3, tone_map(film, 1.0f));
        }
        if (!a.stats_file.empty()) {
            nlohmann::json j = stats_json(a, st, ds, renderer.name(), s, build, light_set, sis, spp,
                                          static_cast<int>(resumed_from), sig, render_s, cl.size(),
                                          static_cast<int>(first), renderer);
            j["aovs"] = st.aovs;
            // A pass abandoned at a signal or the time limit: its time and rays are counted.
            j["stopped_inside_a_pass"] = stopped;
            if (noise)
                j["noise_target"] = {{"target", a.noise_target},
                                     {"reached", noise_reached},
                                     {"estimated_relative_error", noise_error}};
            write_json_file(*outputs, a.stats_file, j, 2);
        }
        if (keep_state)
            write_render_state(
                *outputs, state_path,
                RenderState{state.key, spp, static_cast<int>(first), sums, whole_render});
        outputs->commit();
    }));

    const int64_t rendered = done - resumed_from;
    const double mrays = s.rays() / render_s * 1e-6;
    std::printf(
        "rendered %d spp in %.2f s: %.2f Mrays/s (%llu camera, %llu continuation, %llu shadow), "
        "%.3g samples/s, %.4f s/spp%s\n",
        static_cast<int>(rendered), render_s, mrays, (unsigned long long)s.camera_rays,
        (unsigned long long)s.continuation_rays, (unsigned long long)s.shadow_rays,
        double(rendered) * ds.width() * ds.height() / render_s,
        render_s / std::max<int64_t>(1, rendered),
        stopped ? " (the time and rays include the pass abandoned at the stop)" : "");
    if (s.nonfinite_samples > 0 && cl.root())
        warn(a.scene + ": " + std::to_string(s.nonfinite_samples) +
             " samples were not finite and counted as zero (a renderer bug: please "
             "report the scene)");
    std::printf("%s time per stage, summed over the lanes%s:",
                st.backend == Backend::cpu ? "thread" : "device", cl.size() > 1 ? " (rank 0)" : "");
    for (const auto& [name, t] : s.stage_seconds)
        std::printf(" %s %.3fs", name.c_str(), t);
    if (partial)
        std::printf("\nwrote the partial film %s (samples %d..%d)%s%s (total %.2f s)\n",
                    state_path.c_str(), static_cast<int>(first), static_cast<int>(first + done - 1),
                    a.stats_file.empty() ? "" : " and ", a.stats_file.c_str(), total.seconds());
    else
        std::printf("\nwrote %s%s%s%s%s at %d spp (total %.2f s)\n", exr_name.c_str(),
                    png_name.empty() ? "" : " and ", png_name.c_str(),
                    keep_state ? " and the state " : "", keep_state ? state_path.c_str() : "", spp,
                    total.seconds());
    if (noise && cl.root())
        std::printf("noise target %g %s at %d spp: estimated relative error %.4g\n", a.noise_target,
                    noise_reached ? "reached" : "NOT reached", spp, noise_error);
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
    cmd->add_option("--time-limit", a->time_limit,
                    "Render for this many seconds (--spp, if given, caps the samples)")
        ->check(finite_range(0.0, 1e7));
    cmd->add_option("--noise-target", a->noise_target,
                    "Stop once the image's estimated relative RMS error is at most this (e.g. "
                    "0.02); --spp, if given, caps the samples, --time-limit the time")
        ->check(finite_range(1e-6, 10.0));
    cmd->add_flag("--aovs", a->aovs,
                  "Write albedo, normal (N), depth (Z) and variance layers into the EXR");
    cmd->add_option("--max-depth", a->max_depth,
                    "Bounces (1: direct lighting only, the paper's setting)")
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--rr-depth", a->rr_depth,
                    "Russian roulette ends paths only past this many surfaces (default 5; 0: "
                    "from the first)")
        ->check(CLI::Range(0, 1000));
    cmd->add_option(
           "--strategy", a->strategy,
           "light | bsdf | mis (the paper's) | compensated (the default: MIS, the light "
           "distribution compensated below the first vertex) | visibility (MIS, learns what blocks "
           "the map) "
           "| cosine (compensated, the first vertex's light from the map x the cosine to its "
           "normal) | uniform | sis (structured importance sampling)")
        ->check(CLI::IsMember(strategy_names()));
    cmd->add_option("--sis-samples", a->sis_samples,
                    "SIS strata (one shadow ray per sample; --spp a multiple of it)")
        ->check(CLI::Range(1, 1 << 16));
    cmd->add_option("--light-samples", a->light_samples,
                    "mis: light samples per vertex (splitting, a power of two up to 64; "
                    "default 1)");
    cmd->add_option("--bsdf-samples", a->bsdf_samples,
                    "mis: BSDF samples per vertex (splitting, a power of two up to 64; "
                    "default 1)");
    cmd->add_option("--lights", a->lights,
                    "Render with this directional light set ('envtrace lights'), natively");
    cmd->add_option("--mis-heuristic", a->heuristic,
                    "auto | balance | power (auto: power for mis, the paper's estimator; balance "
                    "for compensated, visibility, cosine)")
        ->check(CLI::IsMember(heuristic_names()));
    cmd->add_option("--sampler", a->sampler, "sobol | random")
        ->check(CLI::IsMember(sampler_names()));
    cmd->add_option("--bsdf-sampling", a->bsdf_sampling,
                    "GGX lobes: vndf (visible normals) | ndf (the paper's) | auto (vndf for "
                    "compensated, visibility and cosine, ndf otherwise)")
        ->check(CLI::IsMember(bsdf_sampling_names()));
    cmd->add_option("--light-batch", a->light_batch,
                    "Draw light samples " + std::to_string(ETK_LIGHT_BATCH) +
                        " to a work-item in their own stage: auto (on natively and on OpenCL CPU "
                        "devices, off on GPUs) | on | off; the same image")
        ->check(CLI::IsMember(light_batch_names()));
    cmd->add_option("--guide-verdict", a->guide_verdict,
                    "Visibility strategy: after learning, measure its tables against MIS on "
                    "the image and keep the one cheaper per error (on, the default) | off (the "
                    "tables throughout)")
        ->check(CLI::IsMember({"on", "off"}));
    cmd->add_option("--seed", a->seed, "Sampler seed")->check(CLI::Range(0LL, 4294967295LL));
    cmd->add_option("--paths", a->paths,
                    "Paths in flight per lane (0: the film over the lanes; on a CPU device waves "
                    "of at most 65536; capped by memory)")
        ->check(CLI::Range(0, 1 << 26));
    cmd->add_option("--stats", a->stats_file, "Write the render summary as JSON");
    cmd->add_option("--checkpoint", a->checkpoint,
                    "Save a resumable state every SECONDS of rendering (0: every pass), when "
                    "interrupted, and at the end")
        ->check(finite_range(0.0, 1e7));
    cmd->add_flag("--resume", a->resume,
                  "Continue from the saved state (same scene and settings; --spp is the total)");
    cmd->add_option("--state", a->state,
                    "The state file of --checkpoint and --resume (default: OUTPUT.envtrace-state "
                    "beside the image)");
    cmd->add_option("--sample-range", a->sample_range,
                    "FIRST:END: render sample indices FIRST .. END-1 only and write the partial "
                    "film (to --state, default OUTPUT.samples-FIRST-END.envtrace-state) for "
                    "'envtrace merge' (farm tasks); with --spp N, N is the whole render's samples "
                    "and merge checks that none of 0 .. N-1 is missing");
    cmd->add_option("--backend", a->backend,
                    "opencl (default) or cpu (native C++, same kernels/ sources)")
        ->check(CLI::IsMember(backend_names()));
    cmd->add_option("--threads", a->threads, "Native back end threads (0: all cores)")
        ->check(CLI::Range(0, 1024));
    cmd->callback([a, &g, cmd, &app] {
        a->light_samples_given = cmd->count("--light-samples") > 0;
        a->bsdf_samples_given = cmd->count("--bsdf-samples") > 0;
        a->sis_samples_given = cmd->count("--sis-samples") > 0;
        a->paths_given = cmd->count("--paths") > 0;
        a->device_given = app.count("--device") > 0;
        run(*a, g);
    });
}

} // namespace et::cli
