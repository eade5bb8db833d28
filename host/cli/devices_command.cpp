#include "commands.h"
#include "opencl/opencl_runtime.h"
#include "render/executor_cl.h"
#include "util/error.h"
#include "util/file_check.h"

#include <cstdio>
#include <iostream>
#include <string>

namespace et::cli {

void add_devices_command(CLI::App& app, Globals& g) {
    auto* cmd = app.add_subcommand("devices", "List OpenCL platforms and devices");
    static bool kernels = false;
    cmd->add_flag("--kernels", kernels,
                  "Also build wavefront.cl on each device and list, per stage kernel, what the "
                  "device reports and the work-group size envtrace launches it with");
    cmd->callback([&g] {
        auto devices = list_devices();
        // With --device: that one only (it was ignored; --kernels builds on every device).
        if (g.device_given && g.device >= static_cast<int>(devices.size()))
            throw Error("--device " + std::to_string(g.device) + " does not exist: there " +
                        (devices.size() == 1
                             ? "is 1 device"
                             : "are " + std::to_string(devices.size()) + " devices") +
                        " (envtrace devices lists them)");
        for (size_t i = 0; i < devices.size(); ++i) {
            if (g.device_given && static_cast<int>(i) != g.device)
                continue;
            const auto& d = devices[i];
            std::cout << "[" << i << "] " << d.device_name << "\n"
                      << "    platform: " << d.platform_name << "\n"
                      << "    device:   " << d.device_version << ", driver " << d.driver_version
                      << ", " << d.compute_units << " compute units\n";
            if (!kernels)
                continue;
            ClRuntime rt(static_cast<int>(i));
            const DeviceLimits& l = rt.limits();
            std::cout << "    memory:   " << byte_text(l.global_mem) << " global, largest buffer "
                      << byte_text(l.max_alloc) << (l.host_unified ? ", shared with the host" : "")
                      << "\n    floats:   "
                      << (l.correctly_rounded_div_sqrt
                              ? "x / y and sqrt correctly rounded, as on the host (built so)"
                              : "x / y and sqrt within OpenCL's ulp bounds only: images agree "
                                "with the native back end's statistically, not bit for bit")
                      << "\n    light samples: "
                      << (prefers_light_batches_on(l)
                              ? "in batches of " + std::to_string(ETK_LIGHT_BATCH) +
                                    " per work-item (a CPU; --light-batch auto)"
                              : std::string("one per shade work-item (not a CPU; --light-batch "
                                            "auto)"))
                      << "\n";
            std::cout << "    kernel          max group  preferred multiple  private bytes  "
                         "launched with\n";
            for (const StageKernelInfo& k : stage_kernel_info(rt)) {
                std::printf("    %-15s %9zu  %18zu  %13llu  %13zu\n", k.name.c_str(),
                            k.work_group_size, k.preferred_multiple,
                            static_cast<unsigned long long>(k.private_bytes), k.local);
            }
        }
    });
}

} // namespace et::cli
