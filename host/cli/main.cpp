// envtrace: Monte Carlo rendering with natural illumination.
#include "cluster.h"
#include "commands.h"
#include "util/error.h"
#include "util/signal_cleanup.h"
#include "opencl/opencl_runtime.h"

#include <csignal>
#include <iostream>

int main(int argc, char** argv) {
    // A reader that goes away (`envtrace render ... | head -1`) must not kill a render before
    // its image is written: stdout's writes then fail quietly instead of raising SIGPIPE.
    std::signal(SIGPIPE, SIG_IGN);
    // Under mpirun: MPI starts here and ends when main returns (the ranks of `render`).
    et::cli::Cluster cluster(&argc, &argv);
    // A signal that ends envtrace (convert, lights, merge ... or a render's second) removes the
    // temporaries of the outputs it was writing.
    et::install_signal_cleanup();
    CLI::App app{"envtrace " ENVTRACE_VERSION
                 ": renders scenes lit by HDR environment maps, importance-sampled as in\n"
                 "'Monte Carlo Rendering with Natural Illumination', on OpenCL devices."};
    app.require_subcommand(1);
    et::cli::Globals globals;
    globals.cluster = &cluster;
    app.add_option("--device", globals.device, "OpenCL device index (see 'envtrace devices')")
        ->check(CLI::NonNegativeNumber);
    app.set_version_flag("--version", ENVTRACE_VERSION);
    et::cli::add_devices_command(app, globals);
    et::cli::add_sample_command(app, globals);
    et::cli::add_render_command(app, globals);
    et::cli::add_bench_command(app, globals);
    et::cli::add_compare_command(app, globals);
    et::cli::add_convert_command(app, globals);
    et::cli::add_lights_command(app, globals);
    et::cli::add_merge_command(app, globals);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help and --version end here too, with status 0 and their text; a command line
        // that cannot be parsed is an error like any other: one line, status 1.
        if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))
            return app.exit(e);
        std::cerr << "envtrace: error: " << e.what() << " (see envtrace --help)\n";
        return 1;
    } catch (const et::cli::ClusterError& e) {
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
