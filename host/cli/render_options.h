// `envtrace render`'s options: what a user chooses (listed by --help, with defaults) and the
// internal knobs (listed by --help-expert), parsed into the render's settings.
#pragma once
#include "commands.h"
#include "load/render_settings.h"

#include <CLI/CLI.hpp>

#include <string>
#include <utility>

namespace et::cli {

struct RenderArgs {
    std::string scene, output, stats_file, strategy, heuristic, sampler, backend = "opencl";
    std::string bsdf_sampling;
    std::string light_batch;   // --light-batch: auto, on, off
    std::string film_sums;     // --film-sums: auto, host, device
    std::string queue_counts;  // --queue-counts: auto, host, device
    std::string guide_verdict; // --guide-verdict: on, off
    std::string lights;        // --lights: render with this directional light set
    int sis_samples = 64;
    int light_samples = 0, bsdf_samples = 0; // --light-samples, --bsdf-samples
    // Which options the command line gave (set from CLI11's counts): for options whose every
    // value means something, and those that only apply to some renders.
    bool light_samples_given = false, bsdf_samples_given = false, sis_samples_given = false;
    bool device_given = false, paths_given = false;
    int spp = 0, max_depth = 0, rr_depth = -1, paths = -1, threads = 0;
    int width = 0, height = 0; // --width, --height: the film's, over the scene's (0: the scene's)
    double exposure = 0.0;     // --exposure: EV of the preview
    long long seed = -1;
    double time_limit = -1.0;
    double checkpoint = -1.0;   // --checkpoint: seconds between saved states (< 0: none)
    double noise_target = 0.0;  // --noise-target: stop at this relative error (0: none)
    bool aovs = false;          // --aovs: albedo, normal, depth and variance layers in the EXR
    bool denoise = false;       // --denoise: OUT.denoised.EXT too (the film keeps AOVs for it)
    double live_preview = -1.0; // --live-preview: seconds between previews of the film so far
    bool live_image = false;    // --live-image: the linear image too
    bool resume = false;
    std::string state;        // --state: the state file (default: beside the image)
    std::string sample_range; // --sample-range A:B: a farm task, samples A .. B-1
};

// The folder an image goes to without -o (the scene's "output" names it there): renders/ under
// the current folder, created when missing; .gitignore lists it in the checkout.
inline constexpr const char* kDefaultOutputFolder = "renders";

// Registers the options on `cmd`, storing into `a`; the expert ones are hidden from --help and
// listed by --help-expert.
void add_render_options(CLI::App& cmd, RenderArgs& a);

// The command line over the scene's settings: parsed once into typed values. Throws et::Error
// for options that exclude each other; warns about options this render does not use.
RenderSettings settings_for(const RenderArgs& a, const Globals& g, RenderSettings st);

// "A:B" -> [A, B): the sample indices of one farm task.
std::pair<int, int> parse_sample_range(const std::string& text);

} // namespace et::cli
