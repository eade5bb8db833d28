// The envtrace subcommands. Each registers itself on the CLI11 app and runs when chosen.
#pragma once
#include <CLI/CLI.hpp>

#include <cmath>

#include <string>
#include <utility>

namespace et {
class Cluster;
}

namespace et::cli {

struct Globals {
    int device = 0;
    bool device_given = false;  // --device on the command line (set before any command runs)
    Cluster* cluster = nullptr; // the MPI ranks of this run, or a cluster of one (cluster.h)
    int exit_code = 0; // main's status when a command ends without an error (e.g. 130: SIGINT)
};

// CLI::Range for a real number that also refuses NaN (CLI::Range's comparisons let it through).
inline CLI::Validator finite_range(double lo, double hi) {
    CLI::Validator range = CLI::Range(lo, hi);
    return CLI::Validator(
        [range](std::string& text) {
            double v = 0;
            if (CLI::detail::lexical_cast(text, v) && std::isnan(v))
                return std::string("Value " + text + " is not a finite number");
            std::string copy = text;
            return range(copy);
        },
        range.get_description());
}

// The image and its twin of an output name: out.exr -> (out.exr, out.png); out.png -> (out.exr,
// out.png); .hdr and .pfm like .exr. Throws et::Error for another extension.
std::pair<std::string, std::string> output_names(const std::string& out);
// The denoised twin of an image: out.exr -> out.denoised.exr (.hdr, .pfm alike).
std::string denoised_name(const std::string& image);

void add_devices_command(CLI::App& app, Globals& g);
void add_sample_command(CLI::App& app, Globals& g);
void add_render_command(CLI::App& app, Globals& g);
void add_bench_command(CLI::App& app, Globals& g);
void add_compare_command(CLI::App& app, Globals& g);
void add_lights_command(CLI::App& app, Globals& g);
void add_merge_command(CLI::App& app, Globals& g);
void add_convert_command(CLI::App& app, Globals& g);

} // namespace et::cli
