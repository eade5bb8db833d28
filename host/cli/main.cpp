// envtrace: Monte Carlo rendering with natural illumination.
#include "commands.h"
#include "session/cluster.h"
#include "util/error.h"
#include "util/signal_cleanup.h"
#include "opencl/opencl_runtime.h"

#include <csignal>
#include <iostream>
#include <vector>

int main(int argc, char** argv) {
    // A reader that goes away (`envtrace render ... | head -1`) must not kill a render before
    // its image is written: stdout's writes then fail quietly instead of raising SIGPIPE.
    std::signal(SIGPIPE, SIG_IGN);
    // Under mpirun: MPI starts here and ends when main returns (the ranks of `render`).
    et::Cluster cluster(&argc, &argv);
    // A signal that ends envtrace (convert, lights, merge ... or a render's second) removes the
    // temporaries of the outputs it was writing.
    et::install_signal_cleanup();
    CLI::App app{"envtrace " ENVTRACE_VERSION
                 ": renders scenes lit by HDR environment maps, importance-sampled as in\n"
                 "'Monte Carlo Rendering with Natural Illumination', on OpenCL devices."};
    app.require_subcommand(1);
    et::cli::Globals globals;
    globals.cluster = &cluster;
    CLI::Option* device_option =
        app.add_option("--device", globals.device, "OpenCL device index (see 'envtrace devices')")
            ->check(CLI::Range(0, 65535));
    app.set_version_flag("--version", ENVTRACE_VERSION);
    et::cli::add_devices_command(app, globals);
    et::cli::add_sample_command(app, globals);
    et::cli::add_render_command(app, globals);
    et::cli::add_bench_command(app, globals);
    et::cli::add_compare_command(app, globals);
    et::cli::add_convert_command(app, globals);
    et::cli::add_lights_command(app, globals);
    et::cli::add_merge_command(app, globals);
    // An empty value (`--json ""`, `compare "" b.exr`) is never a name or a number envtrace
    // takes: refused by the option's name before any command runs (it wrote no JSON, or said
    // ": no such file").
    app.parse_complete_callback([&app, &globals, device_option] {
        globals.device_given = device_option->count() > 0;
        std::vector<const CLI::App*> apps = {&app};
        for (const CLI::App* sub : app.get_subcommands())
            apps.push_back(sub);
        for (const CLI::App* a : apps)
            for (const CLI::Option* opt : a->get_options()) {
                if (opt->count() == 0 || opt->get_type_size() == 0) // absent, or a flag
                    continue;
                for (const std::string& v : opt->results())
                    if (v.empty())
                        throw et::Error((opt->get_positional()
                                             ? "the argument '" + opt->get_name() + "'"
                                             : opt->get_name()) +
                                        " is empty: name what to read or write");
            }
    });
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help and --version end here too, with status 0 and their text; a command line
        // that cannot be parsed is an error like any other: one line, status 1.
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))
            return app.exit(e);
        std::cerr << "envtrace: error: " << e.what() << " (see envtrace --help)\n";
        return 1;
    } catch (const et::ClusterError& e) {
        // A failure of one or more ranks: rank 0 names them, the others stay silent.
        if (*e.what())
            std::cerr << "envtrace: error: " << e.what() << "\n";
        return 1;
    } catch (const et::Error& e) {
        std::cerr << "envtrace: error: " << e.what() << "\n";
        return 1;
    } catch (const cl::Error& e) {
        std::cerr << "envtrace: error: OpenCL call " << e.what()
                  << " failed: " << et::cl_error_name(e.err()) << "\n";
        return 1;
    } catch (const std::bad_alloc&) {
        std::cerr << "envtrace: error: out of memory (a smaller film, fewer --paths or a smaller "
                     "scene needs less)\n";
        return 1;
    } catch (const std::exception& e) {
        // Not one of ours: a library or standard exception a loader did not turn into
        // et::Error. Still one line and exit status 1, with what it says.
        std::cerr << "envtrace: error: " << e.what() << "\n";
        return 1;
    } catch (...) {
        // Anything else thrown (not derived from std::exception): never std::terminate.
        std::cerr << "envtrace: error: unexpected exception (not a std::exception)\n";
        return 1;
    }
    return globals.exit_code;
}
