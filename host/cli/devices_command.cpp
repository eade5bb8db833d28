#include "commands.h"
#include "opencl/opencl_runtime.h"

#include <iostream>

namespace et::cli {

void add_devices_command(CLI::App& app, Globals&) {
    auto* cmd = app.add_subcommand("devices", "List OpenCL platforms and devices");
    cmd->callback([] {
        auto devices = list_devices();
        for (size_t i = 0; i < devices.size(); ++i) {
            const auto& d = devices[i];
            std::cout << "[" << i << "] " << d.device_name << "\n"
                      << "    platform: " << d.platform_name << "\n"
                      << "    device:   " << d.device_version << ", driver " << d.driver_version
                      << ", " << d.compute_units << " compute units\n";
        }
    });
}

} // namespace et::cli
