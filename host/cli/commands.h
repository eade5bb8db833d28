// The envtrace subcommands. Each registers itself on the CLI11 app and runs when chosen.
#pragma once
#include <CLI/CLI.hpp>

namespace et::cli {

struct Globals {
    int device = 0;
    int exit_code = 0; // main's status when a command ends without an error (e.g. 130: SIGINT)
};

void add_devices_command(CLI::App& app, Globals& g);
void add_sample_command(CLI::App& app, Globals& g);
void add_render_command(CLI::App& app, Globals& g);
void add_bench_command(CLI::App& app, Globals& g);
void add_compare_command(CLI::App& app, Globals& g);
void add_lights_command(CLI::App& app, Globals& g);

} // namespace et::cli
