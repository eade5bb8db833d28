#include "render_options.h"

#include "util/error.h"

#include <sstream>
#include <vector>

namespace et::cli {
namespace {

// The scene's value, else the built-in default: what an option left out renders with.
template <class T> std::string scene_or(const char* key, const T& builtin) {
    std::ostringstream s;
    s << "the scene's render." << key << ", else " << builtin;
    return s.str();
}

// CLI::IsMember whose choices the option's text names instead of CLI11's list: the text offers
// what a user should choose, while a name the library is retiring still parses.
CLI::Validator listed_in_text(const std::vector<std::string>& names) {
    return CLI::IsMember(names).description("");
}

// Output, samples, time and noise: what and how much to render.
void add_output_options(CLI::App& cmd, RenderArgs& a) {
    const RenderSettings d;
    cmd.add_option("-o,--output", a.output,
                   "Output image: .exr/.hdr/.pfm (linear) plus a .png preview beside it, or a "
                   ".png/.jpg name and the .exr beside it")
        ->default_str(std::string(kDefaultOutputFolder) +
                      "/ + the scene's \"output\", else SCENE.exr (folder created)");
    cmd.add_option("--spp", a.spp, "Samples per pixel")
        ->check(CLI::Range(1, 1 << 24))
        ->default_str(scene_or("spp", d.spp));
    cmd.add_option("--time-limit", a.time_limit,
                   "Render for this many seconds (--spp, if given, caps the samples)")
        ->check(finite_range(0.0, 1e7))
        ->default_str("none");
    cmd.add_option("--noise-target", a.noise_target,
                   "Stop once the image's estimated relative RMS error is at most this (e.g. "
                   "0.02); --spp, if given, caps the samples, --time-limit the time")
        ->check(finite_range(1e-6, 10.0))
        ->default_str("none");
    cmd.add_option("--width", a.width, "Film width in pixels, over the scene's")
        ->check(CLI::Range(1, 16384))
        ->default_str("the scene's film.width");
    cmd.add_option("--height", a.height, "Film height in pixels, over the scene's")
        ->check(CLI::Range(1, 16384))
        ->default_str("the scene's film.height");
    cmd.add_option("--exposure", a.exposure,
                   "Preview exposure in stops: radiance x 2^EV before its tone curve (the linear "
                   "image is unchanged)")
        ->check(finite_range(-30.0, 30.0))
        ->capture_default_str();
    cmd.add_flag("--aovs", a.aovs,
                 "Write albedo, normal (N), depth (Z) and variance layers into the EXR");
    cmd.add_flag("--denoise", a.denoise,
                 "Also write OUT.denoised.EXT: the image denoised by Open Image Denoise 2, "
                 "guided by the albedo and normal; the preview shows it (tools/setup installs "
                 "OIDN)");
    cmd.add_option("--live-preview", a.live_preview,
                   "Every this many seconds of rendering (0: every pass), rewrite the preview "
                   "of the film so far, atomically, for an image viewer to watch it converge")
        ->check(finite_range(0.0, 1e7))
        ->default_str("none");
    cmd.add_flag("--live-image", a.live_image,
                 "With --live-preview: rewrite the linear image (OUT.exr) each time too");
    cmd.add_option("--stats", a.stats_file, "Write the render summary as JSON")
        ->default_str("none");
}

// The estimator: depth, strategy and seed.
void add_estimator_options(CLI::App& cmd, RenderArgs& a) {
    const RenderSettings d;
    cmd.add_option("--max-depth", a.max_depth,
                   "Bounces (1: direct lighting only, the paper's setting)")
        ->check(CLI::Range(1, 1000))
        ->default_str(scene_or("max_depth", d.max_depth));
    cmd.add_option("--strategy", a.strategy,
                   "light | bsdf | mis (the paper's) | compensated (MIS, the light distribution "
                   "compensated below the first vertex) | visibility (MIS, learns what blocks "
                   "the map) | cosine (compensated, the first vertex's light from the map x the "
                   "cosine to its normal) | auto (visibility's learning, kept only where a "
                   "measurement shows it beats compensated) | uniform | sis (structured "
                   "importance sampling)")
        ->check(listed_in_text(strategy_names()))
        ->default_str(scene_or("strategy", name_of(d.strategy)));
    cmd.add_option("--sis-samples", a.sis_samples,
                   "SIS strata (one shadow ray per sample; --spp a multiple of it)")
        ->check(CLI::Range(1, 1 << 16))
        ->capture_default_str();
    cmd.add_option("--lights", a.lights,
                   "Render with this directional light set ('envtrace lights'), natively")
        ->default_str("none");
    cmd.add_option("--seed", a.seed, "Sampler seed")
        ->check(CLI::Range(0LL, 4294967295LL))
        ->default_str(scene_or("seed", d.seed));
}

// Where it runs, and how a render is kept, resumed or split into farm tasks.
void add_run_options(CLI::App& cmd, RenderArgs& a) {
    cmd.add_option("--backend", a.backend, "opencl or cpu (native C++, same kernels/ sources)")
        ->check(CLI::IsMember(backend_names()))
        ->capture_default_str();
    cmd.add_option("--threads", a.threads, "Native back end threads (0: all cores)")
        ->check(CLI::Range(0, 1024))
        ->capture_default_str();
    cmd.add_option("--checkpoint", a.checkpoint,
                   "Save a resumable state every SECONDS of rendering (0: every pass) and at the "
                   "end (an interrupted render saves one anyway)")
        ->check(finite_range(0.0, 1e7))
        ->default_str("none");
    cmd.add_flag("--resume", a.resume,
                 "Continue from the saved state (same scene and settings; --spp is the total)");
    cmd.add_option("--state", a.state, "The state file of --checkpoint and --resume")
        ->default_str("OUTPUT.envtrace-state beside the image");
    cmd.add_option("--sample-range", a.sample_range,
                   "FIRST:END: render sample indices FIRST .. END-1 only and write the partial "
                   "film (to --state, default OUTPUT.samples-FIRST-END.envtrace-state) for "
                   "'envtrace merge' (farm tasks); with --spp N, N is the whole render's samples "
                   "and merge checks that none of 0 .. N-1 is missing")
        ->default_str("all");
}

// Internal knobs: tested, and rarely a user's choice (their defaults suit every scene).
std::vector<CLI::Option*> add_expert_options(CLI::App& cmd, RenderArgs& a) {
    const RenderSettings d;
    return {
        cmd.add_option("--rr-depth", a.rr_depth,
                       "Russian roulette ends paths only past this many surfaces (0: from the "
                       "first)")
            ->check(CLI::Range(0, 1000))
            ->default_str(scene_or("rr_depth", d.rr_depth)),
        cmd.add_option("--mis-heuristic", a.heuristic,
                       "auto | balance | power (auto: power for mis, the paper's estimator; "
                       "balance for compensated, visibility, cosine)")
            ->check(CLI::IsMember(heuristic_names()))
            ->default_str("auto"),
        cmd.add_option("--bsdf-sampling", a.bsdf_sampling,
                       "GGX lobes: vndf (visible normals) | ndf (the paper's) | auto (vndf for "
                       "compensated, visibility and cosine, ndf otherwise)")
            ->check(listed_in_text(bsdf_sampling_names()))
            ->default_str("auto"),
        cmd.add_option("--light-samples", a.light_samples,
                       "mis: light samples per vertex (splitting, a power of two up to 64)")
            ->default_str("1"),
        cmd.add_option("--bsdf-samples", a.bsdf_samples,
                       "mis: BSDF samples per vertex (splitting, a power of two up to 64)")
            ->default_str("1"),
        cmd.add_option("--sampler", a.sampler, "sobol | random")
            ->check(CLI::IsMember(sampler_names()))
            ->default_str(scene_or("sampler", name_of(d.sampler))),
        cmd.add_option("--light-batch", a.light_batch,
                       "Draw light samples " + std::to_string(ETK_LIGHT_BATCH) +
                           " to a work-item in their own stage: auto (on natively and on OpenCL "
                           "CPU devices, off on GPUs) | on | off; the same image")
            ->check(CLI::IsMember(light_batch_names()))
            ->default_str("auto"),
        cmd.add_option("--film-sums", a.film_sums,
                       "Where each pass is added to the film's exact sums: auto (device on "
                       "GPUs, host otherwise) | host | device (OpenCL only); the same image")
            ->check(CLI::IsMember(film_sums_names()))
            ->default_str("auto"),
        cmd.add_option("--queue-counts", a.queue_counts,
                       "Where each bounce's queue sizes are read: auto (device on GPUs, host "
                       "otherwise) | host | device (OpenCL only); the same image")
            ->check(CLI::IsMember(queue_counts_names()))
            ->default_str("auto"),
        cmd.add_option("--guide-verdict", a.guide_verdict,
                       "Visibility strategy: after learning, measure its tables against MIS on "
                       "the image and keep the one cheaper per error (on) | off (the tables "
                       "throughout)")
            ->check(CLI::IsMember({"on", "off"}))
            ->default_str("on"),
        cmd.add_option("--paths", a.paths,
                       "Paths in flight per lane (0: the film over the lanes; on a CPU device "
                       "waves of at most 32768; capped by memory)")
            ->check(CLI::Range(0, 1 << 26))
            ->default_str("0"),
    };
}

} // namespace

void add_render_options(CLI::App& cmd, RenderArgs& a) {
    cmd.add_option("scene", a.scene, "Scene file (.json; the format: docs/scene-format.md)")
        ->required();
    add_output_options(cmd, a);
    add_estimator_options(cmd, a);
    add_run_options(cmd, a);
    // Hidden (CLI11's empty group) until --help-expert names their group and asks for help.
    const std::vector<CLI::Option*> expert = add_expert_options(cmd, a);
    for (CLI::Option* o : expert)
        o->group("");
    cmd.add_flag_callback(
           "--help-expert",
           [expert] {
               for (CLI::Option* o : expert)
                   o->group("Expert options (internal knobs; their defaults suit every scene)");
               throw CLI::CallForHelp();
           },
           "Print this help with the expert options too (internal knobs) and exit")
        ->trigger_on_parse();
    cmd.footer("The scene format: docs/scene-format.md. Internal knobs: envtrace render "
               "--help-expert.");
}

namespace {

// The values the command line gives, over the scene's.
void apply_overrides(const RenderArgs& a, const Globals& g, RenderSettings& st) {
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
    if (!a.film_sums.empty())
        st.film_sums = parse_film_sums(a.film_sums, cli);
    if (!a.queue_counts.empty())
        st.queue_counts = parse_queue_counts(a.queue_counts, cli);
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
    st.aovs = a.aovs || a.denoise; // the denoiser's guides
}

// Options this render does not use: said, not silently dropped.
void warn_idle_options(const RenderArgs& a, const RenderSettings& st) {
    if (a.sis_samples_given && st.strategy != Strategy::sis)
        warn("--sis-samples applies to --strategy sis only: ignored");
    if (!a.guide_verdict.empty() && st.strategy != Strategy::visibility &&
        st.strategy != Strategy::automatic)
        warn("--guide-verdict applies to --strategy visibility and auto only: ignored");
    if (st.backend == Backend::cpu && a.device_given)
        warn("--device picks an OpenCL device: ignored with --backend cpu");
    if (st.backend == Backend::cpu && a.paths_given)
        warn("--paths sets the OpenCL back end's paths in flight: ignored with --backend cpu "
             "(each native thread keeps its own wave)");
    if (st.backend == Backend::cpu && st.film_sums == FilmSumsAt::device)
        warn("--film-sums device applies to the OpenCL back end: ignored with --backend cpu (its "
             "threads write the host's film)");
    else if (st.film_sums == FilmSumsAt::device && st.aovs)
        warn("--film-sums device: a render with AOVs (--aovs, --denoise) adds its passes on the "
             "host");
    if (st.backend == Backend::cpu && st.queue_counts == QueueCounts::device)
        warn("--queue-counts device applies to the OpenCL back end: ignored with --backend cpu "
             "(its threads read their own counters)");
}

} // namespace

RenderSettings settings_for(const RenderArgs& a, const Globals& g, RenderSettings st) {
    apply_overrides(a, g, st);
    if (!st.lights.empty()) {
        // A light set is its own estimator: a strategy asked for as well would be dropped.
        if (!a.strategy.empty())
            throw Error("command line: --lights renders with the directional light set; it "
                        "excludes --strategy " +
                        a.strategy);
        st.strategy = Strategy::lights;
    }
    warn_idle_options(a, st);
    const bool direct_only = st.strategy == Strategy::sis || st.strategy == Strategy::lights;
    if (direct_only && st.max_depth != 1) {
        // Said only where a depth was named (command line or scene): the default is no choice.
        if (a.max_depth > 0 || st.max_depth != RenderSettings{}.max_depth)
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

} // namespace et::cli
