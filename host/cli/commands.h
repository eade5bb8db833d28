// The envtrace subcommands. Each registers itself on the CLI11 app and runs when chosen.
#pragma once
#include <CLI/CLI.hpp>

#include <string>
#include <utility>

namespace et::cli {

class Cluster;

struct Globals {
    int device = 0;
    Cluster* cluster = nullptr; // the MPI ranks of this run, or a cluster of one (cluster.h)
    int exit_code = 0; // main's status when a command ends without an error (e.g. 130: SIGINT)
};

// The image and its twin of an output name: out.exr -> (out.exr, out.png); out.png -> (out.exr,
// out.png); .hdr and .pfm like .exr. Throws et::Error for another extension.
std::pair<std::string, std::string> output_names(const std::string& out);

void add_devices_command(CLI::App& app, Globals& g);
void add_sample_command(CLI::App& app, Globals& g);
void add_render_command(CLI::App& app, Globals& g);
void add_bench_command(CLI::App& app, Globals& g);
void add_compare_command(CLI::App& app, Globals& g);
void add_lights_command(CLI::App& app, Globals& g);
void add_merge_command(CLI::App& app, Globals& g);
void add_convert_command(CLI::App& app, Globals& g);

} // namespace et::cli
